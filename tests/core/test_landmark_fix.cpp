// Three-landmark fix of §III: error-triangle method and damped least squares.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "lcmloc/core/landmark_fix.hpp"

using namespace lcmloc::core::landmark;

namespace {
constexpr double kArcMin = M_PI / 180.0 / 60.0;
/// Equilateral triangle of landmarks centred on c with circumradius R (ids 1, 2, 3).
std::map<int, Vec2> triangle(double R, Vec2 c = Vec2::Zero()) {
  std::map<int, Vec2> m;
  for (int i = 0; i < 3; ++i) {
    const double a = M_PI / 2 + i * 2 * M_PI / 3;
    m[i + 1] = c + R * Vec2(std::cos(a), std::sin(a));
  }
  return m;
}
std::vector<Bearing> bearings(const std::map<int, Vec2>& m, const Vec2& p, double psi) {
  std::vector<Bearing> b;
  for (const auto& [id, l] : m) b.push_back({id, predictBearing(p, psi, l)});
  return b;
}
}  // namespace

struct FixCase {
  double R;       // circumradius of the landmark triangle
  Vec2 vehicle;   // true position
  double psi;     // true heading
};

class NoiseFree : public ::testing::TestWithParam<FixCase> {};

TEST_P(NoiseFree, TriangleAndLeastSquaresRecoverPoseExactly) {
  const FixCase c = GetParam();
  const auto map = triangle(c.R);
  const auto b = bearings(map, c.vehicle, c.psi);
  // INS off by (500 m, -500 m) and -30' as in §III.
  const Vec2 p_ins = c.vehicle + Vec2(500.0, -500.0);
  const double psi_ins = c.psi - 30.0 * kArcMin;
  const FixResult t = triangleFix(map, b, p_ins, psi_ins);
  ASSERT_TRUE(t.ok) << t.error;
  EXPECT_NEAR(t.heading, c.psi, 1e-9);
  EXPECT_LT((t.position - c.vehicle).norm(), 1e-5);
  const FixResult l = leastSquaresFix(map, b, p_ins, psi_ins);
  ASSERT_TRUE(l.ok) << l.error;
  EXPECT_NEAR(l.heading, c.psi, 1e-9);
  EXPECT_LT((l.position - c.vehicle).norm(), 1e-5);
}

INSTANTIATE_TEST_SUITE_P(
    Geometries, NoiseFree,
    ::testing::Values(FixCase{1000.0, Vec2::Zero(), 0.0},                       // 1000 m from vehicle
                      FixCase{1000.0 / std::sqrt(3.0), Vec2::Zero(), 0.3},      // 1000 m apart
                      FixCase{1000.0, Vec2(300.0, -200.0), -1.2},               // off centre
                      FixCase{1000.0 / std::sqrt(3.0), Vec2(-150.0, 120.0), 2.5}));

TEST(TriangleFix, OffCentreUncorrectedCentroidIsWrongAndCorrectedIsRight) {
  // At the centre the uncorrected lines' LS point is already close; off centre it is not.
  const auto map = triangle(1000.0);
  const Vec2 p(400.0, 250.0);
  const auto b = bearings(map, p, 0.0);
  FixOptions o;
  o.search_half_width = 1e-9;  // no search: heading stays at the INS value
  const FixResult uncorrected = triangleFix(map, b, p, -30.0 * kArcMin, o);
  ASSERT_TRUE(uncorrected.ok) << uncorrected.error;
  EXPECT_GT((uncorrected.position - p).norm(), 1.0);
  const FixResult corrected = triangleFix(map, b, p, -30.0 * kArcMin);
  EXPECT_LT((corrected.position - p).norm(), 1e-5);
}

TEST(LeastSquaresFix, UndampedGaussNewtonFromFarStartFailsDampedSucceeds) {
  // INS far off (hundreds of metres, several degrees): count failures of plain GN.
  const auto map = triangle(1000.0 / std::sqrt(3.0));
  int gn_fail = 0, lm_fail = 0;
  for (int k = 0; k < 36; ++k) {
    const double a = k * 10.0 * M_PI / 180.0;
    const Vec2 p(100.0, -50.0);
    const auto b = bearings(map, p, 0.2);
    const Vec2 start = p + 800.0 * Vec2(std::cos(a), std::sin(a));
    if (!gaussNewtonFix(map, b, start, 0.2 - 0.1).ok ||
        (gaussNewtonFix(map, b, start, 0.1).position - p).norm() > 1e-3)
      ++gn_fail;
    const FixResult l = leastSquaresFix(map, b, start, 0.1);
    if (!l.ok || (l.position - p).norm() > 1e-3) ++lm_fail;
  }
  std::printf("far start: undamped GN failed %d/36, damped %d/36\n", gn_fail, lm_fail);
  EXPECT_GT(gn_fail, lm_fail);
}

