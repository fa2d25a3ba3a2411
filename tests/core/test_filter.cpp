// Filters of the magnetic-ruler family: gate, association, lock-out, hot swap, calibration.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "lcmloc/core/chi2.hpp"
#include "lcmloc/core/filter.hpp"
#include "lcmloc/core/ruler_model.hpp"
#include "lcmloc/core/vehicle_model.hpp"

using namespace lcmloc::core;

namespace {

constexpr double kL1 = 1.5;

FilterConfig config(const std::string& type) {
  FilterConfig c;
  c.type = type;
  return c;
}

/// Straight road north from (0, 0): marker i sits on the centre line at y = 2 (i + 1) + L1, i.e.
/// under the ruler when M has travelled 2 (i + 1) m.
MarkerMap straightMap(int n) {
  MarkerMap m;
  for (int i = 0; i < n; ++i) m.push_back(Marker{i, 0.0, 2.0 * (i + 1) + kL1});
  return m;
}

OdometryInput odometry(int64_t utime, double ds, double steering = 0.0) {
  OdometryInput o;
  o.utime = utime;
  o.delta_s = ds;
  o.has_steering = true;
  o.steering = steering;
  return o;
}

RulerDetection detection(int64_t utime, double dm) {
  RulerDetection d;
  d.utime = utime;
  d.lateral_offset = dm;
  return d;
}

/// Drives `metres` straight in 2 cm steps.
void drive(Filter& f, double metres, int64_t& utime) {
  for (int k = 0; k < static_cast<int>(std::lround(metres / 0.02)); ++k)
    f.predict(odometry(utime += 10000, 0.02));
}

}  // namespace

TEST(FilterFactory, TypesUnknownTypeAndBadConfig) {
  const auto types = filterTypes();
  ASSERT_EQ(types.size(), 4u);
  for (const auto& t : types) EXPECT_EQ(makeFilter(config(t), {})->name(), t);
  try {
    makeFilter(config("kalman_magic"), {});
    FAIL() << "unknown type accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("kalman_magic"), std::string::npos);
  }
  FilterConfig bad = config("ukf_gated");
  bad.wheelbase = 0.0;
  try {
    makeFilter(bad, {});
    FAIL() << "wheelbase 0 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("wheelbase"), std::string::npos);
  }
  bad = config("ukf_gated");
  bad.gate.probability = 1.0;
  EXPECT_THROW(makeFilter(bad, {}), std::invalid_argument);
}

TEST(Gate, ThresholdForms) {
  GateConfig g;
  EXPECT_NEAR(g.threshold(2), 9.2103, 1e-4);  // default: 99% on the innovation's 2 dof
  g.dof = 1;
  EXPECT_NEAR(g.threshold(2), 6.6349, 1e-4);  // the paper's reading
  g.dof = 0;
  g.value = 6.635;
  EXPECT_DOUBLE_EQ(g.threshold(2), 6.635);   // explicit value wins
  GateConfig p95;
  p95.probability = 0.95;
  EXPECT_NEAR(p95.threshold(2), 5.9915, 1e-4);
}

TEST(Gate, DecisionAtTheBoundaryForValueAndProbability) {
  const MarkerMap map = straightMap(3);
  auto run = [&](const FilterConfig& c) {
    auto f = makeFilter(c, map);
    int64_t t = 0;
    drive(*f, 2.0, t);
    const FilterState before = f->state();
    const GateDecision d = f->update(detection(t, 0.3));
    return std::make_tuple(d, before, f->state());
  };
  const auto [ref, ref_before, ref_after] = run(config("ukf"));
  ASSERT_TRUE(ref.accepted);
  EXPECT_EQ(ref.reason, "ungated");
  EXPECT_TRUE(std::isinf(ref.gate));
  EXPECT_EQ(ref.marker_id, 0);
  ASSERT_EQ(ref.innovation.size(), 2);
  const double m = ref.mahalanobis;
  ASSERT_GT(m, 0.1);  // a clearly non-zero innovation
  EXPECT_NE(ref_after.x, ref_before.x);

  for (const double f : {1 + 1e-9, 1 - 1e-9}) {
    FilterConfig c = config("ukf_gated");
    c.gate.value = m * f;
    const auto [d, before, after] = run(c);
    EXPECT_DOUBLE_EQ(d.mahalanobis, m);
    EXPECT_DOUBLE_EQ(d.gate, m * f);
    EXPECT_EQ(d.accepted, f > 1) << f;
    EXPECT_EQ(d.reason, f > 1 ? "accepted" : "gate");
    if (f < 1) {
      EXPECT_EQ(after.x, before.x);  // a rejected measurement leaves the prior untouched
      EXPECT_EQ(after.P, before.P);
    } else {
      EXPECT_EQ(after.x, ref_after.x);
    }
  }
  const double p = chi2Cdf(m, 2);
  for (const double dp : {1e-9, -1e-9}) {
    FilterConfig c = config("ukf_gated");
    c.gate.probability = p + dp;
    const auto [d, before, after] = run(c);
    EXPECT_NEAR(d.gate, m, 1e-6);
    EXPECT_EQ(d.accepted, dp > 0) << dp;
  }
}

