#pragma once
// Generic unscented transform / UKF step over fixed-size Eigen types (paper eq. 9-18, with the
// scaled sigma points of van der Merwe: lambda = alpha^2 (n + kappa) - n). With alpha = 1,
// beta = 0 this is exactly the paper's eq. 9-10 (weights kappa/(n+kappa), 1/(2(n+kappa))).
// Angular state and measurement components are averaged circularly and differenced wrapped.
//
// Allocation-free: every matrix is fixed-size. The update is split in two so the caller can
// gate: innovate() computes z_hat, the innovation v, S, K and the Mahalanobis distance without
// touching the filter; correct() applies it. A rejected measurement leaves the prior untouched.
#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>
#include <utility>

#include "lcmloc/core/angles.hpp"

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

/// Which components of a vector are angles: bit i set <=> component i is an angle.
using AngleMask = std::uint32_t;
constexpr bool isAngle(AngleMask m, int i) { return (m >> i) & 1u; }

/// Weighted mean of the columns of a sigma-point set (2N+1 columns). Angle rows are averaged
/// as wrapped deviations from the first column (the propagated mean point):
///   m = Y0 + sum_k w_k wrap(Y_k - Y0), wrapped to (-pi, pi].
/// This is wrap-aware (the mean of +179 deg and -179 deg is 180 deg), reduces to the ordinary
/// weighted mean when nothing wraps (so a linear system gives exactly the Kalman filter), agrees
/// with the atan2 circular mean to third order in the spread, and needs no sin/cos (half the
/// cost of a predict + update). circularMean() in angles.hpp is the atan2 form.
template <int N, int R>
Eigen::Matrix<double, R, 1> sigmaMean(const Eigen::Matrix<double, R, 2 * N + 1>& Y,
                                      const SigmaWeights<N>& w, AngleMask angles) {
  Eigen::Matrix<double, R, 1> m =
      w.wm0 * Y.col(0) + w.wi * Y.template rightCols<2 * N>().rowwise().sum();
  for (int r = 0; r < R; ++r) {
    if (!isAngle(angles, r)) continue;
    const double ref = Y(r, 0);
    double sum = 0.0;
    for (int k = 1; k < 2 * N + 1; ++k) sum += wrapAngle(Y(r, k) - ref);
    m[r] = wrapAngle(ref + w.wi * sum);  // the weights sum to 1: wm0 * 0 + wi * sum
  }
  return m;
}

/// Deviations of the sigma points from a mean; angle rows wrapped to (-pi, pi].
template <int N, int R>
Eigen::Matrix<double, R, 2 * N + 1> sigmaDeviations(const Eigen::Matrix<double, R, 2 * N + 1>& Y,
                                                   const Eigen::Matrix<double, R, 1>& mean,
                                                   AngleMask angles) {
  Eigen::Matrix<double, R, 2 * N + 1> D = Y.colwise() - mean;
  for (int r = 0; r < R; ++r)
    if (isAngle(angles, r))
      for (int k = 0; k < 2 * N + 1; ++k) D(r, k) = wrapAngle(D(r, k));
  return D;
}

/// Weighted cross-covariance sum_k Wc_k A_k B_k^T of two deviation sets.
template <int N, int RA, int RB>
Eigen::Matrix<double, RA, RB> sigmaCovariance(const Eigen::Matrix<double, RA, 2 * N + 1>& A,
                                              const Eigen::Matrix<double, RB, 2 * N + 1>& B,
                                              const SigmaWeights<N>& w) {
  Eigen::Matrix<double, RA, RB> C = w.wi * (A * B.transpose());
  C.noalias() += (w.wc0 - w.wi) * A.col(0) * B.col(0).transpose();
  return C;
}

