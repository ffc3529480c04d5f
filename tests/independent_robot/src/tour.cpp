// SPDX-License-Identifier: Apache-2.0
#include "swivel/independent/tour.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "angles.hpp"
#include "assignment.hpp"
#include "random_stream.hpp"

namespace swivel::independent {
namespace {

constexpr double kPi = std::numbers::pi;
// Beyond this distance from the start the tour heads back, to stay in a motion-capture room.
constexpr double kHomeRadiusM = 1.5;
// Turns to the left are more likely, so that rotation accumulates (gyro scale shows).
constexpr double kLeftTurnShare = 0.7;
constexpr double kHomingTurnRadps = 0.8;
constexpr double kFinalStopS = 2.5;

enum class Move {
  kStraight,
  kReverse,
  kArc,
  kTurn,
  kStop,
  kSpeedChange,
  kSideways,
  kDiagonal,
  kTranslateRotate,
};

std::vector<Move> deck_of(Robot robot, Steering steering) {
  using M = Move;
  if (robot == Robot::kDocent) {
    return {M::kStraight, M::kStraight, M::kReverse, M::kArc,        M::kArc,
            M::kTurn,     M::kTurn,     M::kStop,    M::kSpeedChange};
  }
  if (steering == Steering::kSelfAligning) {
    // Passive casters cannot be pushed straight across their wheels: no pure sideways
    // moves; diagonals stay within about 60 degrees of the heading and start from an arc.
    return {M::kStraight, M::kStraight, M::kArc,      M::kArc,  M::kTurn,
            M::kTurn,     M::kDiagonal, M::kDiagonal, M::kStop, M::kSpeedChange};
  }
  return {M::kStraight,        M::kSideways,        M::kSideways, M::kDiagonal, M::kDiagonal,
          M::kTranslateRotate, M::kTranslateRotate, M::kTurn,     M::kArc,      M::kStop,
          M::kSpeedChange};
}

class TourBuilder {
 public:
  TourBuilder(Robot robot, Steering steering, std::uint64_t seed, double duration_s)
      : robot_(robot), steering_(steering), duration_s_(duration_s), rng_(seed, kTourStream) {}

  std::vector<TourSegment> build() {
    add(kTourStandStillS + rng_.uniform(0.2, 1.0), 0.0, Twist{});
    std::vector<Move> deck;
    while (!full_ && t_ < duration_s_ - kFinalStopS - 1.5) {
      if (deck.empty()) deck = shuffled(deck_of(robot_, steering_));
      const Move move = deck.back();
      deck.pop_back();
      perform(move);
    }
    const double ramp = rng_.chance(0.5) ? 0.0 : 1.0;
    segments_.push_back(TourSegment{t_, ramp, Twist{}});
    return segments_;
  }

 private:
  std::vector<Move> shuffled(std::vector<Move> deck) {
    for (std::size_t i = deck.size(); i > 1; --i) {
      const auto j = static_cast<std::size_t>(rng_.integer(0, static_cast<int>(i) - 1));
      std::swap(deck[i - 1], deck[j]);
    }
    return deck;
  }

