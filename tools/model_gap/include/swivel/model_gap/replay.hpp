#pragma once
// Replaying a run with a robot model: every measured channel next to its prediction.
//  - sensor-to-pose: dead reckoning from the logged encoders and gyro through the
//    drivetrain's kinematics library, compared with motion capture;
//  - command-to-sensor and command-to-pose: the logged commands re-simulated through the
//    simulator (noise off), compared with encoders, steering, gyro and motion capture.

#include <memory>
#include <string>
#include <vector>

#include "swivel/model_gap/channels.hpp"
#include "swivel/model_gap/fit.hpp"
#include "swivel/model_gap/run_data.hpp"
#include "swivel/robot_model.hpp"

namespace swivel::model_gap {

class Replay {
 public:
  /// @throws std::invalid_argument when the run's drivetrain or module count differs from
  /// the model's, or the run has fewer than 10 samples.
  Replay(const RobotModel& nominal, const RunData& run);
  ~Replay();
  Replay(const Replay&) = delete;
  Replay& operator=(const Replay&) = delete;

  /// The measured channels (same layout as predict() fills).
  [[nodiscard]] const ChannelSet& measured() const;

  /// Predictions of every channel by `model`: the nominal parameters plus model.effects,
  /// for samples [0, end) (later samples of `out` are left as they were). Reuses `out`'s
  /// storage. Not thread-safe (keeps scratch state).
  void predict(const RobotModel& model, ChannelSet& out,
               std::size_t end = static_cast<std::size_t>(-1)) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// A named effect of the simulator's library with the parameters the workflow fits.
struct CandidateEffect {
  std::string effect;             ///< name in the model's `effects:` map
  std::vector<ParamSpec> params;  ///< name = the effect's parameter key; initial = start value
  std::vector<double> identity;   ///< per parameter: the value that changes nothing
};

/// The simulator's effects that apply to the model's drivetrain, with fit scales.
std::vector<CandidateEffect> candidate_library(const RobotModel& nominal);

}  // namespace swivel::model_gap
