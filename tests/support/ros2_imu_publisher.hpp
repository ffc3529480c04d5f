// SPDX-License-Identifier: Apache-2.0
#pragma once
// A ROS 2 IMU driver as the tests play it: sensor_msgs/Imu (the ROS 2 type, plain CDR) on
// its own DDS participant, best effort (the sensor-data profile) or reliable.

#include <dds/dds.h>
#include <gtest/gtest.h>

#include <chrono>
#include <functional>
#include <string>
#include <thread>

#include "dds_test_util.hpp"
#include "ros2_interfaces.h"
#include "swivel/dds/topics.hpp"

namespace swivel::dds::test {

class ImuPublisher {
 public:
  ImuPublisher(const Participant& client, const std::string& topic, bool reliable) {
    const dds_entity_t t =
        create_topic(client.handle(), &sensor_msgs_msg_dds__Imu__desc, topic.c_str());
    const QosPtr qos = reliable ? default_qos(10) : best_effort_qos(10);
    writer_ = dds_create_writer(client.handle(), t, qos.get(), nullptr);
  }
  [[nodiscard]] bool matched() const { return publication_matched(writer_); }
  void write(double wx, double wy, double wz) const {
    std::string frame = "imu_link";
    sensor_msgs_msg_dds__Imu_ m{};
    m.header.frame_id = frame.data();
    m.orientation.w = 1.0;
    m.orientation_covariance[0] = -1.0;  // no orientation, as many gyro-only drivers send
    m.angular_velocity = {wx, wy, wz};
    m.linear_acceleration = {0.0, 0.0, 9.81};
    ASSERT_EQ(dds_write(writer_, &m), DDS_RETCODE_OK);
  }
  /// Publishes at up to 200 Hz until `done` or the timeout.
  bool stream_until(double wx, double wy, double wz, const std::function<bool()>& done,
                    std::chrono::milliseconds timeout = std::chrono::seconds(10)) const {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      write(wx, wy, wz);
      if (done()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return false;
  }

 private:
  dds_entity_t writer_ = 0;
};

}  // namespace swivel::dds::test
