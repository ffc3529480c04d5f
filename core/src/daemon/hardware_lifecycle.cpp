// SPDX-License-Identifier: Apache-2.0
#include "hardware_lifecycle.hpp"

#include <spdlog/spdlog.h>

#include <array>
#include <cstdio>
#include <exception>
#include <typeinfo>

#include "swivel/rt/exception_text.hpp"

namespace swivel::daemon {
namespace {

using ExceptionText = std::array<char, 512>;

// Calls `lifecycle_call` (activate or deactivate): "" when it returned kOk, else why not: the
// plugin's last_error(), or the type and message of what it threw.
template <class Call>
std::string failure_of(Hardware& hardware, Call&& lifecycle_call) {
  ExceptionText text{};
  try {
    if (lifecycle_call() == Status::kOk) return "";
    const std::string reason = hardware.last_error();
    return reason.empty() ? "no reason given" : reason;
  } catch (const std::exception& e) {
    return std::string("threw ") + rt::describe_exception(&typeid(e), e.what(), text);
  } catch (...) {
    return std::string("threw ") +
           rt::describe_exception(rt::current_exception_type(), nullptr, text);
  }
}

}  // namespace

std::string activate_hardware(Hardware& hardware) {
  return failure_of(hardware, [&] { return hardware.activate(); });
}

bool deactivate_hardware(Hardware& hardware, const std::string& plugin) noexcept {
  try {
    const std::string failure = failure_of(hardware, [&] { return hardware.deactivate(); });
    if (failure.empty()) {
      spdlog::info("hardware {} deactivated", plugin);
      return true;
    }
    spdlog::error("hardware {} failed to deactivate: {}", plugin, failure);
  } catch (...) {
    // Only the logging can get here (out of memory at shutdown): say so without allocating.
    (void)std::fputs("swiveld: hardware deactivation failed, and so did logging it\n", stderr);
  }
  return false;
}

}  // namespace swivel::daemon
