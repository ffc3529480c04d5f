// SPDX-License-Identifier: Apache-2.0
#include "swivel/dds/cmd_vel_type_check.hpp"

#include <spdlog/spdlog.h>

#include <array>
#include <utility>

#include "swivel/dds/topics.hpp"
#include "take_all.hpp"

namespace swivel::dds {

namespace {

constexpr const char* kTwist = "geometry_msgs::msg::dds_::Twist_";
constexpr const char* kTwistStamped = "geometry_msgs::msg::dds_::TwistStamped_";

// "Twist" or "TwistStamped" for the two cmd_vel types, else the full ROS 2 name.
std::string short_name(const std::string& dds_type_name) {
  if (dds_type_name == kTwist) return "Twist";
  if (dds_type_name == kTwistStamped) return "TwistStamped";
  return CmdVelTypeCheck::ros_type_name(dds_type_name);
}

}  // namespace

std::string CmdVelTypeCheck::ros_type_name(const std::string& dds_type_name) {
  // <pkg>::msg::dds_::<Name>_ (rmw_cyclonedds' mangling) back to <pkg>/msg/<Name>.
  const std::string::size_type dds = dds_type_name.find("::dds_::");
  if (dds == std::string::npos || dds_type_name.empty() || dds_type_name.back() != '_') {
    return dds_type_name;
  }
  std::string name = dds_type_name.substr(0, dds) +
                     "::" + dds_type_name.substr(dds + 8, dds_type_name.size() - dds - 9);
  for (std::string::size_type at = name.find("::"); at != std::string::npos;
       at = name.find("::", at + 1)) {
    name.replace(at, 2, "/");
  }
  return name;
}

CmdVelTypeCheck::CmdVelTypeCheck(dds_entity_t participant, std::string dds_topic, bool stamped)
    : dds_topic_(std::move(dds_topic)),
      ros_topic_("/" + dds_topic_.substr(3)),
      stamped_(stamped),
      reader_(
          check(dds_create_reader(participant, DDS_BUILTIN_TOPIC_DCPSPUBLICATION, nullptr, nullptr),
                "dds_create_reader(DCPSPublication)")) {}

void CmdVelTypeCheck::take() {
  const std::string expected = stamped_ ? kTwistStamped : kTwist;
  std::array<void*, kTakeBatch> samples{};
  std::array<dds_sample_info_t, kTakeBatch> infos{};
  for (;;) {
    samples[0] = nullptr;  // loaned
    const dds_return_t n = dds_take(reader_, samples.data(), infos.data(), kTakeBatch, kTakeBatch);
    if (n <= 0) return;
    const std::scoped_lock lock(mutex_);
    for (dds_return_t i = 0; i < n; ++i) {
      const dds_sample_info_t& info = infos[i];
      if (info.instance_state != DDS_IST_ALIVE) {
        foreign_.erase(info.instance_handle);  // the publisher left
        continue;
      }
      if (!info.valid_data) continue;
      const auto& endpoint = *static_cast<const dds_builtintopic_endpoint_t*>(samples[i]);
      if (endpoint.topic_name == nullptr || endpoint.type_name == nullptr ||
          dds_topic_ != endpoint.topic_name || expected == endpoint.type_name) {
        continue;
      }
      const std::string type = endpoint.type_name;
      foreign_[info.instance_handle] = type;
      if (logged_.insert(type).second) {
        spdlog::warn(
            "dds: a {} publisher on {}: its commands do not reach swiveld, which reads {} "
            "(dds.ros2.cmd_vel_stamped: {}); the diagnostics say so while it publishes",
            short_name(type), ros_topic_, ros_type_name(expected), stamped_);
      }
    }
    dds_return_loan(reader_, samples.data(), n);
    if (n < static_cast<dds_return_t>(kTakeBatch)) return;
  }
}

std::string CmdVelTypeCheck::warning() const {
  std::map<std::string, int> count_by_type;
  {
    const std::scoped_lock lock(mutex_);
    for (const auto& entry : foreign_) ++count_by_type[entry.second];
  }
  std::string text;
  for (const auto& [type, count] : count_by_type) {
    if (!text.empty()) text += "; ";
    text += (count == 1 ? std::string("a ") : std::to_string(count) + " ") + short_name(type) +
            (count == 1 ? " publisher on " : " publishers on ") + ros_topic_ + "; ";
    if (type == kTwist || type == kTwistStamped) {
      text += std::string("set dds.ros2.cmd_vel_stamped: ") + (stamped_ ? "false" : "true");
    } else {
      text += "swiveld reads " + ros_type_name(stamped_ ? kTwistStamped : kTwist);
    }
  }
  return text;
}

}  // namespace swivel::dds
