// The scoring library (lcmloc/core/scoring.hpp): numbers worked out by hand, and the chi-square
// quantile of any dof against Boost.Math's.
#include <cmath>
#include <stdexcept>
#include <vector>

#include <boost/math/distributions/chi_squared.hpp>
#include <gtest/gtest.h>

#include "lcmloc/core/chi2.hpp"
#include "lcmloc/core/scoring.hpp"

using namespace lcmloc;

TEST(Chi2AnyDof, MatchesBoostOverTheRangeTheEvaluationUses) {
  for (double dof : {0.5, 1.0, 2.0, 3.0, 7.5, 42.0, 100.0, 6000.0, 3.0e6})
    for (double p : {1e-6, 0.025, 0.05, 0.5, 0.95, 0.975, 1.0 - 1e-6}) {
      const double expected = boost::math::quantile(boost::math::chi_squared_distribution<double>(dof), p);
      EXPECT_NEAR(core::chi2QuantileAnyDof(p, dof), expected, 1e-10 * expected) << "dof " << dof << " p " << p;
    }
}

TEST(Chi2AnyDof, AgreesWithTheIntegerQuantileAndRefusesBadArguments) {
  for (int dof = 1; dof <= 10; ++dof)
    EXPECT_NEAR(core::chi2QuantileAnyDof(0.99, dof), core::chi2Quantile(0.99, dof), 1e-9) << dof;
  EXPECT_THROW(core::chi2QuantileAnyDof(0.5, 0.0), std::invalid_argument);
  EXPECT_THROW(core::chi2QuantileAnyDof(1.0, 2.0), std::invalid_argument);
  EXPECT_THROW(core::chi2QuantileAnyDof(0.0, 2.0), std::invalid_argument);
}

TEST(Scoring, ErrorStatisticsByHand) {
  const auto s = core::errorStats({3.0, -4.0});
  EXPECT_EQ(s.n, 2);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(12.5));
  EXPECT_DOUBLE_EQ(s.mean, 3.5);
  EXPECT_DOUBLE_EQ(s.max, 4.0);
  EXPECT_DOUBLE_EQ(s.median, 3.5);
  EXPECT_DOUBLE_EQ(s.p95, 3.0 + 0.95);
  EXPECT_DOUBLE_EQ(core::rms({3.0, -4.0}), std::sqrt(12.5));
  EXPECT_EQ(core::rms({}), 0.0);
  EXPECT_EQ(core::errorStats({}).n, 0);
  EXPECT_DOUBLE_EQ(core::percentile({5, 1, 3}, 0.25), 2.0);
  EXPECT_DOUBLE_EQ(core::percentile({5, 1, 3}, 2.0), 5.0);  // clamped
}

TEST(Scoring, NeesOfADiagonalCovarianceAndRefusalOfAnIndefiniteOne) {
  const Eigen::Matrix2d P = Eigen::Vector2d(4.0, 0.25).asDiagonal();
  const auto n = core::nees<2>(Eigen::Vector2d(2.0, 1.0), P);
  ASSERT_TRUE(n.has_value());
  EXPECT_DOUBLE_EQ(*n, 1.0 + 4.0);
  Eigen::Matrix3d bad = Eigen::Matrix3d::Identity();
  bad(2, 2) = -1.0;
  EXPECT_FALSE(core::nees<3>(Eigen::Vector3d(1, 1, 1), bad).has_value());
}

TEST(Scoring, DriftIsTheErrorChangeOverTheDistanceTravelled) {
  // 0, 5, 10, 15 m along; the x error grows by 0.1 m every 5 m: 2 % over any 10 m.
  const std::vector<core::DriftSample> s{{0, 0.0, 0}, {5, 0.1, 0}, {10, 0.2, 0}, {15, 0.3, 0}};
  const auto d = core::drift(s, 10.0);
  EXPECT_EQ(d.segments, 2);
  EXPECT_NEAR(d.mean_pct, 2.0, 1e-12);
  EXPECT_NEAR(d.max_pct, 2.0, 1e-12);
  EXPECT_EQ(core::drift(s, 20.0).segments, 0);
}

