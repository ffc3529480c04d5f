// SPDX-License-Identifier: Apache-2.0
#include "swivel/config/param_reader.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <utility>

namespace swivel {
namespace {

std::string format_number(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

// "a number in [1, 10000]", "a number >= 0", "a number": whichever bounds are real.
std::string range_text(const char* what, double min, double max, double lowest, double highest) {
  std::string text = what;
  const bool has_min = min > lowest;
  const bool has_max = max < highest;
  if (has_min && has_max) {
    text += " in [" + format_number(min) + ", " + format_number(max) + "]";
  } else if (has_min) {
    text += " >= " + format_number(min);
  } else if (has_max) {
    text += " <= " + format_number(max);
  }
  return text;
}

// What a value looks like, for "got ..." in messages.
std::string describe(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Scalar: return "'" + node.Scalar() + "'";
    case YAML::NodeType::Sequence: return "a list";
    case YAML::NodeType::Map: return "a mapping";
    case YAML::NodeType::Null: return "nothing";
    case YAML::NodeType::Undefined: break;
  }
  return "nothing";
}

// Not std::to_string: its digit table is a GNU-unique symbol, and one of those in a plugin
// (which links this file) makes the plugin library impossible to unload.
std::string decimal(long long value) {
  char buf[24];
  std::snprintf(buf, sizeof buf, "%lld", value);
  return buf;
}

std::string location(const std::string& file, const YAML::Mark& mark) {
  if (mark.is_null()) return file;
  return file + ":" + decimal(mark.line + 1) + ":" + decimal(mark.column + 1);
}

// Const lookup so that asking for an absent key never inserts it.
YAML::Node lookup(const YAML::Node& map, const std::string& key, YAML::Mark* key_mark) {
  if (!map.IsMap()) return YAML::Node(YAML::NodeType::Undefined);
  for (auto it = map.begin(); it != map.end(); ++it) {
    if (it->first.IsScalar() && it->first.Scalar() == key) {
      if (key_mark != nullptr) *key_mark = it->first.Mark();
      return it->second;
    }
  }
  return YAML::Node(YAML::NodeType::Undefined);
}

// Edit distance, to point at a misspelt key when a required one is missing.
std::size_t distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = above;
    }
  }
  return row[b.size()];
}

std::string missing(const ParamReader& r, const std::string& key, const std::string& expected) {
  std::string text = r.where("") + " missing required key '" + key + "' (" + expected + ")";
  if (!r.node().IsMap()) return text;
  for (auto it = r.node().begin(); it != r.node().end(); ++it) {
    if (!it->first.IsScalar()) continue;
    const std::string& present = it->first.Scalar();
    if (distance(present, key) <= 2) {
      text += "; is '" + present + "' on line " + decimal(it->first.Mark().line + 1) +
              " a misspelling?";
      break;
    }
  }
  return text;
}

}  // namespace

ParamReader::ParamReader(const YAML::Node& node, std::string file, std::string path)
    : node_(node), file_(std::move(file)), path_(std::move(path)) {
  if (node_.IsDefined() && !node_.IsNull() && !node_.IsMap()) {
    throw ConfigError(location(file_, node_.Mark()) + ": " +
                      (path_.empty() ? std::string("document") : path_) +
                      ": expected a mapping, got " + describe(node_));
  }
}

bool ParamReader::has(const std::string& key) const {
  return lookup(node_, key, nullptr).IsDefined();
}

std::string ParamReader::where(const std::string& key) const {
  YAML::Mark mark = YAML::Mark::null_mark();
  if (!key.empty()) lookup(node_, key, &mark);
  if (mark.is_null() && node_.IsDefined()) mark = node_.Mark();
  std::string full = path_;
  if (!key.empty()) full = path_.empty() ? key : path_ + "." + key;
  std::string text = location(file_, mark) + ":";
  if (!full.empty()) text += " " + full + ":";
  return text;
}

void ParamReader::fail(const std::string& key, const std::string& message) const {
  throw ConfigError(where(key) + " " + message);
}

double ParamReader::number(const std::string& key, double min, double max) {
  known_.push_back(key);
  const YAML::Node value = lookup(node_, key, nullptr);
  const std::string expected =
      "expected " + range_text("a number", min, max, -std::numeric_limits<double>::max(),
                               std::numeric_limits<double>::max());
  if (!value.IsDefined()) {
    // Missing keys are reported at the enclosing mapping.
    throw ConfigError(missing(*this, key, expected));
  }
  double result = 0.0;
  bool ok = value.IsScalar();
  if (ok) {
    try {
      result = value.as<double>();
    } catch (const YAML::Exception&) {
      ok = false;
    }
  }
  if (!ok || !std::isfinite(result)) fail(key, expected + ", got " + describe(value));
  if (result < min || result > max) fail(key, expected + ", got " + value.Scalar());
  return result;
}

