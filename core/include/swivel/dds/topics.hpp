// SPDX-License-Identifier: Apache-2.0
#pragma once
// Topic names, default QoS and participant creation shared by the daemon's bridge, swivelctl
// and the tests. Types are the C types idlc generates from core/idl/swivel.idl ("swivel.h")
// and core/idl/ros2/ros2_interfaces.idl ("ros2_interfaces.h"). None of this is real-time
// safe: DDS calls belong on the bridge's own threads.

#include <dds/dds.h>

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>

namespace swivel::dds {

inline constexpr const char* kRobotStateTopic = "swivel_robot_state";
inline constexpr const char* kModuleStatesTopic = "swivel_module_states";
inline constexpr const char* kDiagnosticsTopic = "swivel_diagnostics";
inline constexpr const char* kCalibrationResultTopic = "swivel_calibration_result";
inline constexpr const char* kVelocityCommandTopic = "swivel_velocity_command";
inline constexpr const char* kMotionCaptureTopic = "swivel_motion_capture";
inline constexpr const char* kRequestTopic = "swivel_command";
inline constexpr const char* kSetPoseTopic = "swivel_set_pose";
inline constexpr const char* kReplyTopic = "swivel_reply";
inline constexpr const char* kRunSamplesTopic = "swivel_run_samples";
/// ROS 2's graph announcements (no "rt/" prefix), written with dds.ros2 enabled (ros2_node.hpp).
inline constexpr const char* kRosDiscoveryInfoTopic = "ros_discovery_info";

/// Keep-last depth of swivel_run_samples on both ends: 20 s at the default 100 Hz, so that a
/// recorder that stalls that long still gets every sample.
inline constexpr int kRunSamplesHistoryDepth = 2000;

/// A DDS call failed; the message names the call and Cyclone's return code.
class DdsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Throws DdsError("<what>: <dds_strretcode>") when `rc` is negative; returns `rc` otherwise.
dds_return_t check(dds_return_t rc, const char* what);

struct QosDeleter {
  void operator()(dds_qos_t* qos) const noexcept { dds_delete_qos(qos); }
};
using QosPtr = std::unique_ptr<dds_qos_t, QosDeleter>;

/// Swivel's default QoS: reliable, keep-last `depth` (clamped to 1..100), volatile, and
/// plain CDR (XCDR1) so that ROS 2 and other XCDR1-only peers interoperate.
QosPtr default_qos(int depth = 1);

/// As default_qos but best-effort: used for readers of streamed commands (ROS 2 cmd_vel)
/// so that both best-effort and reliable writers match.
QosPtr best_effort_qos(int depth = 1);

/// QoS of swivel_run_samples, for the daemon's writer and a recorder's reader alike: reliable
/// (a lost packet is resent), keep-last kRunSamplesHistoryDepth (room for the writer to
/// resend and for a reader that falls behind), volatile (a recording starts when the recorder
/// joins), plain CDR.
QosPtr run_samples_qos();

/// The participant's domain and Cyclone configuration.
struct ParticipantOptions {
  std::uint32_t domain_id = 0;
  /// Cyclone configuration: a "file://" URI or XML. Empty: use CYCLONEDDS_URI (or Cyclone's
  /// defaults when unset).
  std::string config_uri;
};

/// A DDS domain participant, deleted (with every entity under it) on destruction.
class Participant {
 public:
  /// `user_data`: the participant's USER_DATA QoS ("" for none; ROS 2 reads "enclave=/;"
  /// there). @throws DdsError when the domain or the participant cannot be created.
  explicit Participant(const ParticipantOptions& options, const std::string& user_data = "");
  ~Participant();
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;
  Participant(Participant&&) = delete;
  Participant& operator=(Participant&&) = delete;

  [[nodiscard]] dds_entity_t handle() const { return handle_; }

 private:
  dds_entity_t handle_ = 0;
};

/// The Cyclone configuration a participant uses, and a line saying where it came from.
struct ResolvedConfig {
  /// "file://..." to create the domain with, or "" to let Cyclone read CYCLONEDDS_URI.
  std::string uri;
  /// For logs, --help and errors, e.g. "CYCLONEDDS_URI=file:///etc/... (environment)".
  std::string description;
};

/// The one rule, for the daemon and every tool: CYCLONEDDS_URI, when set and not empty,
/// wins, as for any Cyclone DDS program (a systemd drop-in that sets it, e.g. the DDS
/// Security profile, takes effect); otherwise `file_uri` (the daemon's dds.config) when
/// not empty; otherwise the loopback configuration shipped with Swivel (the source tree's
/// config/dds/loopback.xml for a binary in the build tree, the installed
/// <sysconfdir>/swivel/dds/loopback.xml otherwise), never Cyclone's defaults.
ResolvedConfig resolve_config(const std::string& file_uri = "");

/// The last DDS domain a DDS Security governance or permissions document can name (OMG DDS
/// Security's DomainId: 0..230); plain DDS goes to 232.
inline constexpr std::uint32_t kMaxSecureDomainId = 230;

/// True when the Cyclone configuration in effect (CYCLONEDDS_URI when it is a single
/// file:// URI, else `config_uri`) enables DDS Security (has a <Security> element).
bool uses_dds_security(const std::string& config_uri);

/// resolve_config("").uri: what a command-line tool uses.
std::string tool_config_uri();

/// resolve_config("").description, for --help and errors.
std::string describe_tool_config();

/// Creates a topic of `descriptor` named `name`. @throws DdsError
dds_entity_t create_topic(dds_entity_t participant, const dds_topic_descriptor_t* descriptor,
                          const char* name);

}  // namespace swivel::dds
