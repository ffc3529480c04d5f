// SPDX-License-Identifier: Apache-2.0
// YAML text -> parse_robot_model. Contract: a model or ConfigError, nothing else. A model
// that parses must also survive robot_model_to_yaml and parse back to the same values, as
// robot_model_io.hpp promises (calibration and the model-gap workflow write models back).

#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_support.hpp"
#include "swivel/config/config_error.hpp"
#include "swivel/robot_model_io.hpp"

namespace {

constexpr const char* kTarget = "fuzz_robot_model";

bool same(const swivel::RobotModel& a, const swivel::RobotModel& b) {
  if (a.name != b.name || a.drivetrain != b.drivetrain) return false;
  const auto& da = a.differential;
  const auto& db = b.differential;
  if (da.wheel_radius_left_m != db.wheel_radius_left_m ||
      da.wheel_radius_right_m != db.wheel_radius_right_m || da.track_width_m != db.track_width_m) {
    return false;
  }
  if (a.modules.size() != b.modules.size()) return false;
  for (std::size_t i = 0; i < a.modules.size(); ++i) {
    const auto& ma = a.modules[i];
    const auto& mb = b.modules[i];
    if (ma.x_m != mb.x_m || ma.y_m != mb.y_m || ma.steering_offset_rad != mb.steering_offset_rad ||
        ma.caster_offset_m != mb.caster_offset_m || ma.wheel_radius_m != mb.wheel_radius_m) {
      return false;
    }
  }
  const auto& sa = a.sensors;
  const auto& sb = b.sensors;
  return sa.wheel_encoder_counts_per_rev == sb.wheel_encoder_counts_per_rev &&
         sa.steering_encoder_counts_per_rev == sb.steering_encoder_counts_per_rev &&
         sa.gyro.scale == sb.gyro.scale && sa.gyro.bias_rad_s == sb.gyro.bias_rad_s &&
         sa.gyro.noise_rad_s == sb.gyro.noise_rad_s &&
         sa.motion_capture.position_noise_m == sb.motion_capture.position_noise_m &&
         sa.motion_capture.yaw_noise_rad == sb.motion_capture.yaw_noise_rad &&
         sa.motion_capture.rate_hz == sb.motion_capture.rate_hz && a.effects == b.effects;
}

}  // namespace

// The entry point libFuzzer names.
// NOLINTNEXTLINE(readability-identifier-naming)
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  swivel::RobotModel model;
  try {
    model = swivel::parse_robot_model(text, "fuzz.yaml");
  } catch (const swivel::ConfigError&) {
    return 0;
  } catch (const std::exception& e) {
    swivel::fuzz::unexpected_exception(kTarget, e);
  }

  const std::string written = swivel::robot_model_to_yaml(model);
  swivel::RobotModel again;
  try {
    again = swivel::parse_robot_model(written, "written.yaml");
  } catch (const std::exception& e) {
    swivel::fuzz::contract_broken(
        kTarget, "a model that parsed does not read back after robot_model_to_yaml: " +
                     std::string(e.what()) + "\n--- written:\n" + written);
  }
  if (!same(model, again)) {
    swivel::fuzz::contract_broken(
        kTarget, "robot_model_to_yaml changed the model\n--- written:\n" + written);
  }
  return 0;
}
