#pragma once
// Car-like kinematics of the magnetic-ruler paper, eq. 1-2. Written once, used by the
// simulator's dead reckoning, every filter and the tests.
#include <cmath>

#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/types.hpp"

namespace lcmloc::core {

/// eq. 2: heading increment of a car with wheelbase L [m] for a distance ds [m] at steering psi [rad].
inline double headingIncrement(double ds, double psi, double wheelbase) { return ds * std::tan(psi) / wheelbase; }

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

}  // namespace lcmloc::core
