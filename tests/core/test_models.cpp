// Models, angles and chi-square against values worked out by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/chi2.hpp"
#include "lcmloc/core/ruler_model.hpp"
#include "lcmloc/core/vehicle_model.hpp"

using namespace lcmloc::core;

namespace {
constexpr double kDeg = M_PI / 180.0;
}

TEST(Angles, WrapToHalfOpenInterval) {
  EXPECT_DOUBLE_EQ(wrapAngle(M_PI), M_PI);    // +pi stays
  EXPECT_DOUBLE_EQ(wrapAngle(-M_PI), M_PI);   // -pi maps to +pi
  EXPECT_DOUBLE_EQ(wrapAngle(3 * M_PI), M_PI);
  EXPECT_DOUBLE_EQ(wrapAngle(-3 * M_PI), M_PI);
  EXPECT_NEAR(wrapAngle(7.0), 7.0 - 2 * M_PI, 1e-15);
  EXPECT_NEAR(wrapAngle(-7.0), -7.0 + 2 * M_PI, 1e-15);
  EXPECT_DOUBLE_EQ(wrapAngle(0.5), 0.5);
  EXPECT_NEAR(wrapAngle(181 * kDeg), -179 * kDeg, 1e-12);
}

TEST(Angles, CircularMeanAcrossPi) {
  Eigen::Vector2d a(179 * kDeg, -179 * kDeg), w(0.5, 0.5);
  EXPECT_NEAR(circularMean(a, w), M_PI, 1e-12);  // not 0
  Eigen::Vector3d b(10 * kDeg, 20 * kDeg, 30 * kDeg), wb(0.25, 0.5, 0.25);
  EXPECT_NEAR(circularMean(b, wb), 20 * kDeg, 1e-12);
}

TEST(VehicleModel, HeadingIncrementEq2) {
  EXPECT_NEAR(headingIncrement(1.0, std::atan(0.25), 2.5), 0.1, 1e-15);
  EXPECT_NEAR(headingIncrement(-1.0, std::atan(0.25), 2.5), -0.1, 1e-15);  // reversing
  OdometryInput car{0, 2.0, std::atan(0.5), true, 99.0};
  EXPECT_NEAR(headingIncrement(car, 2.5), 0.4, 1e-15);  // from steering, ignores delta_theta
  OdometryInput diff{0, 0.0, 0.0, false, 0.3};
  EXPECT_DOUBLE_EQ(headingIncrement(diff, 2.5), 0.3);  // turn in place: as given
}

namespace {
bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }
}  // namespace

// The cache gives, bit for bit, what std::tan gives: for angles met again (hits), for more
// distinct angles than it has entries (replaced entries), for +0 and -0 (different bits) and NaN.
TEST(VehicleModel, TanCacheReturnsExactlyWhatTanReturns) {
  TanCache tan;
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> level(-600, 600);  // 1201 steering steps of 0.0005 rad
  for (int i = 0; i < 20000; ++i) {
    const double psi = 0.0005 * level(rng);
    ASSERT_TRUE(sameBits(tan(psi), std::tan(psi))) << psi;
  }
  for (double psi : {0.0, -0.0, 0.3, -0.0, 0.0, 1.5707963267948966, -1e-300}) {
    EXPECT_TRUE(sameBits(tan(psi), std::tan(psi))) << psi;
  }
  EXPECT_TRUE(std::signbit(tan(-0.0)));
  EXPECT_FALSE(std::signbit(tan(0.0)));
  EXPECT_TRUE(std::isnan(tan(std::nan(""))));
  // headingIncrement through the cache is eq. 2 as headingIncrement computes it, bit for bit.
  for (int k = -50; k <= 50; ++k) {
    const OdometryInput car{0, 0.013 * k, 0.0007 * k * k, true, 99.0};
    EXPECT_TRUE(sameBits(headingIncrement(car, 2.5, tan), headingIncrement(car, 2.5)));
  }
  const OdometryInput diff{0, 0.1, 0.2, false, 0.3};
  EXPECT_DOUBLE_EQ(headingIncrement(diff, 2.5, tan), 0.3);
}

