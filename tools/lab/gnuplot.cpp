// SPDX-License-Identifier: Apache-2.0
#include "gnuplot.hpp"

#include <cstdlib>
#include <stdexcept>

namespace swivel::lab {

std::string gnuplot_quote(const std::filesystem::path& path) {
  std::string out = "'";
  for (const char c : path.string()) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

void run_gnuplot(const std::filesystem::path& script, const std::string& written) {
  std::string shell = "'";
  for (const char c : script.string())
    shell += c == '\'' ? std::string("'\\''") : std::string(1, c);
  const std::string cmd = "gnuplot " + shell + "' 2>&1";
  // The script's path is quoted for the shell, which sends gnuplot's errors to its output.
  if (std::system(cmd.c_str()) != 0) {  // NOLINT(cert-env33-c)
    throw std::runtime_error("gnuplot failed on " + script.string() + " (is gnuplot installed?); " +
                             written + " were written");
  }
}

}  // namespace swivel::lab
