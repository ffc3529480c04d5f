// SPDX-License-Identifier: Apache-2.0
#include "swivel/run_import/run_import.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <istream>
#include <limits>
#include <numbers>
#include <span>
#include <sstream>
#include <string_view>
#include <system_error>
#include <utility>

#include "swivel/config/config_error.hpp"
#include "swivel/config/param_reader.hpp"

namespace swivel::run_import {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr int kMaxColumnIndex = 1 << 20;

// A unit's name in a map and its factor to SI.
struct Unit {
  std::string_view name;
  double to_si;
};
constexpr std::array<Unit, 4> kTimeUnits = {{{"s", 1.0}, {"ms", 1e-3}, {"us", 1e-6}, {"ns", 1e-9}}};
constexpr std::array<Unit, 2> kLengthUnits = {{{"m", 1.0}, {"mm", 1e-3}}};
constexpr std::array<Unit, 2> kAngleUnits = {{{"rad", 1.0}, {"deg", std::numbers::pi / 180.0}}};
constexpr std::array<Unit, 2> kRateUnits = {{{"rad/s", 1.0}, {"deg/s", std::numbers::pi / 180.0}}};
constexpr std::array<Unit, 2> kSpeedUnits = {{{"m/s", 1.0}, {"mm/s", 1e-3}}};

YAML::Node parse_yaml(const std::string& text, const std::string& source_name) {
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    std::string where = source_name;
    if (!e.mark.is_null()) {
      where += ":" + std::to_string(e.mark.line + 1) + ":" + std::to_string(e.mark.column + 1);
    }
    throw ConfigError(where + ": invalid YAML: " + e.msg);
  }
}

// The unit key's factor to SI; `fallback` is the unit assumed when the key is absent (empty:
// the key is required).
double unit_scale(ParamReader& r, std::span<const Unit> units, const std::string& fallback) {
  std::vector<std::string> names;
  for (const Unit& u : units) names.emplace_back(u.name);
  if (fallback.empty()) r.string("unit");  // a missing unit is reported as missing
  const std::string unit = r.choice_or("unit", fallback, names);
  for (const Unit& u : units) {
    if (u.name == unit) return u.to_si;
  }
  return 1.0;  // not reached: choice_or accepted one of the names
}

double sign_of(ParamReader& r) {
  const double sign = r.number_or("sign", 1.0);
  if (sign != 1.0 && sign != -1.0) {
    r.fail("sign", "expected 1 or -1, got " + r.node()["sign"].Scalar());
  }
  return sign;
}

ColumnRef column_ref(ParamReader& r, bool header_row) {
  ColumnRef c;
  c.key = r.path();
  const bool by_name = r.has("column");
  const bool by_index = r.has("index");
  if (by_name == by_index) {
    r.fail("", by_name ? "give either 'column' (a header name) or 'index' (0-based), not both"
                       : "missing 'column' (a header name) or 'index' (0-based)");
  }
  if (by_name) {
    c.name = r.string("column");
    if (c.name.empty()) r.fail("column", "expected a header name, got ''");
    if (!header_row) {
      r.fail("column",
             "a column by name needs 'input: {header_row: true}'; without a header "
             "row give its 0-based 'index'");
    }
    r.integer_or("index", 0, 0, kMaxColumnIndex);  // marks the key as known
  } else {
    c.index = static_cast<std::size_t>(r.integer("index", 0, kMaxColumnIndex));
    r.string_or("column", "");
  }
  return c;
}

// A column with a unit (from `units`, `fallback` when absent) and a sign.
ScaledColumn scaled_column(ParamReader r, bool header_row, std::span<const Unit> units,
                           const std::string& fallback) {
  ScaledColumn s;
  s.column = column_ref(r, header_row);
  s.scale = unit_scale(r, units, fallback) * sign_of(r);
  r.finish();
  return s;
}

