// SPDX-License-Identifier: Apache-2.0
#include "swivel/run_log.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <istream>
#include <numbers>
#include <ostream>
#include <string_view>
#include <system_error>
#include <utility>

namespace swivel {
namespace {

// Header keys, matched on a comment's text after '#' and blanks: "#robot: x" is the robot line
// as much as "# robot: x". An annotation is written back as "# <text>", so a key must not
// depend on the blanks after '#', or an annotation could read back as a key.
constexpr std::string_view kVersionKey = "swivel-run";
constexpr std::string_view kRobotKey = "robot:";
constexpr std::string_view kDrivetrainKey = "drivetrain:";
constexpr std::string_view kModulesKey = "modules:";
// What gyro_wz means in time (RunLogHeader::gyro_mean_over_row) and its two values.
constexpr std::string_view kGyroTimingKey = "gyro_wz:";
constexpr std::string_view kGyroMean = "mean over the row";
constexpr std::string_view kGyroReading = "reading at t";
// The optional trailing columns (RunLogHeader::estimate_columns).
constexpr std::array<const char*, 4> kEstimateColumns = {"est_x", "est_y", "est_yaw", "fault"};

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) {
    s.remove_suffix(1);
  }
  return s;
}

bool starts_with(std::string_view s, std::string_view prefix) {
  return s.substr(0, prefix.size()) == prefix;
}

void validate_header(const RunLogHeader& h, const std::string& where) {
  if (h.drivetrain == DrivetrainKind::kDifferential && h.module_count != 2) {
    throw RunLogError(where + "a differential run log has 2 wheels, got " +
                      std::to_string(h.module_count));
  }
  if (h.module_count < 2 || h.module_count > kMaxModules) {
    throw RunLogError(where + "expected between 2 and " + std::to_string(kMaxModules) +
                      " modules, got " + std::to_string(h.module_count));
  }
}

void append_number(std::string& line, double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  line.append(buffer, result.ptr);
}

std::string join(const std::vector<std::string>& names) {
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i > 0) out += ',';
    out += names[i];
  }
  return out;
}

// Splits on commas without allocating per cell; `cells` is reused between rows.
void split(std::string_view line, std::vector<std::string_view>& cells) {
  cells.clear();
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    if (comma == std::string_view::npos) {
      cells.push_back(trim(line.substr(start)));
      return;
    }
    cells.push_back(trim(line.substr(start, comma - start)));
    start = comma + 1;
  }
}

class Parser {
 public:
  Parser(std::istream& in, std::string source) : in_(in), source_(std::move(source)) {}

  RunLog parse() {
    RunLog log;
    log.source = source_;
    read_comments(log.header);
    std::vector<std::string> columns = run_log_columns(log.header);
    read_header_row(log.header, columns);
    read_rows(log, columns);
    return log;
  }

 private:
  [[noreturn]] void fail(const std::string& message) const {
    const std::size_t line = line_number_ == 0 ? 1 : line_number_;  // an empty file
    throw RunLogError(source_ + ":" + std::to_string(line) + ": " + message);
  }

  bool next_line() {
    if (!std::getline(in_, line_)) return false;
    ++line_number_;
    return true;
  }

