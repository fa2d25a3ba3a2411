#pragma once
// Generic unscented transform / UKF step over fixed-size Eigen types (paper eq. 9-18, with the
// scaled sigma points of van der Merwe: lambda = alpha^2 (n + kappa) - n). With alpha = 1,
// beta = 0 this is exactly the paper's eq. 9-10 (weights kappa/(n+kappa), 1/(2(n+kappa))).
// Angular state and measurement components are averaged circularly and differenced wrapped.
#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <array>

namespace lcmloc::core {

struct SigmaParams {
  double alpha = 1.0;
  double beta = 0.0;
  double kappa = 0.0;
};

template <int N>
struct SigmaWeights {
  double lambda = 0.0;
  double wm0 = 0.0, wc0 = 0.0, wi = 0.0;  ///< weights of the mean and covariance
  static SigmaWeights compute(const SigmaParams& p) {
    SigmaWeights w;
    w.lambda = p.alpha * p.alpha * (N + p.kappa) - N;
    w.wm0 = w.lambda / (N + w.lambda);
    w.wc0 = w.wm0 + (1.0 - p.alpha * p.alpha + p.beta);
    w.wi = 1.0 / (2.0 * (N + w.lambda));
    return w;
  }
};

}  // namespace lcmloc::core
