// SPDX-License-Identifier: Apache-2.0
// swivel-second-run: writes a run log and the nominal robot model from the second robot
// generator (tests/second_robot/README.md), a run built on the command line or a case of the
// validation (or smoke) set. Exit codes: 0 done, 1 a file could not be written, 2 usage error.

#include <CLI/CLI.hpp>
#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "swivel/cli/command_line.hpp"
#include "swivel/second/second_robot.hpp"
#include "swivel/second/validation_set.hpp"

namespace {

using namespace swivel::second;

bool write(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  f << text;
  f.close();
  if (!f) {
    std::fprintf(stderr, "swivel-second-run: cannot write %s\n", path.c_str());
    return false;
  }
  return true;
}

std::string expected_text(const std::vector<ExpectedEffect>& expected) {
  if (expected.empty()) return "no library effect (no significant gap)";
  std::string s;
  for (const auto& e : expected) {
    for (const auto& [k, v] : e.params) {
      s += (s.empty() ? "" : " ") + e.effect + "." + k + "=" + std::to_string(v);
    }
  }
  return s;
}

int run(int argc, char** argv) {
  CLI::App app{"The second robot generator: a run log and its nominal model"};
  std::string robot = "cart4";
  std::vector<std::string> truth;
  std::string script = "mixed";
  double rate = 50.0;
  double duration = 90.0;
  std::uint64_t seed = 1;
  bool no_accel = false;
  bool no_steer = false;
  bool fractional = false;
  bool no_noise = false;
  std::string case_kind;
  std::size_t index = 0;
  std::string seeds = "smoke";
  std::string out;
  std::string model_out;
  auto* case_option =
      app.add_option("--case", case_kind, "a case of a seed set: clean, library or outside");
  app.add_option("--index", index, "with --case: its index")->needs(case_option);
  app.add_option("--seeds", seeds,
                 "with --case: its seed ranges, smoke (default), validation (do not look at "
                 "those while developing), or first-validation to fifteenth-validation (the "
                 "earlier validation sets, development data now)")
      ->check(CLI::IsMember(swivel::second::seed_set_names()))
      ->needs(case_option);
  app.add_option("--true", truth,
                 "NAME.PARAM=VALUE: the true robot (repeatable; with --case, changes the case's)");
  app.add_flag("--no-noise", no_noise,
               "no sensor noise or clock jitter (with --case, changes the case's)");
  // What a case fixes itself: given with --case, they would be silently ignored.
  app.add_option("--robot", robot, "trike3, cart4, hex6, mini_diff, wide_diff, mid_diff")
      ->excludes(case_option);
  app.add_option("--script", script, "waypoints, circles, spot_turns or mixed")
      ->excludes(case_option);
  app.add_option("--rate", rate, "row rate, Hz (20-100)")->excludes(case_option);
  app.add_option("--duration", duration, "s")->excludes(case_option);
  app.add_option("--seed", seed)->excludes(case_option);
  app.add_flag("--no-accel-limits-in-model", no_accel, "the model states no acceleration limits")
      ->excludes(case_option);
  app.add_flag("--no-steering-limit-in-model", no_steer, "the model states no steering rate limit")
      ->excludes(case_option);
  app.add_flag("--fractional-counts", fractional,
               "geared encoders: counts per revolution are not integers (needs a robot-model "
               "reader with real-valued counts)")
      ->excludes(case_option);
  app.add_option("--out", out, "run log (CSV)")->required();
  app.add_option("--model-out", model_out, "nominal model (YAML)");
  std::string hidden_out;
  app.add_option("--hidden-out", hidden_out,
                 "the generator's own state at each row, which the log does not show (CSV: "
                 "true pose and body twist, wheel angles and contact speeds, caster angles and "
                 "servo errors): for tracing what a finding is due to");
  if (const auto exit = swivel::cli::parse(app, argc, argv, "swivel-second-run")) return *exit;

  RunSpec spec;
  std::string description;
  try {
    if (!case_kind.empty()) {
      ValidationCase c;
      const SeedRanges& ranges = *seed_ranges_named(seeds);  // checked by the option
      if (case_kind == "clean") {
        c = clean_case(ranges.clean, index);
      } else if (case_kind == "library") {
        c = library_case(ranges.library, index);
      } else if (case_kind == "outside") {
        c = outside_case(ranges.outside, index);
      } else {
        throw std::invalid_argument("--case " + case_kind + ": expected clean, library or outside");
      }
      spec = c.spec;
      description = c.id + ": " + c.description;
      // The case with some of its physics changed: what a finding on it is due to.
      for (const auto& a : truth) {
        set_truth(spec, a);
        description += " (changed: " + a + ")";
      }
      if (no_noise) {
        spec.noise = false;
        description += " (changed: no noise)";
      }
    } else {
      spec.design = robot;
      (void)design(robot);  // names the robots when unknown
      const std::vector<std::string> scripts = {"waypoints", "circles", "spot_turns", "mixed"};
      bool found = false;
      for (std::size_t i = 0; i < scripts.size(); ++i) {
        if (scripts[i] == script) {
          spec.script = static_cast<Script>(i);
          found = true;
        }
      }
      if (!found) throw std::invalid_argument("--script " + script + ": unknown");
      spec.row_rate_hz = rate;
      spec.duration_s = duration;
      spec.seed = seed;
      spec.model.accel_limits = !no_accel;
      spec.model.steering_rate_limit = !no_steer;
      spec.model.fractional_counts = fractional;
      spec.noise = !no_noise;
      for (const auto& a : truth) set_truth(spec, a);
      description = robot + ", seed " + std::to_string(seed);
    }
    const GeneratedRun run = generate(spec);
    if (!write(out, run.run_csv)) return 1;
    std::printf("wrote %s: %s\n", out.c_str(), description.c_str());
    if (!model_out.empty()) {
      if (!write(model_out, run.nominal_model_yaml)) return 1;
      std::printf("wrote %s: the nominal model\n", model_out.c_str());
    }
    if (!hidden_out.empty()) {
      if (!write(hidden_out, run.hidden_csv)) return 1;
      std::printf("wrote %s: the generator's hidden state\n", hidden_out.c_str());
    }
    std::printf("expected: %s\n", expected_text(run.expected).c_str());
    if (design(spec.design).drive == Drive::kSwpc) {
      std::printf("steering servos while driving: largest median error %.1f mrad (%s)\n",
                  run.driving_servo_error_rad * 1e3,
                  run.driving_servo_error_rad >= kFightingServoErrorRad
                      ? "fighting their tyres"
                      : "not fighting their tyres");
    }
    if (const auto f = geometry_footprint(spec)) {
      std::printf(
          "geometry footprint: the body moves %.3g per metre apart from the nominal geometry's, "
          "%.3g at half the deviations (growth %.2f: %s)\n",
          f->full, f->half, f->growth(),
          f->size_in_motion() ? "the size is in the motion"
                              : "friction-limited, size not in the motion");
    }
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "swivel-second-run: %s\n", e.what());
    return swivel::cli::kUsageError;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "swivel-second-run: %s\n", e.what());
    return 1;
  }
}
