// SPDX-License-Identifier: Apache-2.0
#pragma once
// Requests to one daemon and their answers: a Request (reload, clear, calibrate) or a
// SetPose goes out with a fresh request id, and the Reply carrying that id comes back.

#include <chrono>
#include <string>

#include "client.hpp"
#include "swivel/types.hpp"

namespace swivel::ctl {

/// What the daemon answered.
struct Answer {
  bool ok = false;
  std::string text;
};

/// A pose for set-pose: world frame; sigmas only when `has_sigma`.
struct PoseRequest {
  Pose2 pose;
  bool has_sigma = false;
  double sigma_x_m = 0.0;
  double sigma_y_m = 0.0;
  double sigma_yaw_rad = 0.0;
};

/// Sends Request `verb` (`argument`) to `robot` and waits up to `timeout` for its Reply.
/// @throws std::runtime_error naming what did not answer (no request reader, no reply).
Answer send_request(Client& client, const std::string& robot, const std::string& verb,
                    const std::string& argument, std::chrono::duration<double> timeout);

/// Sends SetPose to `robot` and waits up to `timeout` for its Reply. @throws as send_request.
Answer send_set_pose(Client& client, const std::string& robot, const PoseRequest& pose,
                     std::chrono::duration<double> timeout);

}  // namespace swivel::ctl
