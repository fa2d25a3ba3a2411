#pragma once
// Car-like kinematics of the magnetic-ruler paper, eq. 1-2. Written once, used by the
// simulator's dead reckoning, every filter and the tests.
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/types.hpp"

namespace lcmloc::core {

/// eq. 2 from the steering's tangent: heading increment of a car with wheelbase L [m] for a
/// distance ds [m] at a steering angle whose tangent is tan_psi (see TanCache).
inline double headingIncrementOfTan(double ds, double tan_psi, double wheelbase) { return ds * tan_psi / wheelbase; }
/// eq. 2: the same at steering psi [rad].
inline double headingIncrement(double ds, double psi, double wheelbase) {
  return headingIncrementOfTan(ds, std::tan(psi), wheelbase);
}

/// eq. 1: pose after moving ds along an arc that turns dtheta (midpoint heading).
/// Returned theta is wrapped to (-pi, pi].
Pose propagatePose(const Pose& pose, double ds, double dtheta);
/// The same with the midpoint heading's cosine and sine taken near `mid` (SinCosNear::sinCos):
/// for the sigma points of a UKF, whose midpoint headings lie around the mean's.
inline Pose propagatePose(const Pose& pose, double ds, double dtheta, const SinCosNear& mid) {
  double s, c;
  mid.sinCos(pose.z() + 0.5 * dtheta, s, c);
  return Pose(pose.x() + ds * c, pose.y() + ds * s, wrapAngle(pose.z() + dtheta));
}

/// Heading increment of an odometry input: eq. 2 from steering when has_steering,
/// otherwise delta_theta as given. (Inline: called once per odometry message per filter.)
inline double headingIncrement(const OdometryInput& odo, double wheelbase) {
  return odo.has_steering ? headingIncrement(odo.delta_s, odo.steering, wheelbase) : odo.delta_theta;
}

/// std::tan of the steering angles met lately, remembered: a steering encoder (or a digitized
/// potentiometer) gives few distinct angles, each again and again (the benchmark's hour of
/// driving: 381 of them in 360,000 increments, a new value in 93 % of the increments). A table
/// of kSize entries, each found by the angle's bits, holds the last angle mapped to it and its
/// tangent: a hit returns exactly what std::tan returned for it, a miss calls std::tan.
class TanCache {
 public:
  double operator()(double a) {
    uint64_t bits;
    std::memcpy(&bits, &a, sizeof bits);
    Entry& e = table_[(bits * 0x9E3779B97F4A7C15ull) >> (64 - kBits)];
    if (e.bits != bits) {
      e.bits = bits;
      e.tan = std::tan(a);
    }
    return e.tan;
  }

 private:
  static constexpr int kBits = 8;
  static constexpr std::size_t kSize = std::size_t{1} << kBits;  ///< 4 KiB
  struct Entry {
    uint64_t bits = 0;  ///< +0.0, whose tangent is +0.0
    double tan = 0.0;
  };
  std::array<Entry, kSize> table_{};
};

/// headingIncrement(odo, wheelbase) with the steering's tangent from `tan`: the same value.
inline double headingIncrement(const OdometryInput& odo, double wheelbase, TanCache& tan) {
  return odo.has_steering ? headingIncrementOfTan(odo.delta_s, tan(odo.steering), wheelbase) : odo.delta_theta;
}

}  // namespace lcmloc::core