TEST(Association, NeverPicksAMarkerBehindTheVehicle) {
  // Start at (0, 0) heading north. A marker 1.5 m BEHIND has exactly the measured range; with
  // the heading flipped by pi it would even match the bearing. It must never be a candidate.
  const MarkerMap behind{{7, 0.0, -kL1}};
  auto f = makeFilter(config("ukf"), behind);
  const FilterState before = f->state();
  const GateDecision d = f->update(detection(1, 0.0));
  EXPECT_FALSE(d.accepted);
  EXPECT_EQ(d.reason, "no_candidate");
  EXPECT_EQ(d.marker_id, -1);
  EXPECT_EQ(d.innovation.size(), 0);
  EXPECT_EQ(f->state().x, before.x);

  const MarkerMap both{{7, 0.0, -kL1}, {8, 0.02, kL1}};
  auto g = makeFilter(config("ukf_gated"), both);
  const GateDecision e = g->update(detection(1, -0.02));
  EXPECT_TRUE(e.accepted);
  EXPECT_EQ(e.marker_id, 8);
}

TEST(Association, SmallestMahalanobisAmongReachableMarkers) {
  // Two markers under the ruler, 10 cm left and 30 cm right; a third out of reach sideways.
  const MarkerMap map{{1, -0.1, kL1}, {2, 0.3, kL1}, {3, -1.0, kL1}};
  for (const double dm : {0.1, -0.3}) {
    auto f = makeFilter(config("ukf_gated"), map);
    const GateDecision d = f->update(detection(1, dm));
    EXPECT_TRUE(d.accepted);
    EXPECT_EQ(d.marker_id, dm > 0 ? 1 : 2);
  }
  auto f = makeFilter(config("ukf_gated"), map);
  EXPECT_EQ(f->update(detection(1, 0.9)).reason, "gate");  // only the far-out marker would fit
}

TEST(Filter, BadInputLeavesTheStateUntouched) {
  for (const auto& type : filterTypes()) {
    auto f = makeFilter(config(type), straightMap(3));
    int64_t t = 0;
    drive(*f, 2.0, t);
    const FilterState before = f->state();
    f->predict(odometry(t + 1, std::numeric_limits<double>::quiet_NaN()));
    f->predict(odometry(t + 2, 0.02, std::numeric_limits<double>::infinity()));
    const GateDecision d = f->update(detection(t + 3, std::numeric_limits<double>::quiet_NaN()));
    EXPECT_FALSE(d.accepted) << type;
    EXPECT_EQ(d.reason, "bad_input") << type;
    EXPECT_EQ(f->state().x, before.x) << type;
    EXPECT_EQ(f->state().P, before.P) << type;
    EXPECT_TRUE(f->update(detection(t + 4, 0.0)).accepted || type == "dead_reckoning") << type;
  }
}

TEST(DeadReckoning, Eq1AndLinearisedCovariance) {
  auto f = makeFilter(config("dead_reckoning"), straightMap(3));
  f->predict(odometry(10, 2.0));  // one 2 m step north: F(0,2) = -2
  const FilterState s = f->state();
  EXPECT_NEAR(s.x[0], 0.0, 1e-15);
  EXPECT_NEAR(s.x[1], 2.0, 1e-15);
  EXPECT_NEAR(s.P(0, 0), 0.01 + 4 * 0.01 + 1e-4, 1e-15);  // + Pw over one pw_distance
  EXPECT_NEAR(s.P(0, 2), -0.02, 1e-15);
  EXPECT_NEAR(s.P(2, 2), 0.01 + 8.73e-3, 1e-15);
  EXPECT_EQ(s.status, FilterStatus::DeadReckoning);
  const GateDecision d = f->update(detection(11, 0.0));
  EXPECT_FALSE(d.accepted);
  EXPECT_EQ(d.reason, "dead_reckoning");
  // Along a curve the state follows eq. 1-2 exactly.
  Pose truth = s.x;
  for (int k = 0; k < 50; ++k) {
    f->predict(odometry(20 + k, 0.1, 0.2));
    truth = propagatePose(truth, 0.1, headingIncrement(0.1, 0.2, 2.5));
  }
  EXPECT_LT((f->state().x - truth).norm(), 1e-12);
}

TEST(ProcessNoise, ScaledByDistanceOrPerStep) {
  auto f = makeFilter(config("ukf_gated"), {});
  f->predict(odometry(1, 0.0));
  EXPECT_NEAR(f->state().P(2, 2), 0.01, 1e-15);  // standing still adds nothing
  f->predict(odometry(2, 2.0));                   // one marker interval: the printed Pw
  EXPECT_NEAR(f->state().P(2, 2), 0.01 + 8.73e-3, 1e-12);
  FilterConfig c = config("ukf_gated");
  c.pw_distance = 0.0;  // as printed, per step
  auto g = makeFilter(c, {});
  for (int k = 0; k < 50; ++k) g->predict(odometry(k, 0.02));  // 1 s at 50 Hz
  EXPECT_NEAR(g->state().P(2, 2), 0.01 + 50 * 8.73e-3, 1e-10);  // ~0.44 rad^2 per second
}

