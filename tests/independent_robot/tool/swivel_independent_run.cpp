// SPDX-License-Identifier: Apache-2.0
// swivel-independent-run: writes a "measured" run log and the nominal robot model of a robot
// simulated independently of Swivel's own simulator, either a battery case or a run built
// from the command line. Exit codes: 0 done, 1 a file could not be written, 2 usage error.

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "swivel/cli/command_line.hpp"
#include "swivel/independent/battery.hpp"
#include "swivel/independent/generator.hpp"
#include "swivel/independent/library_effects.hpp"
#include "swivel/independent/outside_effects.hpp"

namespace {

using namespace swivel::independent;

constexpr int kUsageError = swivel::cli::kUsageError;
constexpr int kWriteError = 1;

class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Options {
  bool list = false;
  std::string case_id;
  std::string robot;
  std::string steering = "powered";
  std::vector<std::string> truth;
  std::vector<std::string> outside;
  double duration_s = 0.0;
  std::uint64_t seed = 0;
  bool no_limits = false;
  bool no_steering_limit = false;
  bool no_noise = false;
  std::string out;
  std::string model_out;
};

void print_list() {
  for (const BatteryCase& c : battery()) {
    std::printf("%-44s %-8s %s\n", c.id.c_str(), case_kind_name(c.kind).c_str(),
                c.description.c_str());
  }
}

std::string describe(const std::vector<ExpectedEffect>& expected, const RunSpec& spec) {
  if (expected.empty()) {
    const std::vector<std::string> outside = active_outside_effects(spec.outside);
    if (outside.empty()) return "no library effect (the true robot is the nominal one)";
    std::string names;
    for (const std::string& n : outside) names += (names.empty() ? "" : ", ") + n;
    return "no library effect (outside the library: " + names + ")";
  }
  std::string text;
  for (const ExpectedEffect& e : expected) {
    for (const ExpectedParam& p : e.params) {
      if (!text.empty()) text += ", ";
      char value[32];
      (void)std::snprintf(value, sizeof value, "%.10g", p.value);
      text += e.effect + "." + p.key + "=" + value;
    }
  }
  return text;
}

RunSpec spec_from(const Options& o, const CLI::App& app) {
  const bool by_case = !o.case_id.empty();
  if (by_case == !o.robot.empty()) {
    throw UsageError("give either --case ID or --robot docent|swpc4 (see --list)");
  }
  RunSpec spec;
  if (by_case) {
    const BatteryCase* c = find_case(o.case_id);
    if (c == nullptr) throw UsageError("--case " + o.case_id + ": unknown case (see --list)");
    for (const char* hand : {"--true", "--outside", "--steering", "--no-limits-in-model",
                             "--no-steering-limit-in-model", "--no-noise"}) {
      if (app.count(hand) > 0) {
        throw UsageError(std::string(hand) +
                         ": not with --case (a case fixes the robot; build a run with --robot)");
      }
    }
    spec = c->spec;
  } else {
    spec.robot = o.robot == "docent" ? Robot::kDocent : Robot::kSwpc4;
    spec.steering = o.steering == "self_aligning" ? Steering::kSelfAligning : Steering::kPowered;
    if (spec.robot == Robot::kDocent && app.count("--steering") > 0 && o.steering != "powered") {
      throw UsageError("--steering " + o.steering + ": the docent has no steering");
    }
    for (const std::string& a : o.truth) {
      try {
        set_true_effect(spec, a);
      } catch (const std::invalid_argument& e) {
        throw UsageError(std::string("--true ") + e.what());
      }
    }
    for (const std::string& a : o.outside) {
      try {
        set_outside_effect(spec, a);
      } catch (const std::invalid_argument& e) {
        throw UsageError(std::string("--outside ") + e.what());
      }
    }
    if (o.no_steering_limit) {
      if (spec.robot != Robot::kSwpc4) {
        throw UsageError("--no-steering-limit-in-model: the docent has no steering");
      }
      spec.model_limits = ModelLimits::kNone;
    } else if (o.no_limits) {
      spec.model_limits =
          spec.robot == Robot::kSwpc4 ? ModelLimits::kSteeringOnly : ModelLimits::kNone;
    }
    if (o.no_noise) spec.noise = NoiseSpec::quiet();
  }
  if (app.count("--duration") > 0) spec.duration_s = o.duration_s;
  if (app.count("--seed") > 0) spec.seed = o.seed;
  try {
    validate(spec);
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  return spec;
}

void write_file(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!f) throw std::runtime_error(path + ": cannot open for writing");
  f << text;
  f.close();
  if (!f) throw std::runtime_error(path + ": write failed");
}

}  // namespace

