// SPDX-License-Identifier: Apache-2.0
#include "planner.hpp"

#include <algorithm>
#include <cmath>

#include "random.hpp"

namespace swivel::second {
namespace {

constexpr double kPi = 3.14159265358979323846;

double wrap(double a) {
  while (a > kPi) a -= 2 * kPi;
  while (a <= -kPi) a += 2 * kPi;
  return a;
}

double clamp(double v, double lim) { return std::clamp(v, -lim, lim); }

Segment waypoint(Stream& rng, const double start[3], bool swpc) {
  Segment s;
  s.kind = Segment::Kind::kGoto;
  s.x_m = start[0] + rng.uniform(-1.3, 1.3);
  s.y_m = start[1] + rng.uniform(-1.3, 1.3);
  s.yaw_rad = swpc ? rng.uniform(-kPi, kPi) : 0.0;
  return s;
}

Segment circle(Stream& rng, const Design& d, bool crab) {
  Segment s;
  s.kind = crab ? Segment::Kind::kCrabCircle : Segment::Kind::kCircle;
  static constexpr double kRadii[] = {0.25, 0.4, 0.7, 1.1};
  s.radius_m = kRadii[rng.integer(0, 3)];
  const double way = rng.chance(0.5) ? 1.0 : -1.0;
  s.angle_rad = way * rng.uniform(1.0, 2.2) * kPi;
  s.speed =
      std::min(d.max_speed_mps, 0.8 * d.max_yaw_rate_radps * s.radius_m) * rng.uniform(0.6, 1.0);
  return s;
}

Segment spot_turn(Stream& rng, const Design& d) {
  Segment s;
  s.kind = Segment::Kind::kSpotTurn;
  s.angle_rad = (rng.chance(0.5) ? 1.0 : -1.0) * rng.uniform(0.5, 2.0) * kPi;
  s.speed = d.max_yaw_rate_radps * rng.uniform(0.5, 1.0);
  return s;
}

Segment pause(Stream& rng) {
  Segment s;
  s.duration_s = rng.uniform(0.3, 1.5);
  return s;
}

}  // namespace

Planner::Planner(const Design& design, Script script, std::uint64_t seed, const double start[3],
                 double duration_s)
    : design_(design), duration_s_(duration_s) {
  Stream rng(seed, kScriptStream);
  const bool swpc = design.drive == Drive::kSwpc;
  Segment first;
  first.duration_s = 2.0;  // at rest first
  segments_.push_back(first);
  // Enough segments for any duration; the run's end cuts them.
  for (int i = 0; i < 200; ++i) {
    Script kind = script;
    if (script == Script::kMixed) kind = static_cast<Script>(rng.integer(0, 2));
    switch (kind) {
      case Script::kWaypoints:
        segments_.push_back(waypoint(rng, start, swpc));
        if (rng.chance(0.3)) segments_.push_back(pause(rng));
        break;
      case Script::kCircles:
        segments_.push_back(circle(rng, design, swpc && rng.chance(0.4)));
        segments_.push_back(waypoint(rng, start, swpc));  // back towards the start
        break;
      case Script::kSpotTurns:
      case Script::kMixed:
        segments_.push_back(spot_turn(rng, design));
        if (rng.chance(0.5)) segments_.push_back(pause(rng));
        if (rng.chance(0.6)) segments_.push_back(waypoint(rng, start, swpc));
        break;
    }
  }
}

void Planner::next_segment(double t_s) {
  ++current_;
  segment_start_s_ = t_s;
}

void Planner::goto_command(const Segment& s, const double pose[3]) {
  const double dx = s.x_m - pose[0];
  const double dy = s.y_m - pose[1];
  const double dist = std::hypot(dx, dy);
  const double c = std::cos(pose[2]);
  const double sn = std::sin(pose[2]);
  if (design_.drive == Drive::kDifferential) {
    const double e = wrap(std::atan2(dy, dx) - pose[2]);
    if (std::abs(e) > 0.35) {  // turn first
      cmd_[0] = 0.0;
      cmd_[2] = clamp(2.0 * e, design_.max_yaw_rate_radps);
    } else {
      cmd_[0] = std::min(design_.max_speed_mps, 0.9 * dist);
      cmd_[2] = clamp(2.5 * e, design_.max_yaw_rate_radps);
    }
    cmd_[1] = 0.0;
    return;
  }
  const double speed = std::min(design_.max_speed_mps, 0.9 * dist);
  const double vx_w = dist > 1e-9 ? speed * dx / dist : 0.0;
  const double vy_w = dist > 1e-9 ? speed * dy / dist : 0.0;
  cmd_[0] = c * vx_w + sn * vy_w;
  cmd_[1] = -sn * vx_w + c * vy_w;
  cmd_[2] = clamp(1.5 * wrap(s.yaw_rad - pose[2]), design_.max_yaw_rate_radps);
}

void Planner::update(double t_s, const double pose[3]) {
  target(t_s, pose);
  // The user's side eases its commands in: casters that must swing round before they can
  // roll the new way are given the time to (a command that asks more makes them scrub).
  // Casters (swpc) get a gentler ramp than wheels on a fixed axle.
  const double gentle = design_.drive == Drive::kSwpc ? kCasterEaseShare : 1.0;
  const double step[3] = {gentle * kEaseLinearMps2 * kPeriodS, gentle * kEaseLinearMps2 * kPeriodS,
                          gentle * kEaseAngularRadps2 * kPeriodS};
  for (int a = 0; a < 3; ++a) {
    eased_[a] += std::clamp(cmd_[a] - eased_[a], -step[a], step[a]);
    cmd_[a] = eased_[a];
  }
}

void Planner::target(double t_s, const double pose[3]) {
  cmd_[0] = cmd_[1] = cmd_[2] = 0.0;
  if (t_s >= duration_s_ - 3.0 || current_ >= segments_.size()) return;  // at rest at the end
  for (int guard = 0; guard < 4 && current_ < segments_.size(); ++guard) {
    const Segment& s = segments_[current_];
    const double elapsed = t_s - segment_start_s_;
    switch (s.kind) {
      case Segment::Kind::kPause:
        if (elapsed >= s.duration_s) {
          next_segment(t_s);
          continue;
        }
        return;
      case Segment::Kind::kGoto: {
        const double dist = std::hypot(s.x_m - pose[0], s.y_m - pose[1]);
        const double yaw_error =
            design_.drive == Drive::kSwpc ? std::abs(wrap(s.yaw_rad - pose[2])) : 0.0;
        if ((dist < 0.04 && yaw_error < 0.05) || elapsed > 25.0) {
          next_segment(t_s);
          continue;
        }
        goto_command(s, pose);
        return;
      }
      case Segment::Kind::kCircle:
      case Segment::Kind::kCrabCircle: {
        const double rate = s.speed / s.radius_m;
        const double travelled = rate * elapsed;
        if (travelled >= std::abs(s.angle_rad)) {
          next_segment(t_s);
          continue;
        }
        const double way = s.angle_rad > 0 ? 1.0 : -1.0;
        if (s.kind == Segment::Kind::kCircle) {
          cmd_[0] = s.speed;
          cmd_[2] = way * rate;
        } else {  // translate along a circle with the body's yaw held
          const double a = way * travelled;
          cmd_[0] = s.speed * std::cos(a);
          cmd_[1] = s.speed * std::sin(a);
        }
        return;
      }
      case Segment::Kind::kSpotTurn: {
        if (elapsed * s.speed >= std::abs(s.angle_rad)) {
          next_segment(t_s);
          continue;
        }
        cmd_[2] = s.angle_rad > 0 ? s.speed : -s.speed;
        return;
      }
    }
  }
}

}  // namespace swivel::second
