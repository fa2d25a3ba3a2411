#include "lcmloc/core/vehicle_model.hpp"

#include <cmath>

#include "lcmloc/core/angles.hpp"

namespace lcmloc::core {

Pose propagatePose(const Pose& pose, double ds, double dtheta) {
  const double mid = pose.z() + 0.5 * dtheta;
  return Pose(pose.x() + ds * std::cos(mid), pose.y() + ds * std::sin(mid),
              wrapAngle(pose.z() + dtheta));
}

}  // namespace lcmloc::core
