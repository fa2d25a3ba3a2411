#include "lcmloc/core/ruler_model.hpp"

#include <cmath>

#include "lcmloc/core/angles.hpp"

namespace lcmloc::core {

Vec2 rulerObservation(double lateral_offset, double ruler_offset_l1) {
  return Vec2(std::sqrt(lateral_offset * lateral_offset + ruler_offset_l1 * ruler_offset_l1),
              std::atan2(lateral_offset, ruler_offset_l1));
}

Vec2 predictRangeBearing(const Pose& pose, double xm, double ym) {
  const double dx = xm - pose.x(), dy = ym - pose.y();
  return Vec2(std::sqrt(dx * dx + dy * dy), wrapAngle(std::atan2(dy, dx) - pose.z()));
}

Vec2 markerInBody(const Pose& pose, double xm, double ym) {
  const double dx = xm - pose.x(), dy = ym - pose.y();
  const double c = std::cos(pose.z()), s = std::sin(pose.z());
  return Vec2(c * dx + s * dy, -s * dx + c * dy);
}

}  // namespace lcmloc::core
