// SPDX-License-Identifier: Apache-2.0
#include "bench_plugins.hpp"

#include <exception>

#include "swivel/robot_model_io.hpp"

namespace swivel::bench {

PluginContext Plugins::context(const YAML::Node& params, const std::string& slot) const {
  PluginContext ctx;
  ctx.params = params;
  ctx.config_file = config_file;
  ctx.params_path = slot + ".params";
  ctx.config_dir = config_dir.string();
  ctx.robot = &robot;
  ctx.period_s = period_s;
  return ctx;
}

namespace {

template <class Interface>
PluginInstance<Interface> load_slot(PluginLoader& loader, const Plugins& p, const YAML::Node& root,
                                    const char* slot) {
  auto instance = loader.create<Interface>(root[slot]["plugin"].as<std::string>());
  instance->configure(p.context(root[slot]["params"], slot));
  return instance;
}

}  // namespace

void load_plugins(const std::string& config_file, double rate_hz, bool fakes, Plugins& p) {
  p.config_file = config_file;
  p.config_dir = std::filesystem::path(config_file).parent_path();
  p.period_s = 1.0 / rate_hz;
  if (fakes) {
    p.description = "in-process fakes (--fakes)";
    return;
  }
  try {
    const YAML::Node root = YAML::LoadFile(config_file);
    p.robot = load_robot_model((p.config_dir / root["robot_model"].as<std::string>()).string());
    PluginLoader loader(PluginLoader::default_search_path());
    p.hardware = load_slot<Hardware>(loader, p, root, "hardware");
    p.drivetrain = load_slot<Drivetrain>(loader, p, root, "drivetrain");
    p.localization = load_slot<Localization>(loader, p, root, "localization");
    p.localization->reset(PoseEstimate{});
    p.real = true;
    p.description = "plugins " + p.hardware.name() + " / " + p.drivetrain.name() + " / " +
                    p.localization.name() + ", robot " + p.robot.name + " (" + config_file + ")";
  } catch (const std::exception& e) {
    p.hardware.reset();
    p.drivetrain.reset();
    p.localization.reset();
    p.description =
        std::string("in-process FAKE plugins: the real ones could not be loaded: ") + e.what();
  }
}

}  // namespace swivel::bench
