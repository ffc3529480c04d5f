// SPDX-License-Identifier: Apache-2.0
#pragma once
// Sensors from ROS 2 drivers over DDS (README "External sensors"): the gyro from a
// sensor_msgs/Imu topic, rotated from the IMU's mounting into the body frame, and motion
// capture from a geometry_msgs/PoseStamped topic. Each sample is stamped on reception with
// CLOCK_MONOTONIC, the loop's clock, and handed to a callback that pushes it into the loop's
// lock-free rings; the loop watches each source for staleness (rt::SensorWatch).
//
// The conversions are plain functions (real-time safe). SensorInputs owns the readers; the
// bridge creates it on its participant and takes its samples on its subscriber thread.

#include <dds/dds.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>

#include "swivel/dds/options.hpp"
#include "swivel/rt/external_sensors.hpp"
#include "swivel/types.hpp"

namespace swivel::dds {

/// An IMU's mounting: the rotation R from the IMU frame to the body frame,
/// R = Rz(yaw) Ry(pitch) Rx(roll) (fixed-axis roll, pitch, yaw, as a URDF joint's rpy).
class ImuMounting {
 public:
  /// The identity: the IMU frame is the body frame.
  ImuMounting() noexcept = default;
  [[nodiscard]] static ImuMounting from_rpy(double roll_rad, double pitch_rad,
                                            double yaw_rad) noexcept;

  /// The body-frame yaw rate: the z component of R * (wx, wy, wz) (IMU frame), rad/s.
  [[nodiscard]] double yaw_rate_radps(double wx_radps, double wy_radps,
                                      double wz_radps) const noexcept;

  /// The third row of R: how each IMU axis contributes to the body z axis.
  [[nodiscard]] const std::array<double, 3>& body_z_row() const noexcept { return z_row_; }

 private:
  std::array<double, 3> z_row_{0.0, 0.0, 1.0};
};

/// A motion-capture sample from a pose (position in m, orientation a quaternion x, y, z, w),
/// stamped `received_s`: the heading is the rotation's yaw (quaternion_to_yaw()). False,
/// `out` untouched, when the position is not finite or the quaternion is not a rotation.
bool pose_to_motion_capture(double x_m, double y_m, double qx, double qy, double qz, double qw,
                            double received_s, MotionCaptureSample& out) noexcept;

/// The loop's staleness watches for the sources `ros2` configures, with causes that name
/// each topic (truncated to FaultDetail).
[[nodiscard]] rt::ExternalSensorOptions loop_sensor_options(const Ros2Options& ros2);

/// Where accepted samples go (the subscriber thread calls them). Return false when a sample
/// could not be queued (counted as dropped).
struct SensorCallbacks {
  std::function<bool(const rt::GyroSample&)> on_gyro{};
  std::function<bool(const MotionCaptureSample&)> on_motion_capture{};
};

/// Counters of the sensor inputs.
struct SensorCounters {
  std::uint64_t imu_received = 0;          ///< accepted by on_gyro
  std::uint64_t imu_rejected = 0;          ///< non-finite angular velocity
  std::uint64_t mocap_poses_received = 0;  ///< accepted by on_motion_capture
  std::uint64_t mocap_poses_rejected = 0;  ///< not a rotation, or a non-finite position
  std::uint64_t dropped = 0;               ///< refused by a callback (ring full) or no callback
};

/// The readers of the configured ROS 2 sensor topics. Best effort, so that both best-effort
/// (the sensor-data profile of most drivers) and reliable writers match.
class SensorInputs {
 public:
  /// Creates a reader per configured topic on `participant`; none when nothing is
  /// configured. @throws DdsError
  SensorInputs(dds_entity_t participant, Ros2Options ros2, SensorCallbacks callbacks);
  /// The readers go with the participant (deleted with it).
  ~SensorInputs() = default;
  SensorInputs(const SensorInputs&) = delete;
  SensorInputs& operator=(const SensorInputs&) = delete;
  SensorInputs(SensorInputs&&) = delete;
  SensorInputs& operator=(SensorInputs&&) = delete;

  /// The readers (0 when not configured), for the subscriber's waitset.
  [[nodiscard]] std::array<dds_entity_t, 2> readers() const noexcept {
    return {imu_reader_, pose_reader_};
  }

  /// The subscriber thread only. Takes every available sample. @throws DdsError
  void take();

  [[nodiscard]] SensorCounters counters() const noexcept;

 private:
  void take_imu();
  void take_poses();

  Ros2Options ros2_;
  ImuMounting mounting_;
  SensorCallbacks callbacks_;
  dds_entity_t imu_reader_ = 0;
  dds_entity_t pose_reader_ = 0;
  std::atomic<std::uint64_t> imu_received_{0};
  std::atomic<std::uint64_t> imu_rejected_{0};
  std::atomic<std::uint64_t> poses_received_{0};
  std::atomic<std::uint64_t> poses_rejected_{0};
  std::atomic<std::uint64_t> dropped_{0};
};

}  // namespace swivel::dds
