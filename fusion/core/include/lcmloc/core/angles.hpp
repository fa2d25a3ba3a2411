#pragma once
#include <cmath>
#include <Eigen/Core>

namespace lcmloc::core {

/// Wraps an angle to (-pi, pi]: +pi stays +pi, -pi maps to +pi. Non-finite input is returned
/// unchanged. Inline: it sits in the inner loop of every filter.
inline double wrapAngle(double a) {
  if (a > -M_PI && a <= M_PI) return a;  // fast path: already wrapped
  if (!std::isfinite(a)) return a;
  const double r = std::remainder(a, 2.0 * M_PI);  // in [-pi, pi]
  return r <= -M_PI ? r + 2.0 * M_PI : r;
}

/// Weighted circular mean of angles: atan2(sum w sin a, sum w cos a). Weights may be negative
/// (UKF weights); the result is in (-pi, pi].
double circularMean(const Eigen::Ref<const Eigen::VectorXd>& angles,
                    const Eigen::Ref<const Eigen::VectorXd>& weights);

}  // namespace lcmloc::core
