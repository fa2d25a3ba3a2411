#pragma once
// Composition of odometry increments for the batched time update (fusion.output_every > 1).
// The increments of eq. 1-2 (arc of length ds turning dtheta, midpoint heading) are composed
// in the body frame of the pose where the batch starts: dead reckoning from the origin. Moving
// a pose by the composed increment is, for the mean, exactly the same as moving it by each
// increment in turn (SE(2) composition; equal up to floating-point rounding).
#include <cmath>
#include <cstdint>

#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/types.hpp"

namespace lcmloc::core {

struct OdometryBatch {
  double dx = 0.0, dy = 0.0;  ///< translation, body frame of the batch's start pose [m]
  double dtheta = 0.0;        ///< heading change (not wrapped) [rad]
  double distance = 0.0;      ///< sum of |ds| (for the process noise of the travel) [m]
  int steps = 0;              ///< increments composed
  int64_t utime = 0;          ///< utime of the last increment

  /// Appends one increment (ds, dth) of eq. 1 taken at the end of the batch so far.
  void add(double ds, double dth, int64_t t) {
    const double mid = dtheta + 0.5 * dth;
    dx += ds * std::cos(mid);
    dy += ds * std::sin(mid);
    dtheta += dth;
    distance += std::abs(ds);
    ++steps;
    utime = t;
  }
  bool empty() const { return steps == 0; }
  void clear() { *this = OdometryBatch{}; }

  /// pose moved by the composed increment; theta wrapped to (-pi, pi].
  Pose apply(const Pose& pose) const {
    const double c = std::cos(pose.z()), s = std::sin(pose.z());
    return Pose(pose.x() + c * dx - s * dy, pose.y() + s * dx + c * dy, wrapAngle(pose.z() + dtheta));
  }
};

}  // namespace lcmloc::core
