#pragma once
#include <cmath>
#include <Eigen/Core>

namespace lcmloc::core {

/// Wraps an angle to (-pi, pi].
double wrapAngle(double a);

/// Weighted circular mean of angles: atan2(sum w sin a, sum w cos a). Weights may be negative
/// (UKF weights); the result is in (-pi, pi].
double circularMean(const Eigen::Ref<const Eigen::VectorXd>& angles,
                    const Eigen::Ref<const Eigen::VectorXd>& weights);

}  // namespace lcmloc::core