/// Lower Cholesky factor L of a small symmetric matrix A = L L' (plain loops: for the 2..5
/// sized matrices of this filter this is several times faster than Eigen::LLT's generic path).
/// False when A is not positive definite (or not finite).
template <int N>
bool choleskyLower(const Eigen::Matrix<double, N, N>& A, Eigen::Matrix<double, N, N>& L) {
  L.setZero();
  for (int j = 0; j < N; ++j) {
    double d = A(j, j);
    for (int k = 0; k < j; ++k) d -= L(j, k) * L(j, k);
    if (!(d > 0.0)) return false;  // also catches NaN
    const double ljj = std::sqrt(d), inv = 1.0 / ljj;
    L(j, j) = ljj;
    for (int i = j + 1; i < N; ++i) {
      double v = A(i, j);
      for (int k = 0; k < j; ++k) v -= L(i, k) * L(j, k);
      L(i, j) = v * inv;
    }
  }
  return true;
}

/// Inverse of a small symmetric positive definite matrix from its Cholesky factor.
template <int N>
Eigen::Matrix<double, N, N> inverseFromCholesky(const Eigen::Matrix<double, N, N>& L) {
  Eigen::Matrix<double, N, N> Li = Eigen::Matrix<double, N, N>::Zero();  // L^-1, lower
  for (int j = 0; j < N; ++j) {
    Li(j, j) = 1.0 / L(j, j);
    for (int i = j + 1; i < N; ++i) {
      double v = 0.0;
      for (int k = j; k < i; ++k) v -= L(i, k) * Li(k, j);
      Li(i, j) = v / L(i, i);
    }
  }
  return Li.transpose() * Li;
}

/// Inverse of a small symmetric matrix, false unless it is positive definite. Closed form for
/// 1x1 and 2x2 (one division), Cholesky otherwise.
template <int M>
bool inverseSpd(const Eigen::Matrix<double, M, M>& S, Eigen::Matrix<double, M, M>& S_inv) {
  if constexpr (M == 1) {
    if (!(S(0, 0) > 0.0)) return false;
    S_inv(0, 0) = 1.0 / S(0, 0);
    return true;
  } else if constexpr (M == 2) {
    const double det = S(0, 0) * S(1, 1) - S(0, 1) * S(0, 1);
    if (!(S(0, 0) > 0.0 && det > 0.0)) return false;  // Sylvester's criterion; catches NaN
    const double inv = 1.0 / det;
    S_inv << S(1, 1) * inv, -S(0, 1) * inv, -S(0, 1) * inv, S(0, 0) * inv;
    return true;
  } else {
    Eigen::Matrix<double, M, M> L;
    if (!choleskyLower<M>(S, L)) return false;
    S_inv = inverseFromCholesky<M>(L);
    return true;
  }
}

/// Result of a measurement prediction, before any decision.
template <int N, int M>
struct Innovation {
  Eigen::Matrix<double, M, 1> z_hat;  ///< predicted measurement (eq. 14)
  Eigen::Matrix<double, M, 1> v;      ///< z - z_hat, angle components wrapped
  Eigen::Matrix<double, M, M> S;      ///< innovation covariance (eq. 16)
  Eigen::Matrix<double, N, M> K;      ///< gain P_xz S^-1 (eq. 15)
  double mahalanobis = 0.0;           ///< v' S^-1 v (eq. 19)
};

template <int N>
class Ukf {
 public:
  static constexpr int kSigma = 2 * N + 1;
  using Vector = Eigen::Matrix<double, N, 1>;
  using Matrix = Eigen::Matrix<double, N, N>;
  using Sigmas = Eigen::Matrix<double, N, kSigma>;

  explicit Ukf(const SigmaParams& p = {}, AngleMask state_angles = 0)
      : w_(SigmaWeights<N>::compute(p)), angles_(state_angles) {
    x_.setZero();
    P_.setIdentity();
  }

  void reset(const Vector& x, const Matrix& P) {
    x_ = x;
    wrapAngles(x_);
    P_ = P;
  }
  const Vector& x() const { return x_; }
  const Matrix& P() const { return P_; }
  const SigmaWeights<N>& weights() const { return w_; }
  AngleMask angleMask() const { return angles_; }