TEST(Lockout, ConsecutiveGateRejectionsInflateOnceAndRecover) {
  FilterConfig c = config("ukf_gated");
  auto f = makeFilter(c, straightMap(5));
  int64_t t = 0;
  for (int i = 0; i < 3; ++i) {  // three good markers shrink P0 first
    drive(*f, 2.0, t);
    ASSERT_TRUE(f->update(detection(t, 0.0)).accepted);
  }
  drive(*f, 2.0, t);
  Eigen::MatrixXd P_before;
  for (int i = 0; i < c.lockout_rejections; ++i) {
    EXPECT_EQ(f->state().status, FilterStatus::Ok);
    P_before = f->state().P;
    const GateDecision d = f->update(detection(++t, 0.45));  // far from the predicted 0
    EXPECT_EQ(d.reason, "gate");
  }
  EXPECT_EQ(f->state().status, FilterStatus::Lockout);
  EXPECT_TRUE(f->state().P.isApprox(P_before * c.lockout_inflation, 1e-14));
  // The inflated covariance lets the next valid marker in: recovered.
  drive(*f, 2.0, t);
  const GateDecision good = f->update(detection(++t, 0.0));
  EXPECT_TRUE(good.accepted);
  EXPECT_EQ(f->state().status, FilterStatus::Ok);

  // Inflation happens once per lock-out: with a gate nothing passes, P is inflated only once.
  FilterConfig tight = c;
  tight.gate.value = 1e-9;
  auto g = makeFilter(tight, straightMap(5));
  drive(*g, 2.0, t);
  const Eigen::MatrixXd P0 = g->state().P;
  for (int i = 0; i < 2 * c.lockout_rejections; ++i)
    EXPECT_EQ(g->update(detection(++t, 0.1)).reason, "gate");
  EXPECT_EQ(g->state().status, FilterStatus::Lockout);
  EXPECT_TRUE(g->state().P.isApprox(P0 * c.lockout_inflation, 1e-14));

  // The ungated filter never locks out.
  auto u = makeFilter(config("ukf"), straightMap(3));
  for (int i = 0; i < 5; ++i) u->update(detection(++t, 0.45));
  EXPECT_EQ(u->state().status, FilterStatus::Ok);
}

TEST(HotSwap, CopiesPoseAndCovarianceExtraStatesFromConfig) {
  const MarkerMap map = straightMap(5);
  auto gated = makeFilter(config("ukf_gated"), map);
  int64_t t = 0;
  drive(*gated, 2.0, t);
  ASSERT_TRUE(gated->update(detection(t, 0.02)).accepted);
  drive(*gated, 0.7, t);
  const FilterState s = gated->state();

  FilterConfig cc = config("ukf_calib");
  auto calib = makeFilter(cc, map);
  calib->initialize(s);
  const FilterState c = calib->state();
  ASSERT_EQ(c.x.size(), 5);
  EXPECT_EQ(c.names[3], "odo_scale");
  EXPECT_EQ(c.names[4], "steer_bias");
  EXPECT_EQ(Eigen::VectorXd(c.x.head(3)), s.x);
  EXPECT_EQ(Eigen::MatrixXd(c.P.topLeftCorner(3, 3)), s.P);
  EXPECT_EQ(c.x[3], 0.0);
  EXPECT_EQ(c.x[4], 0.0);
  EXPECT_DOUBLE_EQ(c.P(3, 3), cc.scale_std0 * cc.scale_std0);
  EXPECT_DOUBLE_EQ(c.P(4, 4), cc.steer_bias_std0 * cc.steer_bias_std0);
  EXPECT_TRUE(c.P.topRightCorner(3, 2).isZero(0.0));
  EXPECT_EQ(c.utime, s.utime);

  // Calibrated states survive a swap to a filter that has them too; a 3-state filter drops them.
  drive(*calib, 1.3, t);
  ASSERT_TRUE(calib->update(detection(t, 0.0)).accepted);
  const FilterState c2 = calib->state();
  auto calib2 = makeFilter(cc, map);
  calib2->initialize(c2);
  EXPECT_EQ(calib2->state().x, c2.x);
  EXPECT_EQ(calib2->state().P, c2.P);
  auto back = makeFilter(config("ukf_gated"), map);
  back->initialize(c2);
  EXPECT_EQ(back->state().x, Eigen::VectorXd(c2.x.head(3)));
  EXPECT_EQ(back->state().P, Eigen::MatrixXd(c2.P.topLeftCorner(3, 3)));

  FilterState broken = s;
  broken.x[0] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(back->initialize(broken), std::invalid_argument);
}
