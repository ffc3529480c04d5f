// SPDX-License-Identifier: Apache-2.0
// The conversions behind the ROS 2 sensor topics, without DDS: the IMU mounting's yaw rate
// against a full rotation built with Eigen, the motion-capture pose from a quaternion (and
// its refusal of non-rotations), the loop's fault causes naming each topic, and the
// dds.ros2.imu / dds.ros2.mocap_pose keys with their errors.

#include "swivel/dds/sensor_inputs.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "swivel/config/config_error.hpp"
#include "swivel/dds/bridge.hpp"
#include "swivel/dds/options.hpp"

namespace swivel::dds {
namespace {

constexpr double kPi = std::numbers::pi;

// The body-frame rate by the full rotation R = Rz(yaw) Ry(pitch) Rx(roll).
Eigen::Vector3d rotated(double roll, double pitch, double yaw, const Eigen::Vector3d& w) {
  const Eigen::Matrix3d r = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  return r * w;
}

TEST(ImuMounting, IdentityAndYawOnlyMountingsKeepTheZRate) {
  EXPECT_EQ(ImuMounting().yaw_rate_radps(0.3, -0.2, 0.7), 0.7);
  EXPECT_NEAR(ImuMounting::from_rpy(0.0, 0.0, 1.2).yaw_rate_radps(0.3, -0.2, 0.7), 0.7, 1e-15);
}

TEST(ImuMounting, UpsideDownAndPitchedMountings) {
  // Upside down (rolled by pi): the IMU's z points down, the rate changes sign.
  EXPECT_NEAR(ImuMounting::from_rpy(kPi, 0.0, 0.0).yaw_rate_radps(0.0, 0.0, 0.5), -0.5, 1e-15);
  // Pitched by +90 degrees: the IMU's x axis points down (R e_x = -e_z).
  EXPECT_NEAR(ImuMounting::from_rpy(0.0, kPi / 2, 0.0).yaw_rate_radps(0.4, 0.0, 0.0), -0.4, 1e-15);
  // Rolled by +90 degrees: the IMU's y axis points up (R e_y = e_z).
  EXPECT_NEAR(ImuMounting::from_rpy(kPi / 2, 0.0, 0.0).yaw_rate_radps(0.0, 0.6, 0.0), 0.6, 1e-15);
}

TEST(ImuMounting, MatchesTheFullRotationForArbitraryMountings) {
  const std::array<double, 8> angles{-2.9, -1.3, -0.4, 0.0, 0.25, 1.1, 2.2, 3.1};
  const Eigen::Vector3d w(0.31, -0.77, 1.9);
  for (const double roll : angles) {
    for (const double pitch : angles) {
      for (const double yaw : angles) {
        const double expected = rotated(roll, pitch, yaw, w).z();
        EXPECT_NEAR(ImuMounting::from_rpy(roll, pitch, yaw).yaw_rate_radps(w.x(), w.y(), w.z()),
                    expected, 1e-12)
            << roll << " " << pitch << " " << yaw;
      }
    }
  }
}

TEST(PoseToMotionCapture, TakesTheYawOfTheQuaternionAndTheReceptionStamp) {
  MotionCaptureSample m;
  double qx = 0.0;
  double qy = 0.0;
  double qz = 0.0;
  double qw = 0.0;
  yaw_to_quaternion(0.7, qx, qy, qz, qw);
  ASSERT_TRUE(pose_to_motion_capture(1.5, -2.0, qx, qy, qz, qw, 42.5, m));
  EXPECT_TRUE(m.valid);
  EXPECT_EQ(m.stamp_s, 42.5);
  EXPECT_EQ(m.pose.x_m, 1.5);
  EXPECT_EQ(m.pose.y_m, -2.0);
  EXPECT_NEAR(m.pose.yaw_rad, 0.7, 1e-12);

  // A body tilted on a ramp: the heading is still the rotation's yaw.
  const Eigen::Quaterniond tilted(Eigen::AngleAxisd(-2.5, Eigen::Vector3d::UnitZ()) *
                                  Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY()) *
                                  Eigen::AngleAxisd(-0.05, Eigen::Vector3d::UnitX()));
  ASSERT_TRUE(
      pose_to_motion_capture(0.0, 0.0, tilted.x(), tilted.y(), tilted.z(), tilted.w(), 1.0, m));
  EXPECT_NEAR(m.pose.yaw_rad, -2.5, 1e-12);
}

TEST(PoseToMotionCapture, RefusesWhatIsNotARotationOrAPosition) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  MotionCaptureSample m;
  m.pose.x_m = 9.0;
  EXPECT_FALSE(pose_to_motion_capture(1.0, 2.0, 0.0, 0.0, 0.0, 0.0, 1.0, m));  // all zero
  EXPECT_FALSE(pose_to_motion_capture(1.0, 2.0, 0.0, 0.0, 0.0, 2.0, 1.0, m));  // norm 2
  EXPECT_FALSE(pose_to_motion_capture(1.0, 2.0, 0.0, 0.0, nan, 1.0, 1.0, m));
  EXPECT_FALSE(pose_to_motion_capture(nan, 2.0, 0.0, 0.0, 0.0, 1.0, 1.0, m));
  EXPECT_FALSE(pose_to_motion_capture(1.0, std::numeric_limits<double>::infinity(), 0.0, 0.0, 0.0,
                                      1.0, 1.0, m));
  EXPECT_FALSE(m.valid);
  EXPECT_EQ(m.pose.x_m, 9.0) << "a refused pose leaves the sample as it was";
}

