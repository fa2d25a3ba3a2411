// The generic UKF: weights, sigma points, the linear case against a Kalman filter, angles.
#include <gtest/gtest.h>

#include <cmath>

#include "lcmloc/core/ukf.hpp"

using namespace lcmloc::core;

namespace {
constexpr double kDeg = M_PI / 180.0;
}

TEST(SigmaWeights, AlphaOneBetaTwoKappaOneN3) {
  const auto w = SigmaWeights<3>::compute(SigmaParams{1.0, 2.0, 1.0});
  EXPECT_DOUBLE_EQ(w.lambda, 1.0);
  EXPECT_DOUBLE_EQ(w.wm0, 0.25);
  EXPECT_DOUBLE_EQ(w.wc0, 2.25);
  EXPECT_DOUBLE_EQ(w.wi, 0.125);
  EXPECT_DOUBLE_EQ(w.wm0 + 6 * w.wi, 1.0);
}

TEST(SigmaWeights, PaperKappaZeroIsEq10) {
  const auto w = SigmaWeights<3>::compute(SigmaParams{1.0, 0.0, 0.0});  // n + kappa = 3
  EXPECT_DOUBLE_EQ(w.wm0, 0.0);            // kappa / (n + kappa)
  EXPECT_DOUBLE_EQ(w.wc0, 0.0);
  EXPECT_DOUBLE_EQ(w.wi, 1.0 / 6.0);       // 1 / (2 (n + kappa))
}

TEST(SigmaPoints, HandPickedCovariance) {
  // n + lambda = 4: 4P = [[16,8,0],[8,8,0],[0,0,4]] = L L' with L = [[4,0,0],[2,2,0],[0,0,2]].
  Ukf<3> ukf(SigmaParams{1.0, 2.0, 1.0});
  Eigen::Matrix3d P;
  P << 4, 2, 0, 2, 2, 0, 0, 0, 1;
  ukf.reset(Eigen::Vector3d(1, 2, 3), P);
  Ukf<3>::Sigmas X;
  ASSERT_TRUE(ukf.sigmaPoints(X));
  Ukf<3>::Sigmas expected;
  expected << 1, 5, 1, 1, -3, 1, 1,
              2, 4, 4, 2, 0, 0, 2,
              3, 3, 3, 5, 3, 3, 1;
  EXPECT_TRUE(X.isApprox(expected, 1e-14)) << X;
  // Not positive definite: refused.
  ukf.reset(Eigen::Vector3d::Zero(), -Eigen::Matrix3d::Identity());
  EXPECT_FALSE(ukf.sigmaPoints(X));
}

TEST(SigmaPoints, UnscentedTransformOfIdentityKeepsMeanAndCovariance) {
  Ukf<3> ukf(SigmaParams{0.5, 2.0, 0.0});
  Eigen::Matrix3d P;
  P << 0.3, 0.1, 0.0, 0.1, 0.2, 0.05, 0.0, 0.05, 0.1;
  ukf.reset(Eigen::Vector3d(1, -2, 0.5), P);
  ASSERT_TRUE(ukf.predict([](const Eigen::Vector3d& s) { return s; }, Eigen::Matrix3d::Zero()));
  EXPECT_TRUE(ukf.x().isApprox(Eigen::Vector3d(1, -2, 0.5), 1e-12));
  EXPECT_TRUE(ukf.P().isApprox(P, 1e-12));
}

