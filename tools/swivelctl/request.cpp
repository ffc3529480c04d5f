// SPDX-License-Identifier: Apache-2.0
#include "request.hpp"

#include <random>
#include <stdexcept>
#include <thread>

#include "swivel.h"
#include "swivel/dds/topics.hpp"

namespace swivel::ctl {
namespace {

using Seconds = std::chrono::duration<double>;

// Unique among the requests of every client on the domain with overwhelming probability,
// and below 2^53 so that it prints exactly wherever it is shown as a double.
std::uint64_t fresh_request_id() {
  std::random_device device;
  std::uint64_t id = 0;
  while (id == 0) {
    id = ((static_cast<std::uint64_t>(device()) << 32) | device()) & ((1ULL << 53) - 1);
  }
  return id;
}

bool wait_for_reader_match(dds_entity_t reader, Seconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!interrupted() && std::chrono::steady_clock::now() < deadline) {
    dds_subscription_matched_status_t status{};
    if (dds_get_subscription_matched_status(reader, &status) == DDS_RETCODE_OK &&
        status.current_count > 0) {
      return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

// Writes `sample` once both directions are matched (replies are volatile: the reply reader
// must be matched before the request leaves), then waits for the Reply to `id`.
template <typename Sample>
Answer exchange(Client& client, const std::string& robot, const dds_topic_descriptor_t* desc,
                const char* topic, const Sample& sample, std::uint64_t id, Seconds timeout) {
  const dds_entity_t replies = client.reader(&swivel_msg_Reply_desc, dds::kReplyTopic);
  const dds_entity_t writer = client.writer(desc, topic);
  if (!Client::wait_for_match(writer, timeout) || !wait_for_reader_match(replies, timeout)) {
    if (interrupted()) throw std::runtime_error("interrupted");
    throw std::runtime_error("robot '" + robot + "' has no " + topic +
                             " reader or reply writer (matched none within " +
                             seconds_text(timeout) + ")");
  }
  dds::check(dds_write(writer, &sample), "dds_write(request)");
  dds_wait_for_acks(writer, DDS_SECS(1));

  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!interrupted()) {
    const auto left = deadline - std::chrono::steady_clock::now();
    if (left <= Seconds::zero()) break;
    if (!client.wait_for_data({replies}, std::min<Seconds>(left, Seconds(0.1)))) continue;
    Answer answer;
    bool found = false;
    Client::take(replies, [&](const void* p) {
      const auto& r = *static_cast<const swivel_msg_Reply*>(p);
      if (found || r.request_id != id || r.robot_id == nullptr || robot != r.robot_id) return;
      found = true;
      answer.ok = r.ok;
      answer.text = r.text != nullptr ? r.text : "";
    });
    if (found) return answer;
  }
  if (interrupted()) throw std::runtime_error("interrupted");
  throw std::runtime_error("robot '" + robot + "' received the request but sent no reply within " +
                           seconds_text(timeout));
}

}  // namespace

Answer send_request(Client& client, const std::string& robot, const std::string& verb,
                    const std::string& argument, std::chrono::duration<double> timeout) {
  swivel_msg_Request request{};
  // The C struct takes char*: mutable copies that outlive the exchange.
  std::string id = robot;
  std::string verb_text = verb;
  std::string argument_text = argument;
  request.robot_id = id.data();
  request.verb = verb_text.data();
  request.argument = argument_text.data();
  request.request_id = fresh_request_id();
  return exchange(client, robot, &swivel_msg_Request_desc, dds::kRequestTopic, request,
                  request.request_id, timeout);
}

Answer send_set_pose(Client& client, const std::string& robot, const PoseRequest& pose,
                     std::chrono::duration<double> timeout) {
  swivel_msg_SetPose request{};
  std::string id = robot;
  request.robot_id = id.data();
  request.request_id = fresh_request_id();
  request.x_m = pose.pose.x_m;
  request.y_m = pose.pose.y_m;
  request.yaw_rad = pose.pose.yaw_rad;
  request.has_covariance = pose.has_sigma;
  request.sigma_x_m = pose.sigma_x_m;
  request.sigma_y_m = pose.sigma_y_m;
  request.sigma_yaw_rad = pose.sigma_yaw_rad;
  return exchange(client, robot, &swivel_msg_SetPose_desc, dds::kSetPoseTopic, request,
                  request.request_id, timeout);
}

}  // namespace swivel::ctl
