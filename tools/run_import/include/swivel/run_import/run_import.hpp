// SPDX-License-Identifier: Apache-2.0
#pragma once
// Another lab's CSV into a Swivel run log (swivel/run_log.hpp), driven by a mapping file
// instead of code: which input column is time (or a fixed row period), each wheel (counts
// per row, cumulative counts or cumulative angle, with real-valued counts per revolution and
// a sign), each steering angle, the motion-capture pose, and the optional gyro and command
// columns, with their units and signs. The format is documented in tools/lab/IMPORT.md;
// `swivel-lab import` is its command line. Not real-time safe (allocates, does I/O).

#include <cstddef>
#include <iosfwd>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "swivel/robot_model.hpp"
#include "swivel/run_log.hpp"

namespace swivel::run_import {

/// A malformed input file. The message starts with "file:line: " and names the column, e.g.
/// "run.csv:57: column odoR (index 4): expected a finite number, got 'x'". Errors in the
/// mapping file itself are swivel::ConfigError naming the map file, line and key.
class ImportError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One input column: by header name (`column:`) or 0-based position (`index:`).
struct ColumnRef {
  std::string name;       ///< header name; empty when given by index
  std::size_t index = 0;  ///< resolved position (given, or found in the header row)
  std::string key;        ///< the map key it came from, e.g. "wheels.left", for messages
};

/// A column whose value in SI units is raw * scale (unit conversion and sign folded in).
struct ScaledColumn {
  ColumnRef column;
  double scale = 1.0;
};

enum class WheelMode {
  kCountsPerRow,      ///< encoder counts since the previous row (increments)
  kCumulativeCounts,  ///< encoder count since some origin
  kCumulativeAngle,   ///< wheel angle since some origin (rad or deg)
};

struct WheelColumn {
  ColumnRef column;
  WheelMode mode = WheelMode::kCountsPerRow;
  /// Radians per raw unit, sign included: sign * 2 pi / counts_per_rev for the count modes,
  /// sign * (1 or pi/180) for an angle.
  double rad_per_unit = 1.0;
};

/// A parsed mapping file.
struct ImportMap {
  std::string source;  ///< the map file, for messages
  std::string robot;
  DrivetrainKind drivetrain = DrivetrainKind::kDifferential;
  std::size_t module_count = 2;
  bool header_row = false;
  char delimiter = ',';
  std::string comment_prefix;  ///< lines starting with it are skipped; empty: none

  // Time: a column (scaled to seconds), optionally rescaled from a nominal to a real row
  // period, or no column and a fixed row period.
  std::optional<ScaledColumn> time;
  std::optional<double> nominal_period_s;  ///< with real_period_s: the time column's step
  std::optional<double> real_period_s;     ///< the row period actually achieved, or the fixed one

  /// Differential: left then right. swpc: module 1..N.
  std::vector<WheelColumn> wheels;
  std::vector<ScaledColumn> steering;   ///< swpc: module 1..N, to radians
  std::optional<ScaledColumn> truth_x;  ///< to metres; the three truth columns come together
  std::optional<ScaledColumn> truth_y;
  std::optional<ScaledColumn> truth_yaw;  ///< to radians, counter-clockwise positive
  std::optional<ScaledColumn> gyro;       ///< to rad/s
  std::optional<ScaledColumn> cmd_vx;     ///< to m/s; cmd_vx and cmd_wz come together
  std::optional<ScaledColumn> cmd_vy;     ///< optional even with commands (0 when absent)
  std::optional<ScaledColumn> cmd_wz;     ///< to rad/s
};

/// Parses a mapping file's text. @throws ConfigError naming `source_name`, the line and the
/// key: unknown keys, missing required keys, wrong units, signs other than +-1, counts per
/// revolution that are not finite and > 0, a column given both or neither by name and index,
/// a column name without `header_row: true`, sections that do not fit the drivetrain.
ImportMap parse_import_map(const std::string& yaml_text, const std::string& source_name);

/// Reads and parses a mapping file. @throws ConfigError as parse_import_map, or when the file
/// cannot be read.
ImportMap load_import_map(const std::string& path);

/// What an import found, for the command's summary.
struct ImportSummary {
  std::size_t rows = 0;
  std::size_t truth_rows = 0;  ///< rows with a motion-capture pose
  std::size_t gyro_rows = 0;
  std::size_t command_rows = 0;
  std::size_t gaps = 0;  ///< time-column steps of two or more nominal periods (missing rows)
  double first_t_s = 0.0;
  double last_t_s = 0.0;
};

/// Converts one input file. `input_name` is used in messages and the `# imported from:` line.
/// @throws ImportError naming the input file, line and column: a row with too few columns, a
///   required cell that is not a finite number, truth or command cells only partly present,
///   time going backwards, a header row without a mapped name, or (with nominal_period_s) a
///   time step that is not a whole number of nominal periods.
RunLog import_run(std::istream& in, const std::string& input_name, const ImportMap& map,
                  ImportSummary* summary = nullptr);

/// Reads `input_path`, converts it and writes the run log to `output_path`.
/// @throws ImportError for the input, RunLogError when the output cannot be written.
ImportSummary import_file(const ImportMap& map, const std::string& input_path,
                          const std::string& output_path);

/// @throws std::invalid_argument naming both files when the map's robot name, drivetrain or
///   module count differs from `model`'s (the run would not analyse against it).
void check_map_matches_model(const ImportMap& map, const RobotModel& model);

}  // namespace swivel::run_import