// x = (position, velocity), z = position: the UKF must reproduce the Kalman filter exactly.
TEST(UkfLinear, AgreesWithKalmanFilter) {
  const double dt = 0.1;
  Eigen::Matrix2d F;
  F << 1, dt, 0, 1;
  const Eigen::Vector2d B(0.5 * dt * dt, dt);
  Eigen::Matrix2d Q;
  Q << 1e-3, 2e-4, 2e-4, 5e-3;
  Eigen::Matrix<double, 1, 2> H(1.0, 0.0);
  Eigen::Matrix<double, 1, 1> R;
  R << 0.04;
  for (const SigmaParams sp : {SigmaParams{1, 0, 0}, SigmaParams{1, 2, 1}, SigmaParams{0.3, 2, 0}}) {
    Ukf<2> ukf(sp);
    Eigen::Vector2d x(0.5, -1.0);
    Eigen::Matrix2d P;
    P << 1.0, 0.2, 0.2, 0.5;
    ukf.reset(x, P);
    Eigen::Vector2d truth(0.0, 0.0);
    for (int k = 0; k < 40; ++k) {
      const double u = std::sin(0.3 * k);
      truth = F * truth + B * u;
      ukf.predict([&](const Eigen::Vector2d& s) -> Eigen::Vector2d { return F * s + B * u; }, Q);
      x = F * x + B * u;
      P = F * P * F.transpose() + Q;
      Eigen::Matrix<double, 1, 1> z;
      z << truth(0) + 0.2 * std::cos(1.7 * k);  // deterministic "noise" of about R
      Innovation<2, 1> in;
      ASSERT_TRUE(ukf.innovate<1>([&](const Eigen::Vector2d& s) { return (H * s).eval(); }, R, z,
                                  0u, in));
      const Eigen::Matrix<double, 1, 1> S = H * P * H.transpose() + R;
      const Eigen::Vector2d K = P * H.transpose() / S(0, 0);
      const double v = z(0) - (H * x)(0);
      EXPECT_NEAR(in.v(0), v, 1e-12);
      EXPECT_NEAR(in.S(0, 0), S(0, 0), 1e-12);
      EXPECT_NEAR(in.mahalanobis, v * v / S(0, 0), 1e-12);
      ukf.correct(in);
      x += K * v;
      P = P - K * S * K.transpose();
      ASSERT_LT((ukf.x() - x).cwiseAbs().maxCoeff(), 1e-12) << "step " << k;
      ASSERT_LT((ukf.P() - P).cwiseAbs().maxCoeff(), 1e-12) << "step " << k;
    }
  }
}

TEST(UkfAngles, MeanOfSigmaPointsAcrossPi) {
  // Row 0 is an angle: +179 deg and -179 deg average to 180 deg, not 0.
  const auto w = SigmaWeights<1>::compute(SigmaParams{1, 0, 0});  // wm0 = 0, wi = 1/2
  Eigen::Matrix<double, 1, 3> Y(179 * kDeg, 179 * kDeg, -179 * kDeg);
  EXPECT_NEAR((sigmaMean<1, 1>(Y, w, 1u)(0)), M_PI, 1e-12);
  EXPECT_NEAR((sigmaMean<1, 1>(Y, w, 0u)(0)), 0.0, 1e-12);  // not an angle: plain mean
  const auto D = sigmaDeviations<1, 1>(Y, Eigen::Matrix<double, 1, 1>(M_PI), 1u);
  EXPECT_NEAR(D(0, 1), -1 * kDeg, 1e-12);
  EXPECT_NEAR(D(0, 2), 1 * kDeg, 1e-12);
}

