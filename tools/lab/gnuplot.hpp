// SPDX-License-Identifier: Apache-2.0
#pragma once
// Running gnuplot on a script the reproductions write next to their data.

#include <filesystem>
#include <string>

namespace swivel::lab {

/// A path as a gnuplot string literal ('...', quotes doubled).
std::string gnuplot_quote(const std::filesystem::path& path);

/// Runs gnuplot on `script`. @throws std::runtime_error naming the script when it fails
/// (or gnuplot is missing); `written` says what the caller has already written.
void run_gnuplot(const std::filesystem::path& script, const std::string& written);

}  // namespace swivel::lab