  // A speed change with the robot nearly at rest becomes a straight: one level deep.
  // NOLINTNEXTLINE(misc-no-recursion)
  void perform(Move move) {
    const bool holonomic = robot_ == Robot::kSwpc4 && steering_ == Steering::kPowered;
    switch (move) {
      case Move::kStraight:
        if (!holonomic) {
          face_home_if_far();
          add_motion(Twist{rng_.uniform(0.2, robot_ == Robot::kDocent ? 0.5 : 0.35), 0.0, 0.0});
        } else {
          add_motion(translation(far() ? home_bearing() : 0.0, rng_.uniform(0.15, 0.35)));
        }
        break;
      case Move::kReverse: add_motion(Twist{-rng_.uniform(0.1, 0.25), 0.0, 0.0}, 1.5, 3.0); break;
      case Move::kArc: {
        if (!holonomic) face_home_if_far();
        const double v =
            robot_ == Robot::kDocent ? rng_.uniform(0.15, 0.4) : rng_.uniform(0.15, 0.3);
        const double w = turn_sign() * (robot_ == Robot::kDocent ? rng_.uniform(0.3, 0.9)
                                                                 : rng_.uniform(0.3, 0.7));
        add_motion(Twist{v, 0.0, w}, 2.5, 5.0);
        break;
      }
      case Move::kTurn: {
        const double w = turn_sign() * (robot_ == Robot::kDocent ? rng_.uniform(0.5, 1.0)
                                                                 : rng_.uniform(0.4, 0.8));
        const double angle = rng_.uniform(1.5, 4.0);
        add(std::abs(angle / w), transition(0.6), Twist{0.0, 0.0, w});
        break;
      }
      case Move::kStop: add(rng_.uniform(1.0, 2.5), transition(1.0), Twist{}); break;
      case Move::kSpeedChange: {
        const double speed = std::hypot(last_.vx_mps, last_.vy_mps);
        if (speed < 0.05) {
          perform(Move::kStraight);
          break;
        }
        double next = speed;
        while (std::abs(next - speed) < 0.08) next = rng_.uniform(0.12, 0.35);
        Twist t = last_;
        t.vx_mps *= next / speed;
        t.vy_mps *= next / speed;
        add_motion(t, 2.0, 4.0);
        break;
      }
      case Move::kSideways: {
        const double side = far() ? (std::sin(home_bearing()) >= 0.0 ? 1.0 : -1.0)
                                  : (rng_.chance(0.5) ? 1.0 : -1.0);
        add_motion(Twist{0.0, side * rng_.uniform(0.12, 0.3), 0.0});
        break;
      }
      case Move::kDiagonal: {
        double direction = 0.0;
        if (holonomic) {
          direction = far() ? home_bearing() + rng_.uniform(-0.4, 0.4) : rng_.uniform(-kPi, kPi);
        } else {
          face_home_if_far();
          // Passive casters that have run straight are parallel and nothing pushes the body
          // across them; a short arc first spreads them so that the diagonal can start.
          add(rng_.uniform(1.0, 2.0), 0.0, Twist{0.2, 0.0, turn_sign() * 0.6});
          direction = (rng_.chance(0.5) ? 1.0 : -1.0) * rng_.uniform(0.3, 1.0);
        }
        add_motion(translation(direction, rng_.uniform(0.15, 0.3)));
        break;
      }
      case Move::kTranslateRotate: {
        const double direction = far() ? home_bearing() : rng_.uniform(-kPi, kPi);
        Twist t = translation(direction, rng_.uniform(0.1, 0.25));
        t.wz_radps = turn_sign() * rng_.uniform(0.3, 0.6);
        add_motion(t, 2.0, 4.5);
        break;
      }
    }
  }

  [[nodiscard]] static Twist translation(double direction_rad, double speed) {
    return Twist{speed * std::cos(direction_rad), speed * std::sin(direction_rad), 0.0};
  }

  double turn_sign() { return rng_.chance(kLeftTurnShare) ? 1.0 : -1.0; }

  // Half the changes are steps (the limiter acts), half ramps of up to `longest` seconds
  // (a gentle one may stay within the limits).
  double transition(double longest = 2.5) {
    return rng_.chance(0.5) ? 0.0 : rng_.uniform(std::min(0.5, longest), longest);
  }

  [[nodiscard]] bool far() const { return std::hypot(pose_.x_m, pose_.y_m) > kHomeRadiusM; }

  // Direction of the start point in the robot frame.
  [[nodiscard]] double home_bearing() const {
    return wrap_angle(std::atan2(-pose_.y_m, -pose_.x_m) - pose_.yaw_rad);
  }

  void face_home_if_far() {
    if (!far()) return;
    const double turn = home_bearing();
    if (std::abs(turn) < 0.3) return;
    const double w = turn > 0.0 ? kHomingTurnRadps : -kHomingTurnRadps;
    add(std::abs(turn / w), 0.0, Twist{0.0, 0.0, w});
  }

  void add_motion(const Twist& target, double shortest = 2.5, double longest = 6.0) {
    const double ramp = transition();
    add(ramp + rng_.uniform(shortest, longest), ramp, target);
  }

