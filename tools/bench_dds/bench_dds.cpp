// SPDX-License-Identifier: Apache-2.0
// swivel-bench-dds: how old is the robot state when a client on the same host gets it?
//
// A server process runs the DdsBridge over a synthetic 1 kHz loop (each snapshot stamped
// with CLOCK_MONOTONIC at its cycle) and echoes pings; this process measures
//   age   = client receive time - snapshot stamp, for Swivel's RobotState (monotonic stamp)
//           and for ROS 2's rt/<robot>/odom and rt/tf (header stamps in ROS time, against
//           the client's CLOCK_REALTIME)
//   floor = one-way DDS latency, half the round trip of a ping-pong with the same QoS, one
//           ping per publish period (the cadence of the state), sent half a period after
//           each state sample: both series come from the same seconds
// and prints p50/p99 of each, with the target: age p99 <= floor p99 + 150 us (the bridge
// publishes each sample right after the loop cycle that made it: one DDS hop). The exit
// status follows the RobotState target; odom and tf are reported against the same bound.

#include <sys/wait.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "ros2_interfaces.h"
#include "swivel.h"
#include "swivel/cli/command_line.hpp"
#include "swivel/clock.hpp"
#include "swivel/dds/bridge.hpp"
#include "swivel/dds/topics.hpp"
#include "swivel/stats/summary.hpp"