  // Reads the leading comment lines; leaves the first non-comment line in line_.
  void read_comments(RunLogHeader& header) {
    bool have_version = false;
    bool have_drivetrain = false;
    bool have_modules = false;
    have_line_ = false;
    while (next_line()) {
      const std::string_view line = trim(line_);
      if (line.empty()) continue;
      if (line.front() != '#') {
        have_line_ = true;
        break;
      }
      // Header lines are text: a control byte means a corrupt file, and could not be written
      // back unchanged.
      for (const char c : line) {
        const auto byte = static_cast<unsigned char>(c);
        if ((byte < 0x20 && c != '\t') || byte == 0x7f) {
          char code[8];
          (void)std::snprintf(code, sizeof code, "0x%02x", byte);
          fail(std::string("control character ") + code + " in a header comment line");
        }
      }
      const std::string_view text = trim(line.substr(1));
      if (text == kVersionKey ||
          (starts_with(text, kVersionKey) &&
           (text[kVersionKey.size()] == ' ' || text[kVersionKey.size()] == '\t'))) {
        const std::string_view value = trim(text.substr(kVersionKey.size()));
        int version = 0;
        const auto r = std::from_chars(value.data(), value.data() + value.size(), version);
        if (r.ec != std::errc() || r.ptr != value.data() + value.size()) {
          fail("expected '# swivel-run " + std::to_string(kRunLogVersion) + "', got '" +
               std::string(line) + "'");
        }
        if (version != kRunLogVersion) {
          fail("unsupported run log version " + std::to_string(version) + " (this reader reads " +
               std::to_string(kRunLogVersion) + ")");
        }
        have_version = true;
      } else if (starts_with(text, kRobotKey)) {
        header.robot = std::string(trim(text.substr(kRobotKey.size())));
      } else if (starts_with(text, kDrivetrainKey)) {
        const std::string_view value = trim(text.substr(kDrivetrainKey.size()));
        if (value == "differential") {
          header.drivetrain = DrivetrainKind::kDifferential;
        } else if (value == "swpc") {
          header.drivetrain = DrivetrainKind::kSwpc;
        } else {
          fail("expected drivetrain 'differential' or 'swpc', got '" + std::string(value) + "'");
        }
        have_drivetrain = true;
      } else if (starts_with(text, kModulesKey)) {
        const std::string_view value = trim(text.substr(kModulesKey.size()));
        std::size_t n = 0;
        const auto r = std::from_chars(value.data(), value.data() + value.size(), n);
        if (r.ec != std::errc() || r.ptr != value.data() + value.size()) {
          fail("expected a module count, got '" + std::string(value) + "'");
        }
        header.module_count = n;
        have_modules = true;
      } else if (starts_with(text, kGyroTimingKey)) {
        const std::string_view value = trim(text.substr(kGyroTimingKey.size()));
        if (value != kGyroMean && value != kGyroReading) {
          fail("expected '# gyro_wz: " + std::string(kGyroMean) + "' or '# gyro_wz: " +
               std::string(kGyroReading) + "', got '" + std::string(line) + "'");
        }
        header.gyro_mean_over_row = value == kGyroMean;
      } else if (have_version) {
        // Any other comment is an annotation: kept, never interpreted.
        header.comments.emplace_back(text);
      }
    }
    if (!have_version) {
      fail("missing '# swivel-run " + std::to_string(kRunLogVersion) + "' line");
    }
    if (!have_drivetrain) fail("missing '# drivetrain: differential|swpc' line");
    if (header.drivetrain == DrivetrainKind::kSwpc && !have_modules) {
      fail("missing '# modules: N' line (required for an swpc run log)");
    }
    if (header.drivetrain == DrivetrainKind::kDifferential) {
      if (have_modules && header.module_count != 2) {
        fail("a differential run log has 2 wheels, got '# modules: " +
             std::to_string(header.module_count) + "'");
      }
      header.module_count = 2;
    }
    validate_header(header, source_ + ":" + std::to_string(line_number_) + ": ");
  }

  // The header row decides whether the optional estimate columns follow the truth columns.
  void read_header_row(RunLogHeader& header, std::vector<std::string>& columns) {
    const std::string expected = join(columns);
    if (!have_line_) fail("missing header row '" + expected + "'");
    split(line_, cells_);
    const auto matches = [this](const std::vector<std::string>& names) {
      bool match = cells_.size() == names.size();
      for (std::size_t i = 0; match && i < names.size(); ++i) match = cells_[i] == names[i];
      return match;
    };
    if (matches(columns)) return;
    RunLogHeader with_estimate = header;
    with_estimate.estimate_columns = true;
    std::vector<std::string> extended = run_log_columns(with_estimate);
    if (matches(extended)) {
      header.estimate_columns = true;
      columns = std::move(extended);
      return;
    }
    fail("expected header row '" + expected + "' (optionally followed by '," +
         join(std::vector<std::string>(kEstimateColumns.begin(), kEstimateColumns.end())) +
         "'), got '" + std::string(trim(line_)) + "'");
  }

  [[nodiscard]] double number(std::string_view cell, const std::string& column) const {
    double value = 0.0;
    const auto r = std::from_chars(cell.data(), cell.data() + cell.size(), value);
    if (cell.empty() || r.ec != std::errc() || r.ptr != cell.data() + cell.size() ||
        !std::isfinite(value)) {
      fail("column " + column + ": expected a finite number, got '" + std::string(cell) + "'");
    }
    return value;
  }