WheelColumn wheel_column(ParamReader r, bool header_row) {
  WheelColumn w;
  w.column = column_ref(r, header_row);
  r.string("mode");  // a missing mode is reported as missing
  const std::string mode =
      r.choice_or("mode", "", {"counts_per_row", "cumulative_counts", "cumulative_angle"});
  const double sign = sign_of(r);
  if (mode == "cumulative_angle") {
    w.mode = WheelMode::kCumulativeAngle;
    if (r.has("counts_per_rev")) {
      r.fail("counts_per_rev",
             "applies to the count modes only (this wheel's mode is "
             "cumulative_angle; give its 'unit')");
    }
    w.rad_per_unit = sign * unit_scale(r, kAngleUnits, "");
  } else {
    w.mode = mode == "counts_per_row" ? WheelMode::kCountsPerRow : WheelMode::kCumulativeCounts;
    if (r.has("unit")) {
      r.fail("unit",
             "applies to mode cumulative_angle only (this wheel counts encoder counts; "
             "give its 'counts_per_rev')");
    }
    const double counts = r.number("counts_per_rev");
    if (!(counts > 0.0)) {
      r.fail("counts_per_rev",
             "expected a positive number, got " + r.node()["counts_per_rev"].Scalar());
    }
    w.rad_per_unit = sign * kTwoPi / counts;
  }
  r.finish();
  return w;
}

