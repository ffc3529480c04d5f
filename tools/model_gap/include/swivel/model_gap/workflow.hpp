// SPDX-License-Identifier: Apache-2.0
#pragma once
// The model-gap workflow (tools/lab/GAP.md), as two questions decided separately:
//   1. sensor to pose: dead reckoning from the measured encoders, steering and gyro against
//      motion capture (sensor_replay.hpp) - geometry and sensors;
//   2. command to motion: the logged commands replayed through the simulator against every
//      measured channel (command_replay.hpp) - actuators and the robot's own controller,
//      on the model with what question 1 named.
// Each question locates its gap window by window, fits its candidates (library.hpp),
// selects and gives its own verdict (question.hpp). The report shows both, and the model
// with every named effect added.

#include <string>
#include <vector>

#include "swivel/model_gap/locate.hpp"
#include "swivel/model_gap/question.hpp"
#include "swivel/model_gap/run_data.hpp"
#include "swivel/model_gap/sensor_replay.hpp"
#include "swivel/robot_model.hpp"
#include "swivel/types.hpp"

namespace swivel::model_gap {

struct GapOptions {
  double window_s = 1.0;  ///< length of the windows compared
  QuestionOptions question;
  /// Skip the command-to-motion question (runs without usable commands).
  bool sensor_only = false;
};

/// Pose error of one question's replay over the whole run, before and after.
struct PoseGap {
  Question question = Question::kSensorToPose;
  double rms_position_m_before = 0.0;
  double rms_position_m_after = 0.0;
  double final_position_m_before = 0.0;
  double final_position_m_after = 0.0;
  double rms_heading_rad_before = 0.0;
  double rms_heading_rad_after = 0.0;
  double final_heading_rad_before = 0.0;
  double final_heading_rad_after = 0.0;
};

struct GapResult {
  std::string run_source;
  RobotModel nominal;
  RobotModel augmented;          ///< nominal plus every named effect (and fitted limits)
  QuestionResult sensor;         ///< question 1
  QuestionResult command;        ///< question 2
  bool command_assessed = true;  ///< false with GapOptions::sensor_only or without commands
  /// The motion capture's nuisances as fitted with the sensor question's selection (never
  /// robot effects): the tracked body's offset and the clock offset.
  TruthNuisance truth;
  std::vector<std::string> truth_names;  ///< the ones fitted, QuestionResult::nuisance order
  /// What the run lacked and what the workflow left out for it (no gyro, no commands, ...).
  std::vector<std::string> notes;
  std::string summary;  ///< one line per question
  std::vector<PoseGap> pose_gaps;
  // Paths for the plots, one pose per row.
  std::vector<double> t_s;
  std::vector<Pose2> motion_capture;  ///< NaN where a row has none
  std::vector<Pose2> dead_reckoning_before;
  std::vector<Pose2> dead_reckoning_after;
  std::vector<Pose2> replay_before;
  std::vector<Pose2> replay_after;
  std::vector<double> window_start_s;  ///< per window, for the residual plots
  std::vector<PhaseSegment> segments;  ///< motion phases of the commands
  double command_delay_s = 0.0;        ///< the commands' timing, fitted with the selection
  double steering_yield_rad = 0.0;     ///< caster robots: the servos' yield, fitted with it
  GapOptions options;
  double wall_time_s = 0.0;

  /// Every named effect of both questions.
  [[nodiscard]] std::vector<FittedEffect> named() const;
};

/// The sensor-to-pose question's replay of `sensors` (built with `nominal`): its channels,
/// the nuisance it fits, the regressors of its noise model and misfit tests. `sensors` must
/// outlive the result.
QuestionReplay sensor_question_replay(const SensorReplay& sensors, const RobotModel& nominal);

/// Pose error of two paths (one pose per row, comparable with the run's motion capture)
/// against the motion capture.
PoseGap compare_paths(Question question, const RunData& run, const std::vector<Pose2>& before,
                      const std::vector<Pose2>& after);

/// The motion capture's fitted nuisances, one line each in words with value +- sigma
/// (e.g. "tracked body's yaw offset: 6.21 +- 0.05 mrad"), for the report and the console.
std::vector<std::string> truth_nuisance_lines(const GapResult& result);

/// Runs the workflow on a run with its nominal model.
/// @throws std::invalid_argument when the run does not fit the model (drivetrain, modules)
///         or has no motion capture.
GapResult analyse_gap(const RobotModel& nominal, const RunData& run,
                      const GapOptions& options = {});

/// Writes DIR/report.json, DIR/report.md, DIR/model_augmented.yaml and PNG plots (when
/// gnuplot is available; the report says so when it is not). Creates DIR.
/// @throws std::runtime_error when DIR or a file cannot be written.
void write_report(const GapResult& result, const std::string& dir);

}  // namespace swivel::model_gap
