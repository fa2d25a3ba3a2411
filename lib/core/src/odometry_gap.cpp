// The odometry-gap bridge shared by the filters (docs/odometry_gap.md): the motion no increment
// covers, at the speed and yaw rate before the gap, through each filter's own motion model
// (predict), and the covariance of what that constant-velocity bridge does not know.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "lcmloc/core/filter.hpp"

namespace lcmloc::core {

OdometryInput bridgeIncrement(const OdometryGap& gap) {
  OdometryInput b;
  b.utime = gap.to_utime;
  const double g = std::clamp(gap.seconds, 0.0, kMaxBridgeSeconds);
  b.delta_s = gap.speed * g;
  b.has_steering = gap.has_steering;
  b.steering = gap.steering;
  b.delta_theta = gap.yaw_rate * g;
  return b;
}

Mat3 bridgeNoise(const OdometryGap& gap, double theta) {
  const double g = gap.seconds > 0 ? gap.seconds : 0.0;
  const double v = std::abs(gap.speed);
  // Body frame (along, across, heading). A speed change at accel_std over the gap moves the
  // vehicle accel_std g^2 / 2 along its track; a yaw rate off by yaw_rate_std turns the heading
  // by yaw_rate_std g and, integrated at speed v, moves it v yaw_rate_std g^2 / 2 across.
  const double cap = gap.max_position_std;
  const double along = std::min(0.5 * gap.accel_std * g * g, cap);
  const double head = std::min(gap.yaw_rate_std * g, kLockoutMaxHeadingStd);
  const double across = std::min(0.5 * v * g * head, cap);
  Mat3 B = Mat3::Zero();
  B(0, 0) = along * along;
  B(1, 1) = across * across;
  B(2, 2) = head * head;
  B(1, 2) = B(2, 1) = across * head;
  Mat3 T = Mat3::Identity();
  const double c = std::cos(theta), s = std::sin(theta);
  T(0, 0) = c;
  T(0, 1) = -s;
  T(1, 0) = s;
  T(1, 1) = c;
  return T * B * T.transpose();
}

double positionSigma(const FilterState& s) {
  const double a = s.P(0, 0), b = s.P(0, 1), d = s.P(1, 1);
  const double m = 0.5 * (a + d), r = std::sqrt(0.25 * (a - d) * (a - d) + b * b);
  return std::sqrt(std::max(m + r, 0.0));
}

std::string Filter::bridgeOdometryGap(const OdometryGap& gap) {
  if (!(gap.seconds > 0)) return name() + ": nothing to bridge";
  const FilterState before = state();
  predict(bridgeIncrement(gap));
  FilterState after = state();
  addPoseNoise(bridgeNoise(gap, after.x[2]));
  stateInto(after);
  char text[200];
  std::snprintf(text, sizeof text, "%s: bridged %.2f m at %.2f m/s, position sigma %.3f -> %.3f m, dead reckoning",
                name().c_str(), (after.x.head<2>() - before.x.head<2>()).norm(),
                gap.speed, positionSigma(before), positionSigma(after));
  return text;
}

void Filter::addPoseNoise(const Mat3& Q) {
  FilterState s = state();  // (a filter without its own addPoseNoise: the status initialize() gives)
  s.P.topLeftCorner<3, 3>() += Q;
  initialize(s);
}

}  // namespace lcmloc::core
