// SPDX-License-Identifier: Apache-2.0
#pragma once
// swiveld's periodic status lines on stdout ("t=1.20s pose x=0.240 m y=0.000 m yaw=0.000 rad
// | ... | mode velocity fault none | ..."), parsed for the pose and its loop time.

#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

namespace swivel::test {

struct StatusLine {
  double t_s = 0.0, x_m = 0.0, y_m = 0.0, yaw_rad = 0.0;
  std::string line;
};

/// The status lines in `out`, in order; other output is skipped.
inline std::vector<StatusLine> status_lines(const std::string& out) {
  std::vector<StatusLine> lines;
  std::istringstream in(out);
  for (std::string line; std::getline(in, line);) {
    StatusLine s;
    // The count of conversions tells a status line from other output.
    // NOLINTNEXTLINE(cert-err34-c)
    if (std::sscanf(line.c_str(), "t=%lfs pose x=%lf m y=%lf m yaw=%lf rad", &s.t_s, &s.x_m, &s.y_m,
                    &s.yaw_rad) == 4) {
      s.line = line;
      lines.push_back(s);
    }
  }
  return lines;
}

}  // namespace swivel::test