TEST(Scoring, DecisionsOnFaultsAndGenuineMeasurements) {
  core::FaultCounts c;
  core::countDecision(c, true, "accepted", false);
  core::countDecision(c, false, "gate", false);
  core::countDecision(c, false, "gate", true);
  core::countDecision(c, true, "accepted", true);
  core::countDecision(c, false, "dead_reckoning", true);
  EXPECT_EQ(c.accepted, 2);
  EXPECT_EQ(c.rejected, 2);
  EXPECT_EQ(c.ignored, 1);
  EXPECT_EQ(c.faults_decided, 3);
  EXPECT_EQ(c.faults_accepted, 1);
  EXPECT_EQ(c.faults_rejected, 1);
  EXPECT_EQ(c.valid_rejected, 1);
}

TEST(Scoring, GateStatisticsGroupByFilterAndSensor) {
  const std::vector<core::GateRecord> g{{1, "ukf", "A", "accepted", 2, 1.0, true},
                                        {2, "ukf", "B", "gate", 2, 30.0, false},
                                        {3, "dr", "A", "dead_reckoning", 0, NAN, false}};
  const auto st = core::gateStatistics(g, 0.95);
  ASSERT_EQ(st.by_filter.size(), 2u);
  EXPECT_EQ(st.by_filter[0].filter, "dr");
  EXPECT_EQ(st.by_filter[0].ignored, 1);
  EXPECT_EQ(st.by_filter[1].accepted, 1);
  EXPECT_EQ(st.by_filter[1].rejected, 1);
  EXPECT_DOUBLE_EQ(st.by_filter[1].nis_mean_all, 15.5);
  EXPECT_EQ(st.by_filter[1].nis.samples, 1);
  ASSERT_EQ(st.by_sensor.size(), 2u);
  EXPECT_EQ(st.by_sensor[0].decisions, 2);  // A: ukf and dr
  EXPECT_EQ(st.by_filter_sensor.size(), 3u);
}

// The longest run of rejections of one filter and sensor: in decisions, and in seconds from its
// first rejection to the acceptance that ended it; a run the log ends in is measured to its last
// rejection; ignored decisions neither break nor count; another filter's decisions are apart.
TEST(Scoring, LongestRejectionRunPerFilter) {
  auto rec = [](int64_t t_s, const char* filter, const char* reason, bool accepted) {
    return core::GateRecord{t_s * 1000000, filter, "GPS", reason, 2, accepted ? 1.0 : 30.0, accepted};
  };
  const std::vector<core::GateRecord> g{
      rec(0, "ukf", "accepted", true),  rec(1, "ukf", "gate", false),    rec(2, "ukf", "gate", false),
      rec(3, "ekf", "gate", false),     rec(4, "ukf", "accepted", true), rec(5, "ukf", "gate", false),
      rec(6, "ukf", "gate", false),     rec(7, "ukf", "dead_reckoning", false), rec(9, "ukf", "gate", false),
      rec(12, "ukf", "relocalized", true), rec(13, "ekf", "gate", false)};
  const auto st = core::gateStatistics(g, 0.95);
  ASSERT_EQ(st.by_filter_sensor.size(), 2u);
  const auto& ekf = st.by_filter_sensor[0];
  const auto& ukf = st.by_filter_sensor[1];
  EXPECT_EQ(ukf.filter, "ukf");
  EXPECT_EQ(ukf.longest_rejection_run, 3);  // 5, 6, 9 (7 ignored), ended by the re-localization at 12
  EXPECT_DOUBLE_EQ(ukf.longest_rejection_s, 7.0);
  EXPECT_EQ(ekf.longest_rejection_run, 2);  // 3 and 13: never ended, measured to the last
  EXPECT_DOUBLE_EQ(ekf.longest_rejection_s, 10.0);
  EXPECT_EQ(st.by_sensor.at(0).longest_rejection_run, 0);  // several filters together: no run
}