TEST(LandmarkFix, DangerCircleRefused) {
  const auto map = triangle(1000.0);
  const Vec2 on_circle = 1000.0 * Vec2(std::cos(0.3), std::sin(0.3));
  const Vec2 near_circle = 999.9 * Vec2(std::cos(0.3), std::sin(0.3));
  for (const Vec2& p : {on_circle, near_circle}) {
    const auto b = bearings(map, p, 0.1);
    const FixResult t = triangleFix(map, b, p, 0.1);
    EXPECT_FALSE(t.ok);
    EXPECT_NE(t.error.find("danger circle"), std::string::npos) << t.error;
    const FixResult l = leastSquaresFix(map, b, p, 0.1);
    EXPECT_FALSE(l.ok);
    EXPECT_NE(l.error.find("danger circle"), std::string::npos) << l.error;
  }
  // Collinear with two landmarks but well inside the circle: accepted.
  const Vec2 mid = 0.5 * (map.at(2) + map.at(3)) * 0.5;
  const FixResult ok = triangleFix(map, bearings(map, mid, 0.0), mid, 0.0);
  EXPECT_TRUE(ok.ok) << ok.error;
  // Condition grows as the vehicle approaches the circle.
  const double c_in = triangleFix(map, bearings(map, Vec2(0, -500), 0.0), Vec2(0, -500), 0.0).condition;
  const double c_near = triangleFix(map, bearings(map, Vec2(0, -900), 0.0), Vec2(0, -900), 0.0).condition;
  EXPECT_GT(c_near, 3.0 * c_in);
}

TEST(LandmarkFix, BadInputRefused) {
  const auto map = triangle(1000.0);
  auto b = bearings(map, Vec2::Zero(), 0.0);
  b[1].landmark_id = 42;
  FixResult r = triangleFix(map, b, Vec2::Zero(), 0.0);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.error.find("42 is not in the map"), std::string::npos) << r.error;
  r = leastSquaresFix(map, b, Vec2::Zero(), 0.0);
  EXPECT_FALSE(r.ok);
  b = bearings(map, Vec2::Zero(), 0.0);
  b[0].alpha = NAN;
  EXPECT_FALSE(triangleFix(map, b, Vec2::Zero(), 0.0).ok);
  b.pop_back();
  EXPECT_FALSE(leastSquaresFix(map, b, Vec2::Zero(), 0.0).ok);
  b = bearings(map, Vec2::Zero(), 0.0);
  EXPECT_FALSE(triangleFix(map, b, Vec2::Zero(), NAN).ok);
}

TEST(LandmarkFix, CramerRaoAtCentre) {
  // Equilateral, vehicle at the centre, range r: heading std = sigma / sqrt(3) ... computed
  // from the information matrix: position std = sigma * r * sqrt(2/3).
  const double sigma = 30.0 * M_PI / 180.0 / 3600.0;
  const auto map = triangle(1000.0);
  std::vector<Vec2> lms;
  for (const auto& [id, l] : map) lms.push_back(l);
  const Eigen::Matrix3d C = cramerRao(Vec2::Zero(), lms, sigma);
  EXPECT_NEAR(std::sqrt(C(0, 0)), sigma * 1000.0 * std::sqrt(2.0 / 3.0), 1e-9);
  EXPECT_NEAR(std::sqrt(C(2, 2)), sigma / std::sqrt(3.0), 1e-12);
}

TEST(LandmarkFix, SmallMonteCarloAgainstCramerRao) {
  // 100 runs of §III: INS error (500 m, -500 m), -30', bearing noise 30" quantised to 14",
  // vehicle at the centre. Both readings of "1000 m": range 1000 m and landmarks 1000 m apart.
  const double sigma = 30.0 * M_PI / 180.0 / 3600.0, res = 14.0 * M_PI / 180.0 / 3600.0;
  for (double R : {1000.0, 1000.0 / std::sqrt(3.0)}) {
    const auto map = triangle(R);
    std::vector<Vec2> lms;
    for (const auto& [id, l] : map) lms.push_back(l);
    const Eigen::Matrix3d crb = cramerRao(Vec2::Zero(), lms, sigma);
    std::mt19937 rng(11);
    std::normal_distribution<double> n(0.0, sigma);
    double se_t = 0, se_l = 0, sh_t = 0, sh_l = 0;
    const int N = 100;
    for (int k = 0; k < N; ++k) {
      auto b = bearings(map, Vec2::Zero(), 0.0);
      for (auto& x : b) x.alpha = res * std::round((x.alpha + n(rng)) / res);
      const FixResult t = triangleFix(map, b, Vec2(500, -500), -30.0 * kArcMin);
      const FixResult l = leastSquaresFix(map, b, Vec2(500, -500), -30.0 * kArcMin);
      ASSERT_TRUE(t.ok && l.ok) << t.error << l.error;
      se_t += t.position.squaredNorm() / N, se_l += l.position.squaredNorm() / N;
      sh_t += t.heading * t.heading / N, sh_l += l.heading * l.heading / N;
    }
    const double crb_pos = std::sqrt(crb(0, 0) + crb(1, 1)), crb_h = std::sqrt(crb(2, 2));
    const double as = 180.0 / M_PI * 3600.0;
    std::printf("R %.0f m: rms pos triangle %.3f LS %.3f CRB %.3f m; 2-sigma heading triangle %.1f LS %.1f CRB %.1f arcsec\n",
                R, std::sqrt(se_t), std::sqrt(se_l), crb_pos, 2 * std::sqrt(sh_t) * as, 2 * std::sqrt(sh_l) * as,
                2 * crb_h * as);
    // Efficient estimators: within 30 % of the bound for 100 runs.
    EXPECT_NEAR(std::sqrt(se_l) / crb_pos, 1.0, 0.3);
    EXPECT_NEAR(std::sqrt(sh_l) / crb_h, 1.0, 0.3);
    EXPECT_NEAR(std::sqrt(se_t) / crb_pos, 1.0, 0.3);
    EXPECT_NEAR(std::sqrt(sh_t) / crb_h, 1.0, 0.3);
  }
}
