// SPDX-License-Identifier: Apache-2.0
#pragma once
// LCALSM of docs/methods.md §2: least-squares line compensation of stored E/G positions.
// Plain maths: no threads, no YAML, fixed-capacity storage (no allocation); every method
// is real-time safe.
//
// Storage: the loop offers every E/G pose; one is stored when the path length since the
// last stored sample reaches sample_distance_m (default 0.02 m, about a ROS odometry rate
// of 15 Hz at the docent's 0.3 m/s) or, when sample_period_s is set, that much time has
// passed. Only the newest k samples can still change, so a ring of kMaxWindowPoints holds
// them.
//
// mode paper (faithful): on each stored sample n >= k, the window of the k newest stored
// points [n-k+1, n] (the paper's i .. i+k with i = n-k+1) is fitted with y = a x + b by the
// normal equations solved with Cramer's rule, every point of the window is replaced by its
// fitted value (y_j <- a x_j + b), and i slides by one. Points keep the compensation they
// received in earlier windows, as in the paper. Near-vertical windows (|dx| < |dy| between
// the window's first and last points) fit x = a y + b instead.
//
// mode heading_aligned (variant): the straight line is the one the robot set out on: through
// the first stored point of the current straight segment, along the E/G heading there. The
// newest point is projected onto it. This is the paper's straight-line assumption made
// explicit; it removes slow lateral drift that a k-point fit cannot see, and it is only right
// when the robot really drives straight: once the E/G heading differs from the segment's by
// more than max_window_heading_change_rad (a gentle curve that no single window shows as a
// turn), a new segment starts at the newest point.
//
// Turns: when the E/G heading changes by more than max_window_heading_change_rad across the
// k newest stored points, nothing is fitted (the window is not a line); the output is then
// the raw E/G and a new straight segment starts once the heading settles.
//
// Real-time output: the current E/G pose shifted by the correction of the newest stored
// sample (its compensated minus its raw position). It is therefore current (no window
// delay); the fully compensated point, final only once it leaves the window, is available
// through point() for offline use.

#include <array>
#include <cstddef>

#include "swivel/types.hpp"

namespace swivel::localization {

inline constexpr std::size_t kMaxWindowPoints = 64;

enum class LsmMode : unsigned char { kPaper = 0, kHeadingAligned = 1 };

struct LsmConfig {
  LsmMode mode = LsmMode::kPaper;
  std::size_t window_points = 10;              ///< k, in [3, kMaxWindowPoints]
  double sample_distance_m = 0.02;             ///< 0 disables distance decimation
  double sample_period_s = 0.0;                ///< 0 disables time decimation
  double max_window_heading_change_rad = 0.1;  ///< turn detection across the window
};

struct Point2 {
  double x_m = 0.0;
  double y_m = 0.0;
};

/// Least-squares line over `count` points: y = a x + b, or x = a y + b when `x_of_y`.
struct LineFit {
  bool ok = false;  ///< false when the normal equations are singular (all abscissae equal)
  bool x_of_y = false;
  double a = 0.0;
  double b = 0.0;
};

/// Fits y = a x + b (or x = a y + b when `x_of_y`) to points[0..count) through the normal
/// equations [Sxx Sx; Sx n] [a; b] = [Sxy; Sy] solved by Cramer's rule (eq. (8)-(14)),
/// in coordinates relative to points[0] (same line, fewer cancelled digits), then shifted
/// back. Real-time safe.
LineFit fit_line(const Point2* points, std::size_t count, bool x_of_y) noexcept;

class Lcalsm {
 public:
  Lcalsm() noexcept = default;

  /// Invalid values are clamped into range (the plugin validates before calling).
  void configure(const LsmConfig& config) noexcept;
  [[nodiscard]] const LsmConfig& config() const noexcept { return config_; }

  /// Forgets every stored sample.
  void reset() noexcept;

  /// Offers the E/G pose of one cycle: `yaw_unwrapped_rad` continuous across turns,
  /// `distance_m` the E/G path length so far, `stamp_s` the cycle time. Stores and
  /// compensates per the decimation. Returns true when a sample was stored.
  bool push(const Pose2& eg, double yaw_unwrapped_rad, double distance_m, double stamp_s) noexcept;

  /// The real-time output for the current E/G pose `eg_now` (see the header comment).
  [[nodiscard]] Pose2 output(const Pose2& eg_now) const noexcept;

  /// Correction of the newest stored sample (compensated - raw), m.
  [[nodiscard]] Point2 correction() const noexcept { return correction_; }
  /// True when the newest window was a turn (nothing fitted).
  [[nodiscard]] bool in_turn() const noexcept { return in_turn_; }
  /// Stored samples still held (at most the window size).
  [[nodiscard]] std::size_t size() const noexcept { return held_; }
  /// Total samples stored since reset.
  [[nodiscard]] std::size_t stored() const noexcept { return stored_; }
  /// Held sample `age` (0 = newest) as currently compensated.
  [[nodiscard]] Point2 point(std::size_t age) const noexcept;

 private:
  [[nodiscard]] std::size_t slot(std::size_t age) const noexcept {
    return (head_ + kMaxWindowPoints - age) % kMaxWindowPoints;
  }
  void compensate_paper() noexcept;
  void compensate_heading_aligned(const Point2& raw, double yaw_rad) noexcept;

  LsmConfig config_{};
  std::array<Point2, kMaxWindowPoints> points_{};
  std::array<double, kMaxWindowPoints> yaws_{};
  std::size_t head_ = kMaxWindowPoints - 1;  // slot of the newest sample
  std::size_t held_ = 0;
  std::size_t stored_ = 0;
  bool has_last_ = false;
  double last_distance_m_ = 0.0;
  double last_stamp_s_ = 0.0;
  Point2 correction_{};
  bool in_turn_ = false;
  // heading_aligned: the current straight segment's anchor and direction.
  bool has_segment_ = false;
  Point2 anchor_{};
  double anchor_yaw_rad_ = 0.0;
};

}  // namespace swivel::localization