double ParamReader::number_or(const std::string& key, double fallback, double min, double max) {
  if (!has(key)) {
    known_.push_back(key);
    return fallback;
  }
  return number(key, min, max);
}

int ParamReader::integer(const std::string& key, int min, int max) {
  known_.push_back(key);
  const YAML::Node value = lookup(node_, key, nullptr);
  const std::string expected =
      "expected " + range_text("an integer", min, max, std::numeric_limits<int>::min(),
                               std::numeric_limits<int>::max());
  if (!value.IsDefined()) {
    throw ConfigError(missing(*this, key, expected));
  }
  long long result = 0;
  bool ok = value.IsScalar();
  if (ok) {
    try {
      result = value.as<long long>();
    } catch (const YAML::Exception&) {
      ok = false;
    }
  }
  if (!ok) fail(key, expected + ", got " + describe(value));
  if (result < min || result > max) fail(key, expected + ", got " + value.Scalar());
  return static_cast<int>(result);
}

int ParamReader::integer_or(const std::string& key, int fallback, int min, int max) {
  if (!has(key)) {
    known_.push_back(key);
    return fallback;
  }
  return integer(key, min, max);
}

bool ParamReader::boolean_or(const std::string& key, bool fallback) {
  known_.push_back(key);
  const YAML::Node value = lookup(node_, key, nullptr);
  if (!value.IsDefined()) return fallback;
  if (value.IsScalar()) {
    try {
      return value.as<bool>();
    } catch (const YAML::Exception&) {
    }
  }
  fail(key, "expected true or false, got " + describe(value));
}

std::string ParamReader::string(const std::string& key) {
  known_.push_back(key);
  const YAML::Node value = lookup(node_, key, nullptr);
  if (!value.IsDefined()) {
    throw ConfigError(missing(*this, key, "expected a string"));
  }
  if (!value.IsScalar() || value.Scalar().empty()) {
    fail(key, "expected a non-empty string, got " + describe(value));
  }
  return value.Scalar();
}

std::string ParamReader::string_or(const std::string& key, const std::string& fallback) {
  if (!has(key)) {
    known_.push_back(key);
    return fallback;
  }
  return string(key);
}

std::string ParamReader::choice_or(const std::string& key, const std::string& fallback,
                                   const std::vector<std::string>& choices) {
  std::string value = string_or(key, fallback);
  if (std::find(choices.begin(), choices.end(), value) != choices.end()) return value;
  std::string list;
  for (const auto& c : choices) list += (list.empty() ? "" : ", ") + c;
  fail(key, "expected one of " + list + ", got '" + value + "'");
}

ParamReader ParamReader::child(const std::string& key) {
  known_.push_back(key);
  const YAML::Node value = lookup(node_, key, nullptr);
  const std::string full = path_.empty() ? key : path_ + "." + key;
  if (value.IsDefined() && !value.IsNull() && !value.IsMap()) {
    fail(key, "expected a mapping, got " + describe(value));
  }
  return {value, file_, full};
}

YAML::Node ParamReader::sequence(const std::string& key) {
  known_.push_back(key);
  YAML::Node value = lookup(node_, key, nullptr);
  if (!value.IsDefined() || value.IsNull()) return YAML::Node(YAML::NodeType::Sequence);
  if (!value.IsSequence()) fail(key, "expected a list, got " + describe(value));
  return value;
}

YAML::Node ParamReader::raw(const std::string& key) {
  known_.push_back(key);
  return lookup(node_, key, nullptr);
}

ParamReader ParamReader::element(const YAML::Node& seq, const std::string& key,
                                 std::size_t i) const {
  const std::string base = path_.empty() ? key : path_ + "." + key;
  const YAML::Node item = seq[i];
  if (!item.IsMap()) {
    throw ConfigError(location(file_, item.Mark()) + ": " + base + "[" +
                      decimal(static_cast<long long>(i)) + "]: expected a mapping, got " +
                      describe(item));
  }
  return {item, file_, base + "[" + decimal(static_cast<long long>(i)) + "]"};
}

void ParamReader::finish() const {
  if (!node_.IsMap()) return;
  for (auto it = node_.begin(); it != node_.end(); ++it) {
    const std::string key = it->first.IsScalar() ? it->first.Scalar() : std::string();
    if (!key.empty() && std::find(known_.begin(), known_.end(), key) != known_.end()) continue;
    std::vector<std::string> unique;
    std::string known;
    for (const auto& k : known_) {
      if (std::find(unique.begin(), unique.end(), k) != unique.end()) continue;
      unique.push_back(k);
      known += (known.empty() ? "" : ", ") + k;
    }
    const std::string full = path_.empty() ? key : path_ + "." + key;
    throw ConfigError(
        location(file_, it->first.Mark()) + ": " + (key.empty() ? path_ + ": non-text key" : full) +
        ": unknown key" +
        (known.empty() ? " (this mapping takes no keys)" : " (known: " + known + ")"));
  }
}

}  // namespace swivel