TEST(VehicleModel, PropagatePoseEq1MidpointHeading) {
  const Pose p = propagatePose(Pose(1, 2, 0), 2.0, M_PI / 2);  // midpoint heading pi/4
  EXPECT_NEAR(p.x(), 1 + std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(p.y(), 2 + std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(p.z(), M_PI / 2, 1e-15);
  const Pose q = propagatePose(Pose(0, 0, 3.0), 0.0, 0.5);  // theta wrapped
  EXPECT_NEAR(q.z(), 3.5 - 2 * M_PI, 1e-12);
  EXPECT_DOUBLE_EQ(q.x(), 0.0);
}

TEST(RulerModel, ObservationEq6) {
  const Vec2 z = rulerObservation(0.2, 1.5);
  EXPECT_NEAR(z[0], std::sqrt(2.29), 1e-15);
  EXPECT_NEAR(z[1], std::atan(0.2 / 1.5), 1e-15);
  EXPECT_NEAR(rulerObservation(-0.3, 1.5)[1], -std::atan(0.2), 1e-15);
}

TEST(RulerModel, PredictionEq5MatchesObservationOfTheSameMarker) {
  // Vehicle at the origin heading north (+y): body forward = +y, body left = -x.
  const Pose pose(0, 0, M_PI / 2);
  const Vec2 body = markerInBody(pose, -0.2, 1.5);
  EXPECT_NEAR(body[0], 1.5, 1e-15);
  EXPECT_NEAR(body[1], 0.2, 1e-15);
  const Vec2 h = predictRangeBearing(pose, -0.2, 1.5);
  const Vec2 z = rulerObservation(0.2, 1.5);
  EXPECT_NEAR(h[0], z[0], 1e-15);
  EXPECT_NEAR(h[1], z[1], 1e-15);
}

TEST(RulerModel, PredictedBearingIsWrapped) {
  // Heading pi, marker just left-behind across the +-pi seam: raw atan2 - theta = -pi + 0.001.
  const Vec2 h = predictRangeBearing(Pose(0, 0, M_PI), 1.0, 0.001);
  EXPECT_NEAR(h[1], -M_PI + std::atan(0.001), 1e-12);
  const Vec2 h2 = predictRangeBearing(Pose(0, 0, -3.0), -1.0, -0.5);  // atan2 = -2.678 -> +0.32
  EXPECT_NEAR(h2[1], std::atan2(-0.5, -1.0) + 3.0, 1e-12);
  EXPECT_GT(h2[1], -M_PI);
  EXPECT_LE(h2[1], M_PI);
}

TEST(Chi2, QuantilesOfThePaperTable) {
  EXPECT_NEAR(chi2Quantile(0.99, 1), 6.635, 5e-4);
  EXPECT_NEAR(chi2Quantile(0.99, 2), 9.210, 5e-4);
  EXPECT_NEAR(chi2Quantile(0.95, 1), 3.841, 5e-4);
  EXPECT_NEAR(chi2Quantile(0.90, 1), 2.706, 5e-4);
  EXPECT_NEAR(chi2Quantile(0.975, 1), 5.024, 5e-4);
  EXPECT_NEAR(chi2Quantile(0.995, 1), 7.879, 5e-4);
  EXPECT_NEAR(chi2Quantile(0.99, 2), -2.0 * std::log(0.01), 1e-9);  // closed form for dof 2
  EXPECT_NEAR(chi2Quantile(0.95, 10), 18.307, 5e-4);
  EXPECT_NEAR(chi2Quantile(0.99, 5), 15.086, 5e-4);
}

TEST(Chi2, CdfClosedForms) {
  EXPECT_NEAR(chi2Cdf(2.0, 2), 1 - std::exp(-1.0), 1e-15);
  EXPECT_NEAR(chi2Cdf(1.0, 1), std::erf(std::sqrt(0.5)), 1e-15);
  EXPECT_NEAR(chi2Cdf(3.0, 3), 0.608374823728911, 1e-12);
  EXPECT_NEAR(chi2Cdf(4.0, 4), 1 - 3 * std::exp(-2.0), 1e-14);
  EXPECT_DOUBLE_EQ(chi2Cdf(0.0, 5), 0.0);
  for (int dof = 1; dof <= 10; ++dof)
    EXPECT_NEAR(chi2Cdf(chi2Quantile(0.99, dof), dof), 0.99, 1e-10) << dof;
  EXPECT_THROW(chi2Quantile(0.99, 11), std::invalid_argument);
  EXPECT_THROW(chi2Quantile(1.0, 2), std::invalid_argument);
}
