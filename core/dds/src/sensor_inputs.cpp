// SPDX-License-Identifier: Apache-2.0
#include "swivel/dds/sensor_inputs.hpp"

#include <spdlog/spdlog.h>

#include <cmath>
#include <string>
#include <utility>

#include "ros2_interfaces.h"
#include "swivel/clock.hpp"
#include "swivel/dds/bridge.hpp"
#include "swivel/dds/topics.hpp"
#include "swivel/rt/rt_log.hpp"
#include "take_all.hpp"

namespace swivel::dds {

ImuMounting ImuMounting::from_rpy(double roll_rad, double pitch_rad, double /*yaw_rad*/) noexcept {
  // Third row of Rz(yaw) Ry(pitch) Rx(roll); a yaw about the body z axis leaves it unchanged.
  ImuMounting m;
  const double cp = std::cos(pitch_rad);
  m.z_row_ = {-std::sin(pitch_rad), cp * std::sin(roll_rad), cp * std::cos(roll_rad)};
  return m;
}

double ImuMounting::yaw_rate_radps(double wx_radps, double wy_radps,
                                   double wz_radps) const noexcept {
  return z_row_[0] * wx_radps + z_row_[1] * wy_radps + z_row_[2] * wz_radps;
}

bool pose_to_motion_capture(double x_m, double y_m, double qx, double qy, double qz, double qw,
                            double received_s, MotionCaptureSample& out) noexcept {
  const double yaw_rad = quaternion_to_yaw(qx, qy, qz, qw);
  if (!std::isfinite(yaw_rad) || !std::isfinite(x_m) || !std::isfinite(y_m)) return false;
  out.valid = true;
  out.stamp_s = received_s;
  out.pose = {x_m, y_m, yaw_rad};
  return true;
}

namespace {

rt::SensorWatchOptions watch_options(const Ros2SensorTopic& source, const char* kind) {
  rt::SensorWatchOptions watch;
  watch.enabled = source.enabled;
  if (!source.enabled) return watch;
  watch.max_age_s = source.max_age_s;
  watch.startup_grace_s = source.startup_grace_s;
  // The topic first: a long name is truncated at its end, not at the topic.
  rt::copy_text(
      fmt::format("{}: no {} sample for over {:g} s", source.dds_topic, kind, source.max_age_s)
          .c_str(),
      watch.stale_detail);
  rt::copy_text(fmt::format("{}: no {} sample within {:g} s of start", source.dds_topic, kind,
                            source.startup_grace_s)
                    .c_str(),
                watch.silent_detail);
  return watch;
}

}  // namespace

rt::ExternalSensorOptions loop_sensor_options(const Ros2Options& ros2) {
  rt::ExternalSensorOptions options;
  options.gyro = watch_options(ros2.imu, "IMU");
  options.motion_capture = watch_options(ros2.mocap_pose, "pose");
  return options;
}

SensorInputs::SensorInputs(dds_entity_t participant, Ros2Options ros2, SensorCallbacks callbacks)
    : ros2_(std::move(ros2)), callbacks_(std::move(callbacks)) {
  const auto& rpy = ros2_.imu.rotation_rpy_rad;
  mounting_ = ImuMounting::from_rpy(rpy[0], rpy[1], rpy[2]);
  // Best effort matches best-effort and reliable writers alike; a sensor stream wants the
  // newest sample, not a retransmitted old one.
  const QosPtr qos = best_effort_qos(kTakeBatch);
  // Plain CDR (XCDR1) only, as ROS 2 sends it: Cyclone 0.10.2's XCDR2 normaliser reads past
  // the end of a short Imu_ body (fuzz_dds_samples), so a writer offering XCDR2 must not match.
  const dds_data_representation_id_t xcdr1[] = {DDS_DATA_REPRESENTATION_XCDR1};
  dds_qset_data_representation(qos.get(), 1, xcdr1);
  const auto reader = [&](const dds_topic_descriptor_t* desc, const std::string& name) {
    const dds_entity_t topic = create_topic(participant, desc, name.c_str());
    return check(dds_create_reader(participant, topic, qos.get(), nullptr),
                 ("dds_create_reader(" + name + ")").c_str());
  };
  if (ros2_.imu.enabled) imu_reader_ = reader(&sensor_msgs_msg_dds__Imu__desc, ros2_.imu.dds_topic);
  if (ros2_.mocap_pose.enabled) {
    pose_reader_ = reader(&geometry_msgs_msg_dds__PoseStamped__desc, ros2_.mocap_pose.dds_topic);
  }
}

void SensorInputs::take() {
  if (imu_reader_ != 0) take_imu();
  if (pose_reader_ != 0) take_poses();
}

void SensorInputs::take_imu() {
  take_all<sensor_msgs_msg_dds__Imu_>(imu_reader_, [this](const sensor_msgs_msg_dds__Imu_& m) {
    const auto& w = m.angular_velocity;
    rt::GyroSample sample;
    sample.received_s = monotonic_s();
    sample.wz_radps = mounting_.yaw_rate_radps(w.x, w.y, w.z);
    if (!std::isfinite(sample.wz_radps)) {
      if (imu_rejected_.fetch_add(1, std::memory_order_relaxed) == 0) {
        spdlog::warn(
            "dds: {}: IMU sample with a non-finite angular velocity ({}, {}, {}) "
            "dropped; further ones are counted",
            ros2_.imu.dds_topic, w.x, w.y, w.z);
      }
      return;
    }
    if (callbacks_.on_gyro && callbacks_.on_gyro(sample)) {
      imu_received_.fetch_add(1, std::memory_order_relaxed);
    } else {
      dropped_.fetch_add(1, std::memory_order_relaxed);
    }
  });
}

void SensorInputs::take_poses() {
  take_all<geometry_msgs_msg_dds__PoseStamped_>(
      pose_reader_, [this](const geometry_msgs_msg_dds__PoseStamped_& m) {
        const auto& p = m.pose.position;
        const auto& q = m.pose.orientation;
        MotionCaptureSample sample;
        if (!pose_to_motion_capture(p.x, p.y, q.x, q.y, q.z, q.w, monotonic_s(), sample)) {
          if (poses_rejected_.fetch_add(1, std::memory_order_relaxed) == 0) {
            spdlog::warn(
                "dds: {}: pose dropped: position ({}, {}) or orientation ({}, {}, {}, {}) "
                "is not a pose (a quaternion must have norm 1); further ones are counted",
                ros2_.mocap_pose.dds_topic, p.x, p.y, q.x, q.y, q.z, q.w);
          }
          return;
        }
        if (callbacks_.on_motion_capture && callbacks_.on_motion_capture(sample)) {
          poses_received_.fetch_add(1, std::memory_order_relaxed);
        } else {
          dropped_.fetch_add(1, std::memory_order_relaxed);
        }
      });
}

SensorCounters SensorInputs::counters() const noexcept {
  SensorCounters c;
  c.imu_received = imu_received_.load(std::memory_order_relaxed);
  c.imu_rejected = imu_rejected_.load(std::memory_order_relaxed);
  c.mocap_poses_received = poses_received_.load(std::memory_order_relaxed);
  c.mocap_poses_rejected = poses_rejected_.load(std::memory_order_relaxed);
  c.dropped = dropped_.load(std::memory_order_relaxed);
  return c;
}

}  // namespace swivel::dds
