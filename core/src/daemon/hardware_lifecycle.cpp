// SPDX-License-Identifier: Apache-2.0
#include "hardware_lifecycle.hpp"

#include <spdlog/spdlog.h>

#include <exception>

namespace swivel::daemon {

std::string activate_hardware(Hardware& hardware) {
  try {
    if (hardware.activate() == Status::kOk) return "";
    const std::string reason = hardware.last_error();
    return reason.empty() ? "no reason given" : reason;
  } catch (const std::exception& e) {
    return e.what();
  } catch (...) {
    return "unknown exception";
  }
}

bool deactivate_hardware(Hardware& hardware, const std::string& plugin) noexcept {
  try {
    std::string failure;
    try {
      if (hardware.deactivate() != Status::kOk) {
        failure = hardware.last_error();
        if (failure.empty()) failure = "no reason given";
      }
    } catch (const std::exception& e) {
      failure = e.what();
    }
    if (failure.empty()) {
      spdlog::info("hardware {} deactivated", plugin);
      return true;
    }
    spdlog::error("hardware {} failed to deactivate: {}", plugin, failure);
  } catch (...) {
  }
  return false;
}

}  // namespace swivel::daemon