DdsOptions parse(const std::string& yaml) {
  return parse_dds_options(YAML::Load(yaml), "swiveld.yaml", "/etc/swivel");
}

std::string error_of(const std::string& yaml) {
  try {
    parse(yaml);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "<no error>";
}

TEST(SensorOptions, ImuDefaultsAndNamespacedTopics) {
  const DdsOptions plain = parse("{ros2: {enabled: true, imu: }}");
  EXPECT_TRUE(plain.ros2.imu.enabled);
  EXPECT_EQ(plain.ros2.imu.dds_topic, "rt/imu");
  EXPECT_DOUBLE_EQ(plain.ros2.imu.rate_hz, 100.0);
  EXPECT_DOUBLE_EQ(plain.ros2.imu.max_age_s, 0.05);  // five expected periods
  EXPECT_DOUBLE_EQ(plain.ros2.imu.startup_grace_s, 2.0);
  EXPECT_EQ(plain.ros2.imu.rotation_rpy_rad, (std::array<double, 3>{0.0, 0.0, 0.0}));
  EXPECT_FALSE(plain.ros2.mocap_pose.enabled);

  const DdsOptions ns = parse(
      "{ros2: {enabled: true, namespace: robot1, imu: {topic: imu/data, rate_hz: 400,"
      " rotation_rpy_rad: [3.14159, 0, 0.5], startup_grace_s: 5},"
      " mocap_pose: {topic: /vrpn_mocap/robot1/pose, max_age_s: 0.2}}}");
  EXPECT_EQ(ns.ros2.imu.dds_topic, "rt/robot1/imu/data");
  EXPECT_DOUBLE_EQ(ns.ros2.imu.max_age_s, 5.0 / 400.0);
  EXPECT_DOUBLE_EQ(ns.ros2.imu.startup_grace_s, 5.0);
  EXPECT_EQ(ns.ros2.imu.rotation_rpy_rad, (std::array<double, 3>{3.14159, 0.0, 0.5}));
  EXPECT_TRUE(ns.ros2.mocap_pose.enabled);
  EXPECT_EQ(ns.ros2.mocap_pose.topic, "/vrpn_mocap/robot1/pose");
  EXPECT_EQ(ns.ros2.mocap_pose.dds_topic, "rt/vrpn_mocap/robot1/pose");  // absolute
  EXPECT_DOUBLE_EQ(ns.ros2.mocap_pose.max_age_s, 0.2);
}

TEST(SensorOptions, BadValuesAreErrorsNamingTheKey) {
  EXPECT_EQ(error_of("{ros2: {imu: {topic: imu}}}"),
            "swiveld.yaml:1:9: dds.ros2.imu: a ROS 2 sensor topic needs dds.ros2.enabled: true");
  EXPECT_EQ(error_of("{ros2: {enabled: true, imu: {rotation_rpy_rad: [0, 1]}}}"),
            "swiveld.yaml:1:30: dds.ros2.imu.rotation_rpy_rad: expected three finite angles "
            "[roll, pitch, yaw] in rad, got 2 entries");
  EXPECT_EQ(error_of("{ros2: {enabled: true, imu: {rotation_rpy_rad: [0, x, 1]}}}"),
            "swiveld.yaml:1:30: dds.ros2.imu.rotation_rpy_rad: expected three finite angles "
            "[roll, pitch, yaw] in rad, got 'x' at index 1");
  EXPECT_EQ(error_of("{ros2: {enabled: true, imu: {rotation_rpy_rad: [0, .nan, 1]}}}"),
            "swiveld.yaml:1:30: dds.ros2.imu.rotation_rpy_rad: expected three finite angles "
            "[roll, pitch, yaw] in rad, got a non-finite value at index 1");
  EXPECT_EQ(error_of("{ros2: {enabled: true, imu: {topic: 'imu data'}}}"),
            "swiveld.yaml:1:30: dds.ros2.imu.topic: expected a ROS 2 topic name (letters, "
            "digits, '_', '/'; '/' first for an absolute one), got 'imu data'");
  EXPECT_EQ(error_of("{ros2: {enabled: true, imu: {max_age_s: 0}}}"),
            "swiveld.yaml:1:30: dds.ros2.imu.max_age_s: expected a number in [0.001, 60], got 0");
  EXPECT_EQ(error_of("{ros2: {enabled: true, imu: {max_age: 0.1}}}"),
            "swiveld.yaml:1:30: dds.ros2.imu.max_age: unknown key (known: topic, rate_hz, "
            "max_age_s, startup_grace_s, rotation_rpy_rad)");
  EXPECT_NE(error_of("{ros2: {enabled: true, mocap_pose: {max_age_s: 0.1}}}")
                .find("dds.ros2.mocap_pose: missing required key 'topic'"),
            std::string::npos);
  EXPECT_EQ(error_of("{ros2: {enabled: true, imu: {topic: /pose}, mocap_pose: {topic: /pose}}}"),
            "swiveld.yaml:1:45: dds.ros2.mocap_pose: topic 'rt/pose' is the IMU's as well: give "
            "each sensor its own topic");
}

TEST(SensorOptions, LoopCausesNameTheTopics) {
  const DdsOptions options = parse(
      "{ros2: {enabled: true, imu: {max_age_s: 0.05, startup_grace_s: 3},"
      " mocap_pose: {topic: mocap/pose}}}");
  const rt::ExternalSensorOptions loop = loop_sensor_options(options.ros2);
  EXPECT_TRUE(loop.gyro.enabled);
  EXPECT_DOUBLE_EQ(loop.gyro.max_age_s, 0.05);
  EXPECT_DOUBLE_EQ(loop.gyro.startup_grace_s, 3.0);
  EXPECT_STREQ(loop.gyro.stale_detail.data(), "rt/imu: no IMU sample for over 0.05 s");
  EXPECT_STREQ(loop.gyro.silent_detail.data(), "rt/imu: no IMU sample within 3 s of start");
  EXPECT_TRUE(loop.motion_capture.enabled);
  EXPECT_STREQ(loop.motion_capture.stale_detail.data(),
               "rt/mocap/pose: no pose sample for over 0.05 s");
  EXPECT_FALSE(loop_sensor_options(parse("{}").ros2).gyro.enabled);

  // A long topic is cut at the end of the cause, never in the topic's first 63 characters.
  const std::string long_name(70, 'a');
  const DdsOptions long_topic = parse("{ros2: {enabled: true, imu: {topic: /" + long_name + "}}}");
  const std::string cause = loop_sensor_options(long_topic.ros2).gyro.stale_detail.data();
  EXPECT_EQ(cause.size(), 63U);
  EXPECT_EQ(cause, ("rt/" + long_name).substr(0, 63));
}

}  // namespace
}  // namespace swivel::dds