  void read_rows(RunLog& log, const std::vector<std::string>& names) {
    const std::size_t column_count = names.size();
    const std::size_t n = log.header.module_count;
    const bool swpc = log.header.drivetrain == DrivetrainKind::kSwpc;
    while (next_line()) {
      const std::string_view line = trim(line_);
      if (line.empty() || line.front() == '#') continue;
      split(line, cells_);
      if (cells_.size() != column_count) {
        fail("expected " + std::to_string(column_count) + " columns, got " +
             std::to_string(cells_.size()));
      }
      RunLogSample s;
      std::size_t c = 0;
      auto next = [&]() {
        const double v = number(cells_[c], names[c]);
        ++c;
        return v;
      };
      s.t_s = next();
      const std::size_t empty_cmd = static_cast<std::size_t>(cells_[1].empty()) +
                                    static_cast<std::size_t>(cells_[2].empty()) +
                                    static_cast<std::size_t>(cells_[3].empty());
      if (empty_cmd == 0) {
        s.cmd.vx_mps = next();
        s.cmd.vy_mps = next();
        s.cmd.wz_radps = next();
      } else if (empty_cmd == 3) {
        s.has_cmd = false;  // no command logged
        c += 3;
      } else {
        std::string empty_names;
        for (std::size_t i = 1; i <= 3; ++i) {
          if (!cells_[i].empty()) continue;
          if (!empty_names.empty()) empty_names += " and ";
          empty_names += names[i];
        }
        fail("column " + empty_names +
             ": empty, but cmd_vx, cmd_vy and cmd_wz must be all present or all empty");
      }
      if (swpc) {
        for (std::size_t i = 0; i < n; ++i) s.steer_rad[i] = next();
      }
      for (std::size_t i = 0; i < n; ++i) s.wheel_rad[i] = next();
      if (cells_[c].empty()) {
        s.has_gyro = false;  // no gyro sample
        ++c;
      } else {
        s.gyro_wz_radps = next();
      }
      const std::size_t empty = static_cast<std::size_t>(cells_[c].empty()) +
                                static_cast<std::size_t>(cells_[c + 1].empty()) +
                                static_cast<std::size_t>(cells_[c + 2].empty());
      if (empty == 0) {
        s.has_truth = true;
        s.truth.x_m = next();
        s.truth.y_m = next();
        s.truth.yaw_rad = next();
      } else if (empty != 3) {
        fail("truth_x, truth_y and truth_yaw must be all present or all empty");
      } else {
        c += 3;
      }
      if (log.header.estimate_columns) {
        s.estimate.x_m = next();
        s.estimate.y_m = next();
        s.estimate.yaw_rad = next();
        const double fault = next();
        if (fault < 0.0 || fault > 65535.0 || fault != std::floor(fault)) {
          fail("column fault: expected a fault code (an integer in [0, 65535]), got '" +
               std::string(cells_[c - 1]) + "'");
        }
        s.fault_code = static_cast<std::uint16_t>(fault);
      }
      if (!log.samples.empty() && s.t_s < log.samples.back().t_s) {
        std::string previous;
        append_number(previous, log.samples.back().t_s);
        fail("time goes backwards (" + std::string(cells_[0]) + " after " + previous + ")");
      }
      log.samples.push_back(s);
    }
  }

  std::istream& in_;
  std::string source_;
  std::string line_;
  std::size_t line_number_ = 0;
  bool have_line_ = false;
  std::vector<std::string_view> cells_;
};

}  // namespace

std::vector<std::string> run_log_columns(const RunLogHeader& header) {
  std::vector<std::string> columns = {"t", "cmd_vx", "cmd_vy", "cmd_wz"};
  if (header.drivetrain == DrivetrainKind::kDifferential) {
    columns.emplace_back("wheel_l");
    columns.emplace_back("wheel_r");
  } else {
    for (std::size_t i = 1; i <= header.module_count; ++i) {
      columns.push_back("steer_" + std::to_string(i));
    }
    for (std::size_t i = 1; i <= header.module_count; ++i) {
      columns.push_back("wheel_" + std::to_string(i));
    }
  }
  for (const char* name : {"gyro_wz", "truth_x", "truth_y", "truth_yaw"}) {
    columns.emplace_back(name);
  }
  if (header.estimate_columns) {
    for (const char* name : kEstimateColumns) columns.emplace_back(name);
  }
  return columns;
}

