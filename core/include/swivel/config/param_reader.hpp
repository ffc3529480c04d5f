// SPDX-License-Identifier: Apache-2.0
#pragma once
// Typed, validated access to one YAML mapping, used by the daemon configuration, the robot
// model and every plugin's `params:`. Each getter records the key as known; finish()
// rejects keys nobody asked for. Every error is a ConfigError naming file:line:column, the
// full key path and what was expected.

#include <yaml-cpp/yaml.h>

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "swivel/config/config_error.hpp"

namespace swivel {

class ParamReader {
 public:
  /// @param node      a mapping, or a null/undefined node (treated as empty)
  /// @param file      file name for messages
  /// @param path      key path of `node` for messages ("" at the top, "localization.params")
  /// @throws ConfigError when node is neither a mapping nor null
  ParamReader(const YAML::Node& node, std::string file, std::string path);

  [[nodiscard]] bool has(const std::string& key) const;

  /// Required number in [min, max]. @throws ConfigError (missing, wrong type, out of range)
  double number(const std::string& key, double min = -std::numeric_limits<double>::max(),
                double max = std::numeric_limits<double>::max());
  /// Optional number in [min, max], `fallback` when absent.
  double number_or(const std::string& key, double fallback,
                   double min = -std::numeric_limits<double>::max(),
                   double max = std::numeric_limits<double>::max());
  int integer(const std::string& key, int min, int max);
  int integer_or(const std::string& key, int fallback, int min, int max);
  bool boolean_or(const std::string& key, bool fallback);
  std::string string(const std::string& key);
  std::string string_or(const std::string& key, const std::string& fallback);
  /// String that must be one of `choices`.
  std::string choice_or(const std::string& key, const std::string& fallback,
                        const std::vector<std::string>& choices);
  /// Nested mapping (may be absent: an empty reader).
  ParamReader child(const std::string& key);
  /// Nested sequence node, marked known; caller validates elements with element().
  YAML::Node sequence(const std::string& key);
  /// Raw node (marked known), for values a caller validates itself.
  YAML::Node raw(const std::string& key);
  /// A reader over element `i` of a sequence obtained from sequence(key).
  ParamReader element(const YAML::Node& seq, const std::string& key, std::size_t i) const;

  /// @throws ConfigError for the first key present in the mapping but never asked for.
  void finish() const;

  /// "file:line:col: path.key: message" for `key` (or for the mapping itself when empty).
  [[nodiscard]] std::string where(const std::string& key) const;
  [[noreturn]] void fail(const std::string& key, const std::string& message) const;

  [[nodiscard]] const std::string& file() const { return file_; }
  [[nodiscard]] const std::string& path() const { return path_; }
  [[nodiscard]] const YAML::Node& node() const { return node_; }

 private:
  YAML::Node node_;
  std::string file_;
  std::string path_;
  std::vector<std::string> known_;
};

}  // namespace swivel
