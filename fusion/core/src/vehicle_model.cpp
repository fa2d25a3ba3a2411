#include "lcmloc/core/vehicle_model.hpp"

#include <cmath>

#include "lcmloc/core/angles.hpp"

namespace lcmloc::core {

double headingIncrement(double ds, double psi, double wheelbase) {
  return ds * std::tan(psi) / wheelbase;
}

Pose propagatePose(const Pose& pose, double ds, double dtheta) {
  const double mid = pose.z() + 0.5 * dtheta;
  return Pose(pose.x() + ds * std::cos(mid), pose.y() + ds * std::sin(mid),
              wrapAngle(pose.z() + dtheta));
}

double headingIncrement(const OdometryInput& odo, double wheelbase) {
  return odo.has_steering ? headingIncrement(odo.delta_s, odo.steering, wheelbase)
                          : odo.delta_theta;
}

}  // namespace lcmloc::core