RunLogHeader run_log_header(const RobotModel& model) {
  RunLogHeader h;
  h.robot = model.name;
  h.drivetrain = model.drivetrain;
  h.module_count = model.module_count();
  return h;
}

RunLogWriter::RunLogWriter(const std::string& path, RunLogHeader header)
    : header_(std::move(header)), path_(path) {
  validate_header(header_, path + ": ");
  file_.open(path, std::ios::out | std::ios::trunc);
  if (!file_) throw RunLogError(path + ": cannot open for writing");
  out_ = &file_;
  start();
}

RunLogWriter::RunLogWriter(std::ostream& out, RunLogHeader header)
    : header_(std::move(header)), out_(&out), path_("<stream>") {
  validate_header(header_, path_ + ": ");
  start();
}

void RunLogWriter::start() {
  *out_ << "# swivel-run " << kRunLogVersion << '\n';
  *out_ << "# robot: " << header_.robot << '\n';
  const bool swpc = header_.drivetrain == DrivetrainKind::kSwpc;
  *out_ << "# drivetrain: " << (swpc ? "swpc" : "differential") << '\n';
  if (swpc) *out_ << "# modules: " << header_.module_count << '\n';
  if (header_.gyro_mean_over_row) *out_ << "# " << kGyroTimingKey << ' ' << kGyroMean << '\n';
  for (const std::string& comment : header_.comments) *out_ << "# " << comment << '\n';
  *out_ << join(run_log_columns(header_)) << '\n';
  if (!*out_) throw RunLogError(path_ + ": write failed");
}

void RunLogWriter::write(const RunLogSample& s) {
  line_.clear();
  auto add = [this](double v) {
    append_number(line_, v);
    line_ += ',';
  };
  add(s.t_s);
  if (s.has_cmd) {
    add(s.cmd.vx_mps);
    add(s.cmd.vy_mps);
    add(s.cmd.wz_radps);
  } else {
    line_ += ",,,";  // three empty command cells
  }
  const std::size_t n = header_.module_count;
  if (header_.drivetrain == DrivetrainKind::kSwpc) {
    for (std::size_t i = 0; i < n; ++i) add(s.steer_rad[i]);
  }
  for (std::size_t i = 0; i < n; ++i) add(s.wheel_rad[i]);
  if (s.has_gyro) {
    add(s.gyro_wz_radps);
  } else {
    line_ += ',';  // an empty gyro cell
  }
  if (s.has_truth) {
    add(s.truth.x_m);
    add(s.truth.y_m);
    append_number(line_, s.truth.yaw_rad);
  } else {
    line_ += ",,";  // three empty truth cells
  }
  if (header_.estimate_columns) {
    line_ += ',';
    add(s.estimate.x_m);
    add(s.estimate.y_m);
    add(s.estimate.yaw_rad);
    line_ += std::to_string(s.fault_code);
  }
  line_ += '\n';
  out_->write(line_.data(), static_cast<std::streamsize>(line_.size()));
  if (!*out_) throw RunLogError(path_ + ": write failed");
}

void RunLogWriter::flush() {
  out_->flush();
  if (!*out_) throw RunLogError(path_ + ": write failed");
}

RunLog read_run_log(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw RunLogError(path + ": cannot open for reading");
  return parse_run_log(in, path);
}

RunLog parse_run_log(std::istream& in, const std::string& source_name) {
  return Parser(in, source_name).parse();
}

double unwrap_near(double angle_rad, double reference_rad) noexcept {
  constexpr double kTurn = 2.0 * std::numbers::pi;
  return angle_rad - kTurn * std::round((angle_rad - reference_rad) / kTurn);
}

void unwrap_steering(RunLog& log) {
  if (log.header.drivetrain != DrivetrainKind::kSwpc) return;
  const std::size_t n = std::min<std::size_t>(log.header.module_count, kMaxModules);
  for (std::size_t k = 1; k < log.samples.size(); ++k) {
    for (std::size_t i = 0; i < n; ++i) {
      double& phi = log.samples[k].steer_rad[i];
      phi = unwrap_near(phi, log.samples[k - 1].steer_rad[i]);
    }
  }
}

}  // namespace swivel
