// SPDX-License-Identifier: Apache-2.0
#pragma once
// The hardware plugin's lifecycle calls made by the daemon off the loop
// (swivel/plugin/hardware.hpp): activate() at start-up and on a clear, deactivate() at
// shutdown, with the plugin's exceptions caught. Not real-time safe.

#include <string>

#include "swivel/plugin/hardware.hpp"

namespace swivel::daemon {

/// Hardware::activate(): "" when it succeeded, else why not (its last_error(), the text of
/// what it threw, or "no reason given").
std::string activate_hardware(Hardware& hardware);

/// Hardware::deactivate(), logged as done or failed with the reason; `plugin` names it.
/// False when it failed (the drives may not be off).
bool deactivate_hardware(Hardware& hardware, const std::string& plugin) noexcept;

}  // namespace swivel::daemon