  /// Sigma points of (x, P), eq. 9: columns x, x + sqrt((n+lambda)P)_i, x - sqrt((n+lambda)P)_i,
  /// the square root being the lower Cholesky factor. False when P is not positive definite.
  bool sigmaPoints(Sigmas& X) const {
    Matrix L;
    if (!choleskyLower<N>((N + w_.lambda) * P_, L)) return false;
    X.col(0) = x_;
    X.template middleCols<N>(1) = L.colwise() + x_;
    X.template rightCols<N>() = (-L).colwise() + x_;
    return true;
  }

  /// Time update (eq. 11-13) with process model f: Vector(const Vector&) and additive noise Q.
  /// False (filter untouched) when P is not positive definite or f returns a non-finite value.
  template <typename F>
  bool predict(F&& f, const Matrix& Q) {
    Sigmas X;
    if (!sigmaPoints(X)) return false;
    Sigmas Y;
    for (int k = 0; k < kSigma; ++k) Y.col(k) = f(X.col(k).eval());
    if (!Y.allFinite()) return false;
    const Vector m = sigmaMean<N, N>(Y, w_, angles_);
    const Sigmas D = sigmaDeviations<N, N>(Y, m, angles_);
    x_ = m;
    P_ = sigmaCovariance<N, N, N>(D, D, w_) + Q;
    return true;
  }

  /// Measurement prediction (eq. 14-17) from sigma points X of the current state with model
  /// h: Matrix<M,1>(const Vector&), additive noise R, measurement z whose angle components are
  /// marked in z_angles. Does not modify the filter. False when S is not positive definite or
  /// anything is non-finite.
  template <int M, typename H>
  bool innovate(const Sigmas& X, H&& h, const Eigen::Matrix<double, M, M>& R,
                const Eigen::Matrix<double, M, 1>& z, AngleMask z_angles,
                Innovation<N, M>& out) const {
    Eigen::Matrix<double, M, kSigma> Z;
    for (int k = 0; k < kSigma; ++k) Z.col(k) = h(X.col(k).eval());
    if (!Z.allFinite() || !z.allFinite()) return false;
    out.z_hat = sigmaMean<N, M>(Z, w_, z_angles);
    const Eigen::Matrix<double, M, kSigma> DZ = sigmaDeviations<N, M>(Z, out.z_hat, z_angles);
    // X = x +- columns of a square root: its deviations from X0 = x need no wrapping.
    const Sigmas DX = X.colwise() - X.col(0);
    out.S = sigmaCovariance<N, M, M>(DZ, DZ, w_) + R;
    const Eigen::Matrix<double, N, M> Pxz = sigmaCovariance<N, N, M>(DX, DZ, w_);
    Eigen::Matrix<double, M, M> S_inv;
    if (!inverseSpd<M>(out.S, S_inv)) return false;
    out.v = z - out.z_hat;
    wrapAngles(out.v, z_angles);
    out.K.noalias() = Pxz * S_inv;
    out.mahalanobis = out.v.dot(S_inv * out.v);
    return std::isfinite(out.mahalanobis) && out.K.allFinite();
  }

  /// Convenience: innovate() from the sigma points of the current state.
  template <int M, typename H>
  bool innovate(H&& h, const Eigen::Matrix<double, M, M>& R, const Eigen::Matrix<double, M, 1>& z,
                AngleMask z_angles, Innovation<N, M>& out) const {
    Sigmas X;
    return sigmaPoints(X) && innovate<M>(X, std::forward<H>(h), R, z, z_angles, out);
  }

  /// Applies an accepted innovation: eq. 15 and 18 (P - K S K').
  template <int M>
  void correct(const Innovation<N, M>& in) {
    x_.noalias() += in.K * in.v;
    wrapAngles(x_);
    P_ -= in.K * in.S * in.K.transpose();
    P_ = 0.5 * (P_ + P_.transpose()).eval();
  }

 private:
  template <typename V>
  static void wrapAngles(V& v, AngleMask m) {
    for (int r = 0; r < v.size(); ++r)
      if (isAngle(m, r)) v[r] = wrapAngle(v[r]);
  }
  void wrapAngles(Vector& v) const { wrapAngles(v, angles_); }

  SigmaWeights<N> w_;
  AngleMask angles_;
  Vector x_;
  Matrix P_;
};

}  // namespace lcmloc::core
