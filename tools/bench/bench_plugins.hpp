// SPDX-License-Identifier: Apache-2.0
#pragma once
// The plugins a benchmark runs the ControlLoop with: the ones a daemon configuration names,
// loaded and configured the way swiveld does it, or in-process fakes when asked for (or when
// the real ones cannot be loaded, which the description then says).

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <string>

#include "fake_plugins.hpp"
#include "swivel/plugin/plugin_context.hpp"
#include "swivel/plugin_loader.hpp"
#include "swivel/robot_model.hpp"

namespace swivel::bench {

struct Plugins {
  RobotModel robot;
  PluginInstance<Hardware> hardware;
  PluginInstance<Drivetrain> drivetrain;
  PluginInstance<Localization> localization;
  test::FakeHardware fake_hardware;
  test::FakeDrivetrain fake_drivetrain;
  test::FakeLocalization fake_localization;
  bool real = false;
  std::string description;
  std::string config_file;
  std::filesystem::path config_dir;
  double period_s = 0.001;

  Hardware& hw() { return real ? *hardware : fake_hardware; }
  Drivetrain& dt() { return real ? *drivetrain : fake_drivetrain; }
  Localization& loc() { return real ? *localization : fake_localization; }
  [[nodiscard]] std::string localization_name() const {
    return real ? localization.name() : "fake";
  }

  /// The context a plugin of this configuration is configured with; `slot` names its params
  /// in messages ("localization" -> "localization.params").
  [[nodiscard]] PluginContext context(const YAML::Node& params, const std::string& slot) const;
};

/// Loads and configures the plugins `config_file` names, at `rate_hz`, and resets the
/// localization at the origin; with `fakes`, or when loading fails, uses the fakes.
void load_plugins(const std::string& config_file, double rate_hz, bool fakes, Plugins& p);

}  // namespace swivel::bench
