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

/// |a| up to which sinCosSmall evaluates its polynomials [rad].
inline constexpr double kSmallAngle = 0.25;

/// sin and cos of a: Taylor polynomials for |a| <= kSmallAngle, libm otherwise. To a^9 and a^10
/// for |a| <= 0.05 (the half increments of one odometry step), to a^13 and a^14 beyond: truncation
/// error below 3e-21 relative either way, far under the rounding of the result.
inline void sinCosSmall(double a, double& s, double& c) {
  // 1/k! for the sine's odd and the cosine's even powers
  constexpr double k3 = 1.0 / 6, k5 = 1.0 / 120, k7 = 1.0 / 5040, k9 = 1.0 / 362880, k11 = 1.0 / 39916800,
                   k13 = 1.0 / 6227020800.0;
  constexpr double k2 = 1.0 / 2, k4 = 1.0 / 24, k6 = 1.0 / 720, k8 = 1.0 / 40320, k10 = 1.0 / 3628800,
                   k12 = 1.0 / 479001600, k14 = 1.0 / 87178291200.0;
  const double a2 = a * a;
  if (std::abs(a) <= 0.05) {
    s = a + a * a2 * (-k3 + a2 * (k5 + a2 * (-k7 + a2 * k9)));
    c = 1.0 + a2 * (-k2 + a2 * (k4 + a2 * (-k6 + a2 * (k8 - a2 * k10))));
  } else if (std::abs(a) <= kSmallAngle) {
    s = a + a * a2 * (-k3 + a2 * (k5 + a2 * (-k7 + a2 * (k9 + a2 * (-k11 + a2 * k13)))));
    c = 1.0 + a2 * (-k2 + a2 * (k4 + a2 * (-k6 + a2 * (k8 + a2 * (-k10 + a2 * (k12 - a2 * k14))))));
  } else {
    s = std::sin(a);
    c = std::cos(a);
  }
}

/// An angle with its cosine and sine, and those of angles near it by angle addition: a UKF
/// moves its sigma points, whose headings lie within a few sigma of the mean's, with one libm
/// call for the mean instead of one per point.
struct SinCosNear {
  double theta, c, s;
  explicit SinCosNear(double t) : theta(t), c(std::cos(t)), s(std::sin(t)) {}
  /// cos and sin of a: angle addition from theta when a is within kSmallAngle of it (exactly
  /// c, s at a = theta), libm otherwise.
  void sinCos(double a, double& sa, double& ca) const {
    const double d = a - theta;
    if (!(std::abs(d) <= kSmallAngle)) {
      sa = std::sin(a);
      ca = std::cos(a);
      return;
    }
    double sd, cd;
    sinCosSmall(d, sd, cd);
    ca = c * cd - s * sd;
    sa = s * cd + c * sd;
  }
};

/// Weighted circular mean of angles: atan2(sum w sin a, sum w cos a). Weights may be negative
/// (UKF weights); the result is in (-pi, pi].
double circularMean(const Eigen::Ref<const Eigen::VectorXd>& angles,
                    const Eigen::Ref<const Eigen::VectorXd>& weights);

}  // namespace lcmloc::core