TEST(UkfAngles, PredictedHeadingAcrossPiAndWrappedResidual) {
  // One angular state near pi, rotated by +2 deg: the mean stays near -178 deg with a small
  // covariance (a plain mean would put it near 0 with a huge one).
  Ukf<1> ukf(SigmaParams{1, 0, 0}, 1u);
  ukf.reset(Eigen::Matrix<double, 1, 1>(179 * kDeg),
            Eigen::Matrix<double, 1, 1>(std::pow(2 * kDeg, 2)));
  ASSERT_TRUE(ukf.predict(
      [](const Eigen::Matrix<double, 1, 1>& s) {
        return Eigen::Matrix<double, 1, 1>(wrapAngle(s(0) + 2 * kDeg));
      },
      Eigen::Matrix<double, 1, 1>::Zero()));
  EXPECT_NEAR(ukf.x()(0), -179 * kDeg, 1e-12);
  EXPECT_NEAR(ukf.P()(0, 0), std::pow(2 * kDeg, 2), 1e-12);
  // Measurement of the angle itself: z = 179 deg vs z_hat = -179 deg -> v = -2 deg, not 358.
  Innovation<1, 1> in;
  ASSERT_TRUE(ukf.innovate<1>([](const Eigen::Matrix<double, 1, 1>& s) { return s; },
                              Eigen::Matrix<double, 1, 1>(std::pow(2 * kDeg, 2)),
                              Eigen::Matrix<double, 1, 1>(179 * kDeg), 1u, in));
  EXPECT_NEAR(in.z_hat(0), -179 * kDeg, 1e-12);
  EXPECT_NEAR(in.v(0), -2 * kDeg, 1e-12);
  EXPECT_NEAR(in.mahalanobis, 0.5, 1e-9);  // (2 deg)^2 / (2 * (2 deg)^2)
  ukf.correct(in);
  EXPECT_NEAR(wrapAngle(ukf.x()(0) - M_PI), 0.0, 1e-12);  // halfway, across the seam
  EXPECT_GT(ukf.x()(0), -M_PI);
}

TEST(UkfUpdate, InnovateLeavesTheFilterUntouched) {
  Ukf<2> ukf;
  ukf.reset(Eigen::Vector2d(1, 2), Eigen::Matrix2d::Identity());
  Innovation<2, 1> in;
  ASSERT_TRUE(ukf.innovate<1>(
      [](const Eigen::Vector2d& s) { return Eigen::Matrix<double, 1, 1>(s(0) + s(1)); },
      Eigen::Matrix<double, 1, 1>(1.0), Eigen::Matrix<double, 1, 1>(10.0), 0u, in));
  EXPECT_NEAR(in.v(0), 7.0, 1e-12);
  EXPECT_EQ(ukf.x(), Eigen::Vector2d(1, 2));
  EXPECT_EQ(ukf.P(), Eigen::Matrix2d::Identity());
  // Non-finite measurement: refused.
  EXPECT_FALSE(ukf.innovate<1>(
      [](const Eigen::Vector2d& s) { return Eigen::Matrix<double, 1, 1>(s(0)); },
      Eigen::Matrix<double, 1, 1>(1.0), Eigen::Matrix<double, 1, 1>(NAN), 0u, in));
}

TEST(SmallLinearAlgebra, CholeskyAndSpdInverse) {
  Eigen::Matrix3d A;
  A << 4, 2, 0, 2, 2, 0, 0, 0, 1;
  Eigen::Matrix3d L;
  ASSERT_TRUE(choleskyLower<3>(A, L));
  Eigen::Matrix3d expected;
  expected << 2, 0, 0, 1, 1, 0, 0, 0, 1;
  EXPECT_TRUE(L.isApprox(expected, 1e-15));
  Eigen::Matrix3d A_inv;
  ASSERT_TRUE(inverseSpd<3>(A, A_inv));
  EXPECT_TRUE((A * A_inv).isApprox(Eigen::Matrix3d::Identity(), 1e-14));
  Eigen::Matrix2d S, S_inv;
  S << 2e-4, 5e-5, 5e-5, 4e-4;
  ASSERT_TRUE(inverseSpd<2>(S, S_inv));
  EXPECT_TRUE((S * S_inv).isApprox(Eigen::Matrix2d::Identity(), 1e-12));
  S << 1, 2, 2, 1;  // indefinite
  EXPECT_FALSE(inverseSpd<2>(S, S_inv));
  A(2, 2) = -1;
  EXPECT_FALSE(choleskyLower<3>(A, L));
  EXPECT_FALSE(inverseSpd<3>(A, A_inv));
}