// Blanks around a line or cell (and a CR line end) are not data, except that a tab is never a
// blank when it is the delimiter: a tab-separated line may end in empty cells.
std::string_view trim(std::string_view s, char delimiter) {
  const auto blank = [delimiter](char c) { return c == ' ' || (c == '\t' && delimiter != '\t'); };
  while (!s.empty() && blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && (blank(s.back()) || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

void split(std::string_view line, char delimiter, std::vector<std::string_view>& cells) {
  cells.clear();
  std::size_t start = 0;
  while (true) {
    const std::size_t at = line.find(delimiter, start);
    const std::string_view cell =
        line.substr(start, at == std::string_view::npos ? std::string_view::npos : at - start);
    cells.push_back(trim(cell, delimiter));
    if (at == std::string_view::npos) return;
    start = at + 1;
  }
}

class Importer {
 public:
  Importer(std::istream& in, std::string name, ImportMap map)
      : in_(in), name_(std::move(name)), map_(std::move(map)) {}

  RunLog run(ImportSummary& summary) {
    RunLog log;
    log.source = name_;
    log.header.robot = map_.robot;
    log.header.drivetrain = map_.drivetrain;
    log.header.module_count = map_.module_count;
    log.header.comments.push_back("imported from: " + name_);
    log.header.comments.push_back("import map: " + map_.source);
    if (map_.real_period_s && map_.time) {
      log.header.comments.push_back(
          "time: the time column's steps of " + number_text(*map_.nominal_period_s) +
          " s rescaled to a real row period of " + number_text(*map_.real_period_s) + " s");
    } else if (map_.real_period_s) {
      log.header.comments.push_back("time: a fixed row period of " +
                                    number_text(*map_.real_period_s) + " s");
    }
    resolve_columns();
    const std::size_t n = map_.module_count;
    std::vector<double> wheel_counts(n, 0.0);
    double first_raw_t = 0.0;
    double previous_raw_t = 0.0;
    while (next_data_line()) {
      const std::size_t row = log.samples.size();
      RunLogSample s;
      // Time.
      if (map_.time) {
        const double raw = required(*map_.time);
        if (row > 0 && raw < previous_raw_t) {
          fail(*map_.time, "time goes backwards (" + std::string(cell(*map_.time)) + " after " +
                               number_text(previous_raw_t / map_.time->scale) + ")");
        }
        if (row == 0) first_raw_t = raw;
        if (map_.nominal_period_s && row > 0) {
          const double periods = (raw - previous_raw_t) / *map_.nominal_period_s;
          const double whole = std::round(periods);
          if (whole < 1.0 || std::abs(periods - whole) > 0.05) {
            fail(*map_.time, "step of " + number_text(raw - previous_raw_t) +
                                 " s is not a whole number of nominal periods (" +
                                 number_text(*map_.nominal_period_s) + " s)");
          }
          if (whole >= 2.0) ++summary.gaps;
        }
        previous_raw_t = raw;
        s.t_s = map_.real_period_s ? first_raw_t + (raw - first_raw_t) * *map_.real_period_s /
                                                       *map_.nominal_period_s
                                   : raw;
      } else {
        s.t_s = static_cast<double>(row) * *map_.real_period_s;
      }
      // Wheels and steering.
      for (std::size_t i = 0; i < n; ++i) {
        const WheelColumn& w = map_.wheels[i];
        const double raw = required(ScaledColumn{w.column, 1.0});
        if (w.mode == WheelMode::kCountsPerRow) {
          wheel_counts[i] += raw;
          s.wheel_rad[i] = wheel_counts[i] * w.rad_per_unit;
        } else {
          s.wheel_rad[i] = raw * w.rad_per_unit;
        }
      }
      for (std::size_t i = 0; i < map_.steering.size(); ++i) {
        s.steer_rad[i] = required(map_.steering[i]);
      }
      // Motion capture, gyro and commands: empty or NaN cells mean no sample.
      if (map_.truth_x) {
        const std::array<const ScaledColumn*, 3> truth = {&*map_.truth_x, &*map_.truth_y,
                                                          &*map_.truth_yaw};
        std::array<std::optional<double>, 3> v;
        std::size_t present = 0;
        for (std::size_t k = 0; k < 3; ++k) {
          v[k] = optional(*truth[k]);
          present += v[k] ? 1U : 0U;
        }
        if (present == 3) {
          s.has_truth = true;
          s.truth = Pose2{*v[0], *v[1], *v[2]};
          ++summary.truth_rows;
        } else if (present != 0) {
          const std::size_t missing = !v[0] ? 0 : (!v[1] ? 1 : 2);
          fail(*truth[missing],
               "empty, but the motion-capture x, y and yaw must be all present "
               "or all empty");
        }
      }
      s.has_gyro = false;
      if (map_.gyro) {
        if (const auto g = optional(*map_.gyro)) {
          s.gyro_wz_radps = *g;
          s.has_gyro = true;
          ++summary.gyro_rows;
        }
      }
      s.has_cmd = false;
      if (map_.cmd_vx) {
        const auto vx = optional(*map_.cmd_vx);
        const auto wz = optional(*map_.cmd_wz);
        const auto vy = map_.cmd_vy ? optional(*map_.cmd_vy) : std::nullopt;
        const std::size_t columns = map_.cmd_vy ? 3U : 2U;
        const std::size_t present = (vx ? 1U : 0U) + (vy ? 1U : 0U) + (wz ? 1U : 0U);
        if (present == columns) {
          s.has_cmd = true;
          s.cmd = Twist2{*vx, vy.value_or(0.0), *wz};  // no vy column: a differential command
          ++summary.command_rows;
        } else if (present != 0) {
          const ScaledColumn& missing = !vx ? *map_.cmd_vx : (!wz ? *map_.cmd_wz : *map_.cmd_vy);
          fail(missing, "empty, but the command columns must be all present or all empty");
        }
      }
      log.samples.push_back(s);
    }
    if (log.samples.empty()) {
      throw ImportError(name_ + ":" + std::to_string(std::max<std::size_t>(line_number_, 1)) +
                        ": no data rows");
    }
    summary.rows = log.samples.size();
    summary.first_t_s = log.samples.front().t_s;
    summary.last_t_s = log.samples.back().t_s;
    return log;
  }

 private:
  static std::string number_text(double v) {
    std::ostringstream s;
    s.precision(10);
    s << v;
    return s.str();
  }

  [[noreturn]] void fail_line(const std::string& message) const {
    throw ImportError(name_ + ":" + std::to_string(line_number_) + ": " + message);
  }

  [[nodiscard]] std::string column_text(const ColumnRef& c) const {
    std::string text = "column ";
    text += c.name.empty() ? std::to_string(c.index)
                           : c.name + " (index " + std::to_string(c.index) + ")";
    return text + " [" + map_.source + ": " + c.key + "]";
  }

  [[noreturn]] void fail(const ScaledColumn& c, const std::string& message) const {
    fail_line(column_text(c.column) + ": " + message);
  }

  bool next_line() {
    if (!std::getline(in_, line_)) return false;
    ++line_number_;
    return true;
  }

  [[nodiscard]] bool skipped(std::string_view line) const {
    if (line.empty()) return true;
    return !map_.comment_prefix.empty() &&
           line.substr(0, map_.comment_prefix.size()) == map_.comment_prefix;
  }

  // The next line that is neither blank nor a comment, split into cells_.
  bool next_data_line() {
    while (next_line()) {
      const std::string_view line = trim(line_, map_.delimiter);
      if (skipped(line)) continue;
      split(line, map_.delimiter, cells_);
      if (cells_.size() < min_columns_) {
        fail_line("expected at least " + std::to_string(min_columns_) + " columns, got " +
                  std::to_string(cells_.size()));
      }
      return true;
    }
    return false;
  }

  std::vector<ColumnRef*> all_columns() {
    std::vector<ColumnRef*> refs;
    auto add = [&refs](std::optional<ScaledColumn>& c) {
      if (c) refs.push_back(&c->column);
    };
    add(map_.time);
    for (auto& w : map_.wheels) refs.push_back(&w.column);
    for (auto& s : map_.steering) refs.push_back(&s.column);
    add(map_.truth_x);
    add(map_.truth_y);
    add(map_.truth_yaw);
    add(map_.gyro);
    add(map_.cmd_vx);
    add(map_.cmd_vy);
    add(map_.cmd_wz);
    return refs;
  }

  void resolve_columns() {
    std::vector<ColumnRef*> refs = all_columns();
    if (map_.header_row) {
      bool found = false;
      while (next_line()) {
        const std::string_view line = trim(line_, map_.delimiter);
        if (skipped(line)) continue;
        found = true;
        break;
      }
      if (!found) {
        throw ImportError(name_ + ":" + std::to_string(std::max<std::size_t>(line_number_, 1)) +
                          ": missing header row (the map says 'header_row: true')");
      }
      split(trim(line_, map_.delimiter), map_.delimiter, cells_);
      for (ColumnRef* c : refs) {
        if (c->name.empty()) continue;
        const auto it = std::find(cells_.begin(), cells_.end(), c->name);
        if (it == cells_.end()) {
          fail_line("header row has no column '" + c->name + "' [" + map_.source + ": " + c->key +
                    "]");
        }
        c->index = static_cast<std::size_t>(it - cells_.begin());
      }
    }
    for (const ColumnRef* c : refs) min_columns_ = std::max(min_columns_, c->index + 1);
  }

  [[nodiscard]] std::string_view cell(const ScaledColumn& c) const {
    return cells_[c.column.index];
  }

  static std::optional<double> parse(std::string_view text) {
    if (!text.empty() && text.front() == '+') text.remove_prefix(1);
    double value = 0.0;
    const auto r = std::from_chars(text.data(), text.data() + text.size(), value);
    if (text.empty() || r.ec != std::errc() || r.ptr != text.data() + text.size()) {
      return std::nullopt;
    }
    return value;
  }

  [[nodiscard]] double required(const ScaledColumn& c) const {
    const std::string_view text = cell(c);
    const std::optional<double> v = parse(text);
    if (!v || !std::isfinite(*v)) {
      fail(c, "expected a finite number, got '" + std::string(text) + "'");
    }
    return *v * c.scale;
  }

  // Empty or NaN: no sample. Anything else must be a finite number.
  [[nodiscard]] std::optional<double> optional(const ScaledColumn& c) const {
    const std::string_view text = cell(c);
    if (text.empty()) return std::nullopt;
    const std::optional<double> v = parse(text);
    if (v && std::isnan(*v)) return std::nullopt;
    if (!v || !std::isfinite(*v)) {
      fail(c, "expected a finite number, empty or NaN, got '" + std::string(text) + "'");
    }
    return *v * c.scale;
  }

  std::istream& in_;
  std::string name_;
  ImportMap map_;  // a copy: header names resolve to indices in it
  std::string line_;
  std::size_t line_number_ = 0;
  std::size_t min_columns_ = 1;
  std::vector<std::string_view> cells_;
};

}  // namespace

ImportMap parse_import_map(const std::string& yaml_text, const std::string& source_name) {
  const YAML::Node root = parse_yaml(yaml_text, source_name);
  ParamReader r(root, source_name, "");
  ImportMap m;
  m.source = source_name;
  m.robot = r.string("robot");
  if (m.robot.empty()) r.fail("robot", "expected the robot model's name, got ''");
  r.string("drivetrain");  // a missing key is reported before the choice is checked
  const std::string kind = r.choice_or("drivetrain", "", {"differential", "swpc"});
  m.drivetrain = kind == "swpc" ? DrivetrainKind::kSwpc : DrivetrainKind::kDifferential;
  if (m.drivetrain == DrivetrainKind::kSwpc) {
    m.module_count =
        static_cast<std::size_t>(r.integer("modules", 2, static_cast<int>(kMaxModules)));
  } else {
    m.module_count = static_cast<std::size_t>(r.integer_or("modules", 2, 2, 2));
  }

  ParamReader input = r.child("input");
  m.header_row = input.boolean_or("header_row", false);
  const std::string delimiter = input.string_or("delimiter", ",");
  if (delimiter == "\\t" || delimiter == "tab") {
    m.delimiter = '\t';
  } else if (delimiter.size() == 1 && delimiter != "\"" && delimiter != "\n") {
    m.delimiter = delimiter[0];
  } else {
    input.fail("delimiter", R"(expected one character (or "\t"), got ')" + delimiter + "'");
  }
  m.comment_prefix = input.string_or("comment_prefix", "");
  input.finish();

  if (!r.has("time")) r.fail("", "missing required key 'time' (a time column or row_period_s)");
  ParamReader time = r.child("time");
  if (time.has("column") || time.has("index")) {
    ScaledColumn t;
    t.column = column_ref(time, m.header_row);
    t.scale = unit_scale(time, kTimeUnits, "s");
    m.time = t;
    if (time.has("row_period_s")) {
      time.fail("row_period_s",
                "applies without a time column; to correct a time column's "
                "period give nominal_period_s and real_period_s");
    }
    if (time.has("nominal_period_s") != time.has("real_period_s")) {
      time.fail(time.has("nominal_period_s") ? "nominal_period_s" : "real_period_s",
                "nominal_period_s and real_period_s come together (the time column's step, and "
                "the period actually achieved)");
    }
    if (time.has("nominal_period_s")) {
      m.nominal_period_s = time.number("nominal_period_s", 1e-9, 1e6);
      m.real_period_s = time.number("real_period_s", 1e-9, 1e6);
    }
  } else {
    if (!time.has("row_period_s")) {
      time.fail("", "expected a time 'column' or 'index', or a fixed 'row_period_s'");
    }
    for (const char* key : {"unit", "nominal_period_s", "real_period_s"}) {
      if (time.has(key)) {
        time.fail(key, "applies to a time column only (this map has a fixed row_period_s)");
      }
    }
    m.real_period_s = time.number("row_period_s", 1e-9, 1e6);
  }
  time.finish();

  const std::size_t n = m.module_count;
  // Every section is a known key, so that a misspelt one lists them all.
  for (const char* key : {"wheels", "steering", "truth", "gyro", "commands"}) (void)r.raw(key);
  if (!r.has("wheels")) r.fail("", "missing required key 'wheels'");
  if (m.drivetrain == DrivetrainKind::kDifferential) {
    ParamReader wheels = r.child("wheels");
    for (const char* side : {"left", "right"}) {
      if (!wheels.has(side)) wheels.fail("", std::string("missing required key '") + side + "'");
      m.wheels.push_back(wheel_column(wheels.child(side), m.header_row));
    }
    wheels.finish();
    if (r.has("steering")) {
      r.fail("steering", "applies to swpc robots only (this one is differential)");
    }
  } else {
    for (const char* key : {"wheels", "steering"}) {
      if (!r.has(key)) r.fail("", std::string("missing required key '") + key + "'");
      const YAML::Node seq = r.sequence(key);
      if (!seq.IsSequence() || seq.size() != n) {
        r.fail(key, "expected a list of " + std::to_string(n) +
                        " entries (modules: " + std::to_string(n) + "), one per module");
      }
      for (std::size_t i = 0; i < n; ++i) {
        ParamReader e = r.element(seq, key, i);
        if (std::string(key) == "wheels") {
          m.wheels.push_back(wheel_column(e, m.header_row));
        } else {
          m.steering.push_back(scaled_column(e, m.header_row, kAngleUnits, ""));
        }
      }
    }
  }

  if (r.has("truth")) {
    ParamReader truth = r.child("truth");
    for (const char* key : {"x", "y", "yaw"}) {
      if (!truth.has(key)) {
        truth.fail("", std::string("missing required key '") + key +
                           "' (the motion-capture x, y and yaw come together)");
      }
    }
    m.truth_x = scaled_column(truth.child("x"), m.header_row, kLengthUnits, "");
    m.truth_y = scaled_column(truth.child("y"), m.header_row, kLengthUnits, "");
    m.truth_yaw = scaled_column(truth.child("yaw"), m.header_row, kAngleUnits, "");
    truth.finish();
  }
  if (r.has("gyro")) m.gyro = scaled_column(r.child("gyro"), m.header_row, kRateUnits, "");
  if (r.has("commands")) {
    ParamReader cmd = r.child("commands");
    for (const char* key : {"vx", "wz"}) {
      if (!cmd.has(key)) cmd.fail("", std::string("missing required key '") + key + "'");
    }
    m.cmd_vx = scaled_column(cmd.child("vx"), m.header_row, kSpeedUnits, "");
    if (cmd.has("vy")) m.cmd_vy = scaled_column(cmd.child("vy"), m.header_row, kSpeedUnits, "");
    m.cmd_wz = scaled_column(cmd.child("wz"), m.header_row, kRateUnits, "");
    cmd.finish();
  }
  r.finish();
  return m;
}

ImportMap load_import_map(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot read import map file");
  std::stringstream text;
  text << in.rdbuf();
  return parse_import_map(text.str(), path);
}

RunLog import_run(std::istream& in, const std::string& input_name, const ImportMap& map,
                  ImportSummary* summary) {
  ImportSummary local;
  RunLog log = Importer(in, input_name, map).run(summary != nullptr ? *summary : local);
  return log;
}

ImportSummary import_file(const ImportMap& map, const std::string& input_path,
                          const std::string& output_path) {
  std::ifstream in(input_path);
  if (!in) throw ImportError(input_path + ": cannot open for reading");
  ImportSummary summary;
  const RunLog log = import_run(in, input_path, map, &summary);
  RunLogWriter writer(output_path, log.header);
  for (const RunLogSample& s : log.samples) writer.write(s);
  writer.flush();
  return summary;
}

void check_map_matches_model(const ImportMap& map, const RobotModel& model) {
  const auto kind = [](DrivetrainKind k) {
    return std::string(k == DrivetrainKind::kSwpc ? "swpc" : "differential");
  };
  std::string problem;
  if (map.robot != model.name) {
    problem = "robot '" + map.robot + "' but the model is '" + model.name + "'";
  } else if (map.drivetrain != model.drivetrain) {
    problem =
        "drivetrain " + kind(map.drivetrain) + " but the model's is " + kind(model.drivetrain);
  } else if (map.module_count != model.module_count()) {
    problem = std::to_string(map.module_count) + " modules but the model has " +
              std::to_string(model.module_count());
  }
  if (!problem.empty()) {
    throw std::invalid_argument(map.source + ": " + problem + " (" + model.source_file +
                                "); the imported run would not analyse against that model");
  }
}

}  // namespace swivel::run_import
