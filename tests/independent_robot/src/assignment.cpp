// SPDX-License-Identifier: Apache-2.0
#include "assignment.hpp"

#include <charconv>
#include <cmath>
#include <stdexcept>
#include <system_error>

namespace swivel::independent {

Assignment parse_assignment(const std::string& text) {
  const std::size_t eq = text.find('=');
  const std::size_t dot = text.find('.');
  if (eq == std::string::npos || dot == std::string::npos || dot > eq || dot == 0 ||
      dot + 1 == eq || eq + 1 == text.size()) {
    throw std::invalid_argument(text + ": expected NAME.PARAM=VALUE");
  }
  Assignment a;
  a.effect = text.substr(0, dot);
  a.param = text.substr(dot + 1, eq - dot - 1);
  a.text = text;
  const char* first = text.data() + eq + 1;
  const char* last = text.data() + text.size();
  const auto r = std::from_chars(first, last, a.value);
  if (r.ec != std::errc() || r.ptr != last || !std::isfinite(a.value)) {
    throw std::invalid_argument(text + ": '" + std::string(first, last) + "' is not a number");
  }
  return a;
}

void apply_assignment(RunSpec& spec, const Assignment& a, const std::vector<ParamSlot>& slots,
                      const std::vector<std::string>& other_effects, const std::string& what) {
  std::vector<std::string> effects;
  std::vector<std::string> params;
  for (const ParamSlot& s : slots) {
    if (effects.empty() || effects.back() != s.effect) effects.push_back(s.effect);
    if (s.effect == a.effect) params.push_back(s.param);
  }
  if (params.empty()) {
    for (const std::string& other : other_effects) {
      if (other == a.effect) {
        throw std::invalid_argument(a.effect + ": not an effect of the " + what +
                                    " (effects: " + join_names(effects) + ")");
      }
    }
    throw std::invalid_argument(a.effect + ": unknown effect (effects: " + join_names(effects) +
                                ")");
  }
  for (const ParamSlot& s : slots) {
    if (s.effect != a.effect || s.param != a.param) continue;
    if (!(a.value >= s.min && a.value <= s.max)) {
      throw std::invalid_argument(a.text + ": outside [" + format_number(s.min) + ", " +
                                  format_number(s.max) + "]");
    }
    if (s.integer && a.value != std::floor(a.value)) {
      throw std::invalid_argument(a.text + ": expected a whole number");
    }
    s.set(spec, a.value);
    return;
  }
  throw std::invalid_argument(a.effect + "." + a.param +
                              ": unknown parameter (expected: " + join_names(params) + ")");
}

std::string join_names(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& n : names) {
    if (!out.empty()) out += ", ";
    out += n;
  }
  return out;
}

std::string format_number(double value) {
  if (value == 0.0) return "0";  // never "-0"
  char buf[32];
  // Shortest round-trip digits, fixed notation unless the exponent is far from zero.
  const auto r = std::to_chars(buf, buf + sizeof buf, value, std::chars_format::general);
  return {buf, r.ptr};
}

}  // namespace swivel::independent
