// SPDX-License-Identifier: Apache-2.0
#pragma once
// Swivel's version: the project's (CMake project(VERSION)) and, when built from a git
// checkout, `git describe` of the source tree when the build was configured.

#include <string>
#include <string_view>

namespace swivel {

/// The project version, e.g. "0.1.0".
std::string_view version() noexcept;

/// `git describe --tags --always --dirty` at configure time, e.g. "b21236c-dirty"; empty
/// when the source tree was not a git checkout or git was not found.
std::string_view git_describe() noexcept;

/// What `--version` prints: "<program> <version>", followed by " (git <describe>)" when
/// git_describe() is known.
std::string version_line(std::string_view program);

}  // namespace swivel
