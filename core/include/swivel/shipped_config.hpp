// SPDX-License-Identifier: Apache-2.0
#pragma once
// Where Swivel's shipped configuration is (robots/, dds/, swiveld.yaml): the source tree's
// config/ for an executable in the build tree it was built in, otherwise the installed copy
// in <sysconfdir>/swivel. Tools use it for their defaults, so that they find the same files
// whatever the working directory.

#include <filesystem>
#include <string_view>

namespace swivel {

/// Not real-time safe. The shipped configuration directory for the running executable
/// (/proc/self/exe).
std::filesystem::path shipped_config_dir();

/// Not real-time safe. The same decision for `executable`: the source tree's config/ when
/// it lies under this build's binary directory, else <sysconfdir>/swivel.
std::filesystem::path shipped_config_dir_for(const std::filesystem::path& executable);

/// Not real-time safe. `relative` (e.g. "robots/docent.yaml") in shipped_config_dir().
std::filesystem::path shipped_config_file(std::string_view relative);

}  // namespace swivel