int run_tool(int argc, char** argv) {
  CLI::App app{
      "Writes a measured run log (and the nominal robot model) of a robot simulated "
      "independently of Swivel's simulator: a battery case, or a run built by hand."};
  Options o;
  app.add_flag("--list", o.list, "list the battery's cases with descriptions");
  app.add_option("--case", o.case_id, "battery case id, e.g. docent/track_width/large");
  app.add_option("--robot", o.robot, "build a run by hand for this robot")
      ->check(CLI::IsMember({"docent", "swpc4"}));
  app.add_option("--steering", o.steering, "swpc4 steering: powered (default) or self_aligning")
      ->check(CLI::IsMember({"powered", "self_aligning"}));
  app.add_option("--true", o.truth,
                 "NAME.PARAM=VALUE: a library effect of the true robot (repeatable), e.g. "
                 "gyro_bias.bias_rad_s=0.006");
  app.add_option("--outside", o.outside,
                 "NAME.PARAM=VALUE: an effect outside the library (repeatable), e.g. "
                 "floor_drift.vx_mps=0.002");
  app.add_option("--duration", o.duration_s, "run length, s (default 120)")
      ->check(CLI::Range(2.0, 3600.0));
  app.add_option("--seed", o.seed, "tour, start pose and noise seed");
  app.add_flag("--no-limits-in-model", o.no_limits,
               "the model leaves out the acceleration limits (swpc4 keeps its steering limit)");
  app.add_flag("--no-steering-limit-in-model", o.no_steering_limit,
               "swpc4: the model has no limits: section at all");
  app.add_flag("--no-noise", o.no_noise, "no slip, sensor noise, dropouts or jitter");
  app.add_option("--out", o.out, "run log (CSV) to write");
  app.add_option("--model-out", o.model_out, "nominal robot model (YAML) to write");

  if (const auto exit = swivel::cli::parse(app, argc, argv, "swivel-independent-run")) {
    return *exit;
  }

  if (o.list) {
    print_list();
    return 0;
  }
  RunSpec spec;
  try {
    spec = spec_from(o, app);
    if (o.out.empty()) throw UsageError("--out FILE is required");
  } catch (const UsageError& e) {
    std::cerr << "swivel-independent-run: " << e.what() << "\n";
    return kUsageError;
  }

  const auto start = std::chrono::steady_clock::now();
  const GeneratedRun run = generate(spec);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  try {
    write_file(o.out, run.run_csv);
    if (!o.model_out.empty()) write_file(o.model_out, run.nominal_model_yaml);
  } catch (const std::runtime_error& e) {
    std::cerr << "swivel-independent-run: " << e.what() << "\n";
    return kWriteError;
  }
  std::printf("wrote %s: %s, %g s, seed %llu (generated in %.2f s)\n", o.out.c_str(),
              robot_name(spec.robot).c_str(), spec.duration_s,
              static_cast<unsigned long long>(spec.seed), seconds);
  if (!o.model_out.empty()) std::printf("wrote %s: the nominal model\n", o.model_out.c_str());
  std::printf("expected: %s\n", describe(expected_effects(spec), spec).c_str());
  return 0;
}

int main(int argc, char** argv) {
  try {
    return run_tool(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "swivel-independent-run: %s\n", e.what());
    return 1;
  }
}
