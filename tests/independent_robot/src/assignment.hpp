// SPDX-License-Identifier: Apache-2.0
#pragma once
// "NAME.PARAM=VALUE" as typed on a command line, and the table of settable parameters both
// effect families share.

#include <functional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "swivel/independent/run_spec.hpp"

namespace swivel::independent {

struct Assignment {
  std::string effect;  ///< NAME
  std::string param;   ///< PARAM
  std::string text;    ///< the whole assignment, for messages
  double value = 0.0;
};

/// @throws std::invalid_argument for text that is not NAME.PARAM=VALUE with a finite number.
Assignment parse_assignment(const std::string& text);

/// One settable parameter: its names, accepted range and where it lives in a spec.
struct ParamSlot {
  std::string effect;
  std::string param;
  double min = 0.0;
  double max = 0.0;
  bool integer = false;  ///< only whole numbers
  std::function<double(const RunSpec&)> get;
  std::function<void(RunSpec&, double)> set;
};

/// A slot for a field that `field(spec)` returns by reference (double or int); `field` takes
/// `auto&` so that it serves const and mutable specs.
template <typename Field>
ParamSlot make_slot(std::string effect, std::string param, double min, double max, Field field) {
  ParamSlot s;
  s.effect = std::move(effect);
  s.param = std::move(param);
  s.min = min;
  s.max = max;
  using Value = std::remove_cvref_t<decltype(field(std::declval<RunSpec&>()))>;
  s.integer = std::is_integral_v<Value>;
  s.get = [field](const RunSpec& spec) { return static_cast<double>(field(spec)); };
  s.set = [field](RunSpec& spec, double v) { field(spec) = static_cast<Value>(v); };
  return s;
}

/// Finds the slot of `a` in `slots` and sets it after checking the range.
/// `other_effects`: effect names that exist but not for this robot (for the message).
/// @throws std::invalid_argument naming the effect, parameter or range.
void apply_assignment(RunSpec& spec, const Assignment& a, const std::vector<ParamSlot>& slots,
                      const std::vector<std::string>& other_effects, const std::string& what);

/// "a, b, c".
std::string join_names(const std::vector<std::string>& names);

/// A number as the files and messages write it: the shortest text that reads back exactly.
std::string format_number(double value);

}  // namespace swivel::independent