  // Appends a segment at the current time and follows the ideal commanded pose over it.
  void add(double hold_s, double ramp_s, const Twist& target) {
    hold_s = std::min(hold_s, duration_s_ - kFinalStopS - t_);
    if (hold_s <= 0.2) {
      full_ = true;  // no room left: the final stop follows
      return;
    }
    ramp_s = std::min(ramp_s, hold_s);
    segments_.push_back(TourSegment{t_, ramp_s, target});
    constexpr double kStepS = 0.01;
    const int steps = static_cast<int>(std::ceil(hold_s / kStepS));
    const double h = hold_s / steps;
    for (int k = 0; k < steps; ++k) {
      const Twist v = setpoint_at(segments_, t_ + (k + 0.5) * h);
      const double yaw = pose_.yaw_rad + 0.5 * h * v.wz_radps;
      pose_.x_m += h * (v.vx_mps * std::cos(yaw) - v.vy_mps * std::sin(yaw));
      pose_.y_m += h * (v.vx_mps * std::sin(yaw) + v.vy_mps * std::cos(yaw));
      pose_.yaw_rad += h * v.wz_radps;
    }
    t_ += hold_s;
    last_ = target;
  }

  Robot robot_;
  Steering steering_;
  double duration_s_;
  RandomStream rng_;
  std::vector<TourSegment> segments_;
  Pose pose_;
  Twist last_;
  double t_ = 0.0;
  bool full_ = false;
};

bool finite(const Twist& t) {
  return std::isfinite(t.vx_mps) && std::isfinite(t.vy_mps) && std::isfinite(t.wz_radps);
}

}  // namespace

Twist setpoint_at(const std::vector<TourSegment>& tour, double t_s) {
  const auto after = std::upper_bound(tour.begin(), tour.end(), t_s,
                                      [](double t, const TourSegment& s) { return t < s.start_s; });
  if (after == tour.begin()) return Twist{};
  const TourSegment& seg = *(after - 1);
  const Twist from = after - 1 == tour.begin() ? Twist{} : (after - 2)->target;
  if (seg.ramp_s <= 0.0 || t_s >= seg.start_s + seg.ramp_s) return seg.target;
  const double f = (t_s - seg.start_s) / seg.ramp_s;
  return Twist{from.vx_mps + f * (seg.target.vx_mps - from.vx_mps),
               from.vy_mps + f * (seg.target.vy_mps - from.vy_mps),
               from.wz_radps + f * (seg.target.wz_radps - from.wz_radps)};
}

std::vector<TourSegment> make_tour(Robot robot, Steering steering, std::uint64_t seed,
                                   double duration_s) {
  return TourBuilder(robot, steering, seed, duration_s).build();
}

void validate_tour(Robot robot, const std::vector<TourSegment>& tour) {
  for (std::size_t i = 0; i < tour.size(); ++i) {
    const TourSegment& s = tour[i];
    const std::string where = "tour segment " + std::to_string(i + 1) + ": ";
    if (!std::isfinite(s.start_s) || s.start_s < 0.0) {
      throw std::invalid_argument(where + "start_s=" + format_number(s.start_s) +
                                  ": expected a finite time >= 0");
    }
    if (i > 0 && !(s.start_s > tour[i - 1].start_s)) {
      throw std::invalid_argument(where + "start_s=" + format_number(s.start_s) +
                                  ": expected after the previous segment's start");
    }
    if (!std::isfinite(s.ramp_s) || s.ramp_s < 0.0 ||
        (i + 1 < tour.size() && s.start_s + s.ramp_s > tour[i + 1].start_s)) {
      throw std::invalid_argument(where + "ramp_s=" + format_number(s.ramp_s) +
                                  ": expected >= 0 and ending before the next segment");
    }
    if (!finite(s.target) || std::abs(s.target.vx_mps) > 5.0 || std::abs(s.target.vy_mps) > 5.0 ||
        std::abs(s.target.wz_radps) > 10.0) {
      throw std::invalid_argument(where + "target: expected finite speeds up to 5 m/s, 10 rad/s");
    }
    if (robot == Robot::kDocent && s.target.vy_mps != 0.0) {
      throw std::invalid_argument(where + "vy_mps=" + format_number(s.target.vy_mps) +
                                  ": the docent cannot move sideways");
    }
  }
}

}  // namespace swivel::independent
