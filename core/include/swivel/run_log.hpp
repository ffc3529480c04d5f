// SPDX-License-Identifier: Apache-2.0
#pragma once
// Run logs: the CSV that the daemon records, the simulator writes
// and every offline tool reads. One row per sample, SI units, radians.
//
//   # swivel-run 1
//   # robot: <name>
//   # drivetrain: differential | swpc
//   # modules: <N>            (swpc only)
//   t,cmd_vx,cmd_vy,cmd_wz,wheel_l,wheel_r,gyro_wz,truth_x,truth_y,truth_yaw
//
// swpc rows carry steer_1..steer_N then wheel_1..wheel_N in place of wheel_l, wheel_r.
// The truth columns (motion capture) are empty where a row has no sample. An empty gyro_wz
// cell means the row has no gyro sample (a robot without a gyro), and three empty cmd_* cells
// mean no command was logged (a log from elsewhere); one or two empty command cells are an
// error. Steering angles may be wrapped to (-pi, pi], as absolute encoders report them: the
// reader keeps them as written, and offline tools unwrap them with unwrap_steering() or
// unwrap_near().
//
// Optional trailing columns, written only when RunLogHeader::estimate_columns is set (the
// reader tells from the header row whether a log has them; logs without them read as before):
//
//   ...,truth_yaw,est_x,est_y,est_yaw,fault
//
// est_* are the daemon's pose estimate at the row (world frame, m, m, rad) and fault is the
// active swivel::FaultCode as an integer (0: none). `swivelctl record` writes them; offline
// tools that do not need them ignore them. The command
// columns are the twist commanded at that row's time: a sample of a signal that may change
// between rows (the daemon writes the latest control cycle's command at its record rate), not
// a value held until the next row. A reader that needs the commands between rows reconstructs
// them; the model-gap replay (tools/model_gap/src/command_replay.cpp) takes each row's value
// as holding from halfway to the row before to halfway to the row after, fits one timing
// offset of up to a row for the whole run, and counts what the unknown instant of each change
// within its row leaves as noise.
//
// What each column means in time. Every column is a sample at its row's time t (s, from the
// log's start), never a value over the row:
//   t                  the instant the row's readings belong to
//   cmd_vx/vy/wz       the command in force at t (see above)
//   wheel_*, steer_*   the encoder angles at t (cumulative wheel angles; wheel increments are
//                      differences of instants, so they are exact over the row)
//   gyro_wz            the rate reading at t. A reader that integrates it says how: the
//                      model-gap sensor replay takes the trapezoid (g[k-1] + g[k]) / 2 over
//                      (t[k-1], t[k]]. A source whose gyro reports the mean rate since its
//                      previous row (an integrating sensor read once a row, as `swivel-lab
//                      simulate` reads the simulator's) declares it with the header line
//                      `# gyro_wz: mean over the row` (RunLogHeader::gyro_mean_over_row), and
//                      gyro[k] is then the mean over (t[k-1], t[k]].
//   truth_*            the motion-capture pose at t
//   est_*, fault       the daemon's estimate and active fault at t
// `swivelctl record` and `swiveld --record` write the daemon's latest control cycle at each
// row: with the loop (1 kHz by default) much faster than the record rate, the gyro column is
// the reading at t (the simulated gyro's mean over one loop cycle, 1 ms). Recording the
// simulator at the loop rate itself would make that cycle the row; neither writer declares
// it, so record below the loop rate (the defaults: 1 kHz loop, 100 Hz rows).
//
// Neither the writer nor the reader is real-time safe (they allocate and do I/O); the
// daemon hands RunLogSample values (trivially copyable) to a writer thread.

#include <array>
#include <cstddef>
#include <cstdint>
#include <fstream>
#include <iosfwd>
#include <stdexcept>
#include <string>
#include <vector>

#include "swivel/robot_model.hpp"
#include "swivel/types.hpp"

