#include "lcmloc/core/angles.hpp"

namespace lcmloc::core {

double circularMean(const Eigen::Ref<const Eigen::VectorXd>& angles,
                    const Eigen::Ref<const Eigen::VectorXd>& weights) {
  double s = 0.0, c = 0.0;
  for (Eigen::Index i = 0; i < angles.size(); ++i) {
    s += weights[i] * std::sin(angles[i]);
    c += weights[i] * std::cos(angles[i]);
  }
  return wrapAngle(std::atan2(s, c));
}

}  // namespace lcmloc::core
