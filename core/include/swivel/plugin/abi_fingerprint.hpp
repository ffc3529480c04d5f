// SPDX-License-Identifier: Apache-2.0
#pragma once
// The layout fingerprint of the plugin ABI (abi.hpp): every type that crosses the boundary
// between swiveld and a plugin, with its size and alignment as the including translation
// unit compiles it. A plugin's descriptor carries its own; the loader compares it with the
// host's and names the first type that differs.

#include <yaml-cpp/yaml.h>

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "swivel/plugin/abi.hpp"
#include "swivel/plugin/plugin_context.hpp"
#include "swivel/robot_model.hpp"
#include "swivel/types.hpp"

#ifndef _GLIBCXX_USE_CXX11_ABI
#define SWIVEL_CXX11_STRING_ABI 0u
#else
#define SWIVEL_CXX11_STRING_ABI static_cast<std::uint32_t>(_GLIBCXX_USE_CXX11_ABI)
#endif

namespace swivel {

template <class T>
constexpr SwivelAbiLayout abi_layout(const char* name) {
  return SwivelAbiLayout{name, static_cast<std::uint32_t>(sizeof(T)),
                         static_cast<std::uint32_t>(alignof(T))};
}

/// This translation unit's fingerprint (one static per library).
inline const SwivelAbiFingerprint* abi_fingerprint() {
  static constexpr std::array<SwivelAbiLayout, 13> kLayouts{
      abi_layout<Pose2>("Pose2"),
      abi_layout<Twist2>("Twist2"),
      abi_layout<PoseEstimate>("PoseEstimate"),
      abi_layout<MotionCaptureSample>("MotionCaptureSample"),
      abi_layout<HardwareState>("HardwareState"),
      abi_layout<ActuatorCommand>("ActuatorCommand"),
      abi_layout<OdometryIncrement>("OdometryIncrement"),
      abi_layout<ModuleState>("ModuleState"),
      abi_layout<RobotModel>("RobotModel"),
      abi_layout<PluginContext>("PluginContext"),
      abi_layout<YAML::Node>("YAML::Node"),
      abi_layout<std::string>("std::string"),
      abi_layout<std::vector<double>>("std::vector<double>"),
  };
  static constexpr SwivelAbiFingerprint kFingerprint{
      static_cast<std::uint32_t>(__GXX_ABI_VERSION), SWIVEL_CXX11_STRING_ABI,
      static_cast<std::uint32_t>(kLayouts.size()), kLayouts.data()};
  return &kFingerprint;
}

/// "" when `plugin` matches this translation unit's fingerprint, else what differs first,
/// e.g. "layout of HardwareState differs: 1240 bytes, alignment 8 in the plugin; 1232
/// bytes, alignment 8 here".
/// Host side (swivel_runtime, the loader): defined with the host's own view of the types.
std::string abi_fingerprint_difference(const SwivelAbiFingerprint* plugin);

}  // namespace swivel