namespace swivel {

/// The format version this code writes and reads (`# swivel-run 1`).
inline constexpr int kRunLogVersion = 1;

/// A malformed, truncated or unreadable run log. The message starts with "file:line: "
/// where a line is concerned, e.g. "run.csv:57: expected 12 columns, got 11".
class RunLogError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// What the comment lines declare.
struct RunLogHeader {
  std::string robot;
  DrivetrainKind drivetrain = DrivetrainKind::kDifferential;
  /// Modules whose channels are logged: 2 (left, right) for a differential robot.
  std::size_t module_count = 2;
  /// Other comment lines (without "# "), e.g. how a run was made. Written after the fixed
  /// lines; the reader collects those that follow `# swivel-run` and interprets none.
  std::vector<std::string> comments;
  /// The rows carry est_x, est_y, est_yaw and fault after the truth columns.
  bool estimate_columns = false;
  /// gyro_wz is the mean rate over (t[k-1], t[k]] rather than the reading at t: the header
  /// line `# gyro_wz: mean over the row` (`# gyro_wz: reading at t` states the default).
  bool gyro_mean_over_row = false;
};

/// One row. For a differential robot wheel_rad[0] is the left and wheel_rad[1] the right
/// wheel, and steer_rad is unused.
struct RunLogSample {
  double t_s = 0.0;
  Twist2 cmd;                                   ///< body twist commanded at t_s (a sample)
  std::array<double, kMaxModules> wheel_rad{};  ///< cumulative encoder angles
  std::array<double, kMaxModules> steer_rad{};  ///< measured steering angles (swpc)
  double gyro_wz_radps = 0.0;                   ///< meaningful only when has_gyro
  /// A gyro sample belongs to this row; false: the gyro_wz cell is empty (and gyro_wz_radps 0).
  bool has_gyro = true;
  /// The command columns hold a command; false: all three are empty (and cmd is zero).
  bool has_cmd = true;
  bool has_truth = false;  ///< a motion-capture sample belongs to this row
  Pose2 truth;             ///< world frame; meaningful only when has_truth
  /// The pose estimate at t_s, world frame, and the active fault (swivel::FaultCode, 0:
  /// none): written and read only with RunLogHeader::estimate_columns.
  Pose2 estimate;
  std::uint16_t fault_code = 0;
};

/// A whole log in memory.
struct RunLog {
  std::string source;  ///< file name used in messages
  RunLogHeader header;
  std::vector<RunLogSample> samples;
};

/// The header row's column names for `header`, in order (the estimate columns included when
/// header.estimate_columns).
std::vector<std::string> run_log_columns(const RunLogHeader& header);

/// The header a run of `model` gets (name, drivetrain, module count).
RunLogHeader run_log_header(const RobotModel& model);

/// Streams a run log: comment lines and header row at construction, one row per write().
/// Numbers are written in the shortest form that reads back to the same double.
class RunLogWriter {
 public:
  /// Creates (truncates) `path`.
  /// @throws RunLogError when the file cannot be opened or the header is invalid
  ///         (module count outside 2..kMaxModules, or not 2 for a differential robot).
  RunLogWriter(const std::string& path, RunLogHeader header);
  /// Writes to a stream the caller keeps alive. @throws RunLogError as above.
  RunLogWriter(std::ostream& out, RunLogHeader header);

  ~RunLogWriter() = default;
  RunLogWriter(const RunLogWriter&) = delete;
  RunLogWriter& operator=(const RunLogWriter&) = delete;
  // out_ may point into file_: a moved writer would write to the old one's stream.
  RunLogWriter(RunLogWriter&&) = delete;
  RunLogWriter& operator=(RunLogWriter&&) = delete;

  /// Appends one row. @throws RunLogError when the stream fails.
  void write(const RunLogSample& sample);
  /// Flushes buffered rows. @throws RunLogError when the stream fails.
  void flush();

  [[nodiscard]] const RunLogHeader& header() const { return header_; }

 private:
  void start();

  RunLogHeader header_;
  std::ofstream file_;
  std::ostream* out_ = nullptr;
  std::string path_;
  std::string line_;  // reused row buffer
};

/// Reads a run log. Unknown `#` comment lines are ignored; blank lines are skipped.
/// @throws RunLogError naming the file and line: missing `# swivel-run` or `# drivetrain`
///   line, unsupported version, missing or wrong header row, a row with the wrong number
///   of columns, a cell that is not a finite number, partly empty truth or command columns, a
///   fault cell that is not an integer in [0, 65535], or time going backwards.
RunLog read_run_log(const std::string& path);

/// Parses a run log from a stream; `source_name` is used in messages.
/// @throws RunLogError as read_run_log.
RunLog parse_run_log(std::istream& in, const std::string& source_name);

/// `angle_rad` moved by whole turns to within half a turn of `reference_rad`: the next value of
/// an unwrapped angle whose reading wraps (a sensor never turns half a turn between two rows).
/// Real-time safe.
double unwrap_near(double angle_rad, double reference_rad) noexcept;

/// Makes every module's steering column of an swpc log continuous in place: the first row is
/// kept and each later angle moved by whole turns to within half a turn of the row before
/// (unwrap_near), so a log wrapped to (-pi, pi] reads the same as its unwrapped twin. Does
/// nothing to a differential log.
void unwrap_steering(RunLog& log);

}  // namespace swivel