namespace swivel::dds {
namespace {

constexpr const char* kPingTopic = "swivel_bench_ping";
constexpr const char* kPongTopic = "swivel_bench_pong";

std::atomic<bool> g_stop{false};

std::int64_t realtime_ns() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

double ros_stamp_s(const builtin_interfaces_msg_dds__Time_& t) {
  return static_cast<double>(t.sec) + 1e-9 * static_cast<double>(t.nanosec);
}
extern "C" void on_signal(int) { g_stop = true; }

// 0 for an empty sample (a phase that produced none), else the type-7 quantile.
double percentile(const std::vector<double>& v, double p) {
  return v.empty() ? 0.0 : stats::quantile(v, p);
}

dds_entity_t make_reader(dds_entity_t pp, const dds_topic_descriptor_t* d,
                         const std::string& name) {
  const QosPtr qos = default_qos(10);
  return check(dds_create_reader(pp, create_topic(pp, d, name.c_str()), qos.get(), nullptr),
               "reader");
}

dds_entity_t make_writer(dds_entity_t pp, const dds_topic_descriptor_t* d, const char* name) {
  const QosPtr qos = default_qos(10);
  return check(dds_create_writer(pp, create_topic(pp, d, name), qos.get(), nullptr), "writer");
}

bool matched(dds_entity_t writer) {
  dds_publication_matched_status_t s{};
  return dds_get_publication_matched_status(writer, &s) == 0 && s.current_count > 0;
}

// Server: the bridge over a synthetic loop, and a pong for every ping.
int run_server(const std::string& robot, double rate_hz) {
  signal(SIGTERM, on_signal);
  signal(SIGINT, on_signal);
  std::mutex mutex;
  StateSnapshot latest;
  std::jthread loop([&](const std::stop_token& stop) {
    auto next = std::chrono::steady_clock::now();
    std::uint64_t cycle = 0;
    while (!stop.stop_requested()) {
      next += std::chrono::milliseconds(1);
      std::this_thread::sleep_until(next);
      const std::scoped_lock lock(mutex);
      latest.cycle = ++cycle;
      latest.stamp_s = swivel::monotonic_s();
      latest.ros_stamp_ns = realtime_ns();  // the daemon maps stamp_s through its clock offset
    }
  });
  DdsOptions options;
  options.publish_rate_hz = rate_hz;
  options.config_uri = tool_config_uri();  // loopback unless CYCLONEDDS_URI says otherwise
  // ROS 2 odometry and tf as the daemon publishes them, under the robot's namespace.
  options.ros2.enabled = true;
  options.ros2.ros_namespace = robot;
  options.ros2.odom_frame_id = robot + "/odom";
  options.ros2.base_frame_id = robot + "/base_link";
  DdsBridge bridge(options, robot, {.read_state = [&](StateSnapshot& s) {
                     const std::scoped_lock lock(mutex);
                     s = latest;
                     return s.cycle > 0;
                   }});
  Participant pp({0, tool_config_uri()});
  const dds_entity_t ping = make_reader(pp.handle(), &swivel_msg_VelocityCommand_desc, kPingTopic);
  const dds_entity_t pong = make_writer(pp.handle(), &swivel_msg_VelocityCommand_desc, kPongTopic);
  const dds_entity_t waitset = dds_create_waitset(pp.handle());
  dds_waitset_attach(waitset, dds_create_readcondition(ping, DDS_ANY_STATE), 0);
  bridge.start();
  while (!g_stop) {
    if (dds_waitset_wait(waitset, nullptr, 0, DDS_MSECS(100)) <= 0) continue;
    void* samples[16] = {nullptr};
    dds_sample_info_t infos[16];
    const dds_return_t n = dds_take(ping, samples, infos, 16, 16);
    for (dds_return_t i = 0; i < n; ++i) {
      if (infos[i].valid_data) dds_write(pong, samples[i]);
    }
    if (n > 0) dds_return_loan(ping, samples, n);
  }
  bridge.stop();
  return 0;
}

constexpr double kAllowanceUs = 150.0;

int run_client(const std::string& robot, double rate_hz, double seconds) {
  const pid_t child = fork();
  if (child == 0) {
    const std::string rate = std::to_string(rate_hz);
    execl("/proc/self/exe", "swivel-bench-dds", "--server", "--robot", robot.c_str(), "--rate-hz",
          rate.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  Participant pp({0, tool_config_uri()});
  const dds_entity_t state =
      make_reader(pp.handle(), &swivel_msg_RobotState_desc, kRobotStateTopic);
  Ros2Options ros2;
  ros2.ros_namespace = robot;
  const dds_entity_t odom =
      make_reader(pp.handle(), &nav_msgs_msg_dds__Odometry__desc, ros2.odom_topic());
  const dds_entity_t tf = make_reader(pp.handle(), &tf2_msgs_msg_dds__TFMessage__desc,
                                      swivel::dds::Ros2Options::tf_topic());
  const dds_entity_t ping = make_writer(pp.handle(), &swivel_msg_VelocityCommand_desc, kPingTopic);
  const dds_entity_t pong = make_reader(pp.handle(), &swivel_msg_VelocityCommand_desc, kPongTopic);
  auto finish = [&](int code) {
    kill(child, SIGTERM);
    waitpid(child, nullptr, 0);
    return code;
  };

  // Age and floor are measured in the same seconds: half a publish period after each state
  // sample the client sends a ping, so a burst of load on the host lands in both series,
  // not in one phase only. The pings fall between state samples and do not meet them.
  const double match_deadline = swivel::monotonic_s() + 10.0;
  while (!matched(ping) && swivel::monotonic_s() < match_deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  std::vector<double> ages_us;
  std::vector<double> publish_us;  // snapshot stamp -> dds_write (the bridge's share)
  std::vector<double> hop_us;      // dds_write -> client receive (the DDS hop)
  std::vector<double> odom_ages_us;
  std::vector<double> tf_ages_us;
  std::vector<double> one_way_us;
  const dds_entity_t ws = dds_create_waitset(pp.handle());
  dds_waitset_attach(ws, dds_create_readcondition(state, DDS_ANY_STATE), 0);
  dds_waitset_attach(ws, dds_create_readcondition(odom, DDS_ANY_STATE), 1);
  dds_waitset_attach(ws, dds_create_readcondition(tf, DDS_ANY_STATE), 2);
  dds_waitset_attach(ws, dds_create_readcondition(pong, DDS_ANY_STATE), 3);
  const std::string odom_frame = robot + "/odom";
  std::string id = "bench";
  swivel_msg_VelocityCommand msg{};
  msg.robot_id = id.data();
  constexpr int kWarmupPings = 20;
  int pings_sent = 0;
  double ping_at = 0.0;    // when the next ping goes out (0: none scheduled)
  bool in_flight = false;  // a ping awaits its pong
  const double half_period_s = 0.5 / rate_hz;
  const double deadline_first = swivel::monotonic_s() + 10.0;
  double end = 0.0;
  void* samples[16] = {nullptr};
  dds_sample_info_t infos[16];
  while (end == 0.0 || swivel::monotonic_s() < end) {
    double now = swivel::monotonic_s();
    if (end == 0.0 && now > deadline_first) {
      std::fprintf(stderr, "swivel-bench-dds: no state from the server within 10 s\n");
      return finish(1);
    }
    if (in_flight && now - msg.stamp_s > 2.0) {
      std::fprintf(stderr, "swivel-bench-dds: ping %d unanswered within 2 s\n", pings_sent);
      return finish(1);
    }
    if (ping_at > 0.0 && now >= ping_at && !in_flight) {
      msg.sequence_number = static_cast<std::uint64_t>(++pings_sent);
      msg.stamp_s = swivel::monotonic_s();
      dds_write(ping, &msg);
      in_flight = true;
      ping_at = 0.0;
    }
    const double wait_s = ping_at > 0.0 ? std::max(0.0, ping_at - now) : 0.1;
    if (dds_waitset_wait(ws, nullptr, 0, static_cast<dds_duration_t>(wait_s * 1e9)) <= 0) continue;
    const dds_return_t n = dds_take(state, samples, infos, 16, 16);
    now = swivel::monotonic_s();
    const auto real_now_ns = static_cast<double>(realtime_ns());
    for (dds_return_t i = 0; i < n; ++i) {
      const auto* s = static_cast<const swivel_msg_RobotState*>(samples[i]);
      if (!infos[i].valid_data || robot != s->robot_id) continue;
      if (!in_flight && ping_at == 0.0) ping_at = now + half_period_s;
      if (end == 0.0) {
        end = now + seconds;  // the first sample starts the measurement window
        continue;
      }
      ages_us.push_back(1e6 * (now - s->stamp_s));
      // The server stamps ROS time at the snapshot's instant, and DDS stamps the write
      // (source_timestamp), both from CLOCK_REALTIME: the age splits into the bridge's share
      // and the hop.
      const double stamp_ns =
          1e9 * static_cast<double>(s->ros_stamp_sec) + static_cast<double>(s->ros_stamp_nanosec);
      const auto written_ns = static_cast<double>(infos[i].source_timestamp);
      publish_us.push_back(1e-3 * (written_ns - stamp_ns));
      hop_us.push_back(1e-3 * (real_now_ns - written_ns));
    }
    if (n > 0) dds_return_loan(state, samples, n);
    const dds_return_t n_pong = dds_take(pong, samples, infos, 16, 16);
    for (dds_return_t i = 0; i < n_pong; ++i) {
      const auto* p = static_cast<const swivel_msg_VelocityCommand*>(samples[i]);
      if (!infos[i].valid_data || !in_flight || p->sequence_number != msg.sequence_number) continue;
      in_flight = false;
      if (pings_sent > kWarmupPings && end != 0.0) one_way_us.push_back(0.5e6 * (now - p->stamp_s));
    }
    if (n_pong > 0) dds_return_loan(pong, samples, n_pong);
    if (end == 0.0) continue;
    // ROS 2 stamps are ROS time: compare with this host's realtime clock.
    const dds_return_t n_odom = dds_take(odom, samples, infos, 16, 16);
    const double ros_now = 1e-9 * static_cast<double>(realtime_ns());
    for (dds_return_t i = 0; i < n_odom; ++i) {
      const auto* o = static_cast<const nav_msgs_msg_dds__Odometry_*>(samples[i]);
      if (infos[i].valid_data)
        odom_ages_us.push_back(1e6 * (ros_now - ros_stamp_s(o->header.stamp)));
    }
    if (n_odom > 0) dds_return_loan(odom, samples, n_odom);
    const dds_return_t n_tf = dds_take(tf, samples, infos, 16, 16);
    for (dds_return_t i = 0; i < n_tf; ++i) {
      const auto* m = static_cast<const tf2_msgs_msg_dds__TFMessage_*>(samples[i]);
      if (!infos[i].valid_data || m->transforms._length == 0) continue;
      const auto& t = m->transforms._buffer[0];
      if (odom_frame == t.header.frame_id)
        tf_ages_us.push_back(1e6 * (ros_now - ros_stamp_s(t.header.stamp)));
    }
    if (n_tf > 0) dds_return_loan(tf, samples, n_tf);
  }

  // For reference: back-to-back pings, which find Cyclone's receive threads awake.
  const dds_entity_t pong_ws = dds_create_waitset(pp.handle());
  dds_waitset_attach(pong_ws, dds_create_readcondition(pong, DDS_ANY_STATE), 0);
  std::vector<double> warm_us;
  for (int i = 0; i < 1000; ++i) {
    msg.sequence_number = static_cast<std::uint64_t>(++pings_sent);
    msg.stamp_s = swivel::monotonic_s();
    dds_write(ping, &msg);
    bool got = false;
    while (!got && dds_waitset_wait(pong_ws, nullptr, 0, DDS_SECS(2)) > 0) {
      const dds_return_t n = dds_take(pong, samples, infos, 16, 16);
      const double now = swivel::monotonic_s();
      for (dds_return_t k = 0; k < n; ++k) {
        const auto* p = static_cast<const swivel_msg_VelocityCommand*>(samples[k]);
        if (infos[k].valid_data && p->sequence_number == msg.sequence_number) {
          got = true;
          warm_us.push_back(0.5e6 * (now - p->stamp_s));
        }
      }
      if (n > 0) dds_return_loan(pong, samples, n);
    }
    if (!got) {
      std::fprintf(stderr, "swivel-bench-dds: ping %d unanswered within 2 s\n", pings_sent);
      return finish(1);
    }
    std::this_thread::sleep_for(std::chrono::microseconds(500));
  }

  const double age_p50 = percentile(ages_us, 0.50);
  const double age_p99 = percentile(ages_us, 0.99);
  const double floor_p50 = percentile(one_way_us, 0.50);
  const double floor_p99 = percentile(one_way_us, 0.99);
  // One DDS hop after the loop: the floor plus what the publisher may add (the loop
  // cycle's own work and the publisher's wake-up).
  const double target_us = floor_p99 + kAllowanceUs;
  std::printf(
      "state age at client (%zu samples at %.0f Hz, 1 kHz synthetic loop): "
      "p50 %.1f us  p99 %.1f us  max %.1f us\n",
      ages_us.size(), rate_hz, age_p50, age_p99, percentile(ages_us, 1.0));
  std::printf(
      "DDS floor, one-way (ping-pong RTT/2, %zu round trips at %.0f Hz between the samples, same "
      "QoS): "
      "p50 %.1f us  p99 %.1f us\n",
      one_way_us.size(), rate_hz, floor_p50, floor_p99);
  std::printf(
      "  the age's parts: stamp -> dds_write p50 %.1f us  p99 %.1f us; "
      "dds_write -> client p50 %.1f us  p99 %.1f us\n",
      percentile(publish_us, 0.50), percentile(publish_us, 0.99), percentile(hop_us, 0.50),
      percentile(hop_us, 0.99));
  std::printf("  (back-to-back, %zu round trips 0.5 ms apart: p50 %.1f us  p99 %.1f us)\n",
              warm_us.size(), percentile(warm_us, 0.50), percentile(warm_us, 0.99));
  std::printf(
      "target: age p99 <= floor p99 + %.0f us = %.1f us: %s (age p99 - floor p99 = %.1f us)\n",
      kAllowanceUs, target_us, age_p99 <= target_us ? "met" : "NOT met", age_p99 - floor_p99);
  // ROS 2 ages rest on two clocks (the server's realtime stamp, the client's realtime
  // receive time) of the same host, so they compare directly with the floor too.
  const auto report_ros = [&](const char* name, const std::vector<double>& ages) {
    if (ages.empty()) {
      std::printf("%-8s age at client: no samples (ROS 2 topics not published?)\n", name);
      return;
    }
    const double p99 = percentile(ages, 0.99);
    std::printf(
        "%-8s age at client (%zu samples): p50 %.1f us  p99 %.1f us  max %.1f us; "
        "p99 - floor p99 = %.1f us: %s\n",
        name, ages.size(), percentile(ages, 0.50), p99, percentile(ages, 1.0), p99 - floor_p99,
        p99 <= target_us ? "within the target" : "beyond the target");
  };
  report_ros("rt/odom", odom_ages_us);
  report_ros("rt/tf", tf_ages_us);
  return finish(age_p99 <= target_us ? 0 : 3);
}

}  // namespace
}  // namespace swivel::dds

namespace {

int run(int argc, char** argv) {
  CLI::App app{
      "swivel-bench-dds: age of the robot state at a client process, next to the DDS\n"
      "ping-pong floor of the same run. DDS configuration: CYCLONEDDS_URI when set,\n"
      "otherwise Swivel's loopback.xml. Now: " +
      swivel::dds::describe_tool_config()};
  bool server = false;
  std::string robot = "bench_" + std::to_string(getpid());
  double rate_hz = 100.0;
  double seconds = 20.0;
  app.add_flag("--server", server, "run the publishing side (started by the benchmark)");
  app.add_option("--robot", robot, "robot id of the synthetic daemon");
  app.add_option("--rate-hz", rate_hz, "publish rate, Hz")->capture_default_str();
  app.add_option("--seconds", seconds, "state measurement window, s")->capture_default_str();
  if (const auto exit = swivel::cli::parse(app, argc, argv, "swivel-bench-dds")) return *exit;
  return server ? swivel::dds::run_server(robot, rate_hz)
                : swivel::dds::run_client(robot, rate_hz, seconds);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "swivel-bench-dds: %s\n", e.what());
    return 1;
  } catch (...) {
    std::fprintf(stderr, "swivel-bench-dds: unknown error\n");
    return 1;
  }
}
