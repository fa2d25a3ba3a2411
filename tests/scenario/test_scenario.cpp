// Scenario tests: the simulated world and sensors driving the fusion engine in process.
// Seeded and deterministic; the bounds asserted were measured (see the printed lines) and
// carry a margin.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "lcmloc/core/chi2.hpp"
#include "lcmloc/models/scenario_runner.hpp"

using namespace lcmloc;
using namespace lcmloc::models;

namespace {

std::vector<core::FilterConfig> filtersOf(std::initializer_list<const char*> types) {
  std::vector<core::FilterConfig> out;
  for (const char* t : types) {
    core::FilterConfig f;
    f.type = t;
    out.push_back(f);
  }
  return out;
}

/// Mean position error over [from, to) fractions of the track.
double meanError(const ScenarioFilterResult& r, double from, double to) {
  const auto n = r.track.size();
  double sum = 0.0;
  int count = 0;
  for (auto i = static_cast<std::size_t>(from * n); i < static_cast<std::size_t>(to * n); ++i) {
    const auto& p = r.track[i];
    sum += std::hypot(p.estimate.x(0) - p.truth.x(), p.estimate.x(1) - p.truth.y());
    ++count;
  }
  return count ? sum / count : 0.0;
}

double errorAt(const ScenarioFilterResult& r, int64_t utime) {
  for (const auto& p : r.track)
    if (p.utime >= utime) return std::hypot(p.estimate.x(0) - p.truth.x(), p.estimate.x(1) - p.truth.y());
  return NAN;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? NAN : v[v.size() / 2];
}

}  // namespace

TEST(PaperScenario, GatedRejectsFaultsUngatedJumpsDeadReckoningDrifts) {
  const ScenarioConfig sc;  // 20 markers 2 m apart, two fault markers
  const auto res = runScenario(sc, filtersOf({"dead_reckoning", "ukf", "ukf_gated"}));
  ASSERT_EQ(res.map.size(), 20u);
  ASSERT_EQ(res.filters.size(), 3u);
  const auto& dr = res.filters[0];
  const auto& ukf = res.filters[1];
  const auto& gated = res.filters[2];
  for (const auto& f : res.filters) {
    std::printf("%-15s rmse %.4f max %.4f final %.4f accepted %d rejected %d faults %d/%d "
                "valid_rejected %d mean NEES %.2f\n", f.filter.c_str(), f.rmse_m, f.max_error_m,
                f.final_error_m, f.accepted, f.rejected, f.faults_rejected, f.faults_total,
                f.valid_rejected, f.mean_nees);
    EXPECT_EQ(f.faults_total, 2);
    EXPECT_EQ(f.decisions.size(), 22u);  // 20 markers + 2 faults
    EXPECT_GT(f.track.size(), 2500u);    // ~31 s at 100 Hz
  }
  // Gated UKF: both faults rejected, every valid marker accepted, error small. The default
  // encoders carry a 1 % scale error and a 0.5 deg steering bias (measured, seed 1: max error
  // 4.2 cm, RMSE 2.3 cm; over 200 seeds RMSE median 2.4 cm, p95 2.5 cm).
  EXPECT_EQ(gated.faults_rejected, 2);
  EXPECT_EQ(gated.valid_rejected, 0);
  EXPECT_LT(gated.max_error_m, 0.06);
  EXPECT_LT(gated.rmse_m, 0.035);
  EXPECT_FALSE(gated.locked_out);

  // Ungated UKF: takes both faults, and its error jumps at each (measured max about 0.27 m).
  EXPECT_EQ(ukf.faults_rejected, 0);
  EXPECT_GT(ukf.max_error_m, 0.15);
  EXPECT_GT(ukf.max_error_m, 5.0 * gated.max_error_m);
  for (std::size_t i = 0; i < ukf.decisions.size(); ++i) {
    if (!ukf.decision_is_fault[i]) continue;
    const int64_t t = ukf.decisions[i].utime;
    const double before = errorAt(ukf, t - 20000), after = errorAt(ukf, t + 1);
    std::printf("ukf error at fault %lld: %.3f m before, %.3f m after\n",
                static_cast<long long>(t), before, after);
    // Measured (seed 1): +0.20 m at the phantom marker, +0.07 m at the wrong offset (the valid
    // marker 13 it coincides with is taken right after and pulls part of it back).
    EXPECT_GT(after - before, 0.04);
  }

  // Dead reckoning: uses no marker, error grows along the run.
  EXPECT_EQ(dr.accepted, 0);
  const double early = meanError(dr, 0.0, 0.25), late = meanError(dr, 0.75, 1.0);
  std::printf("dead reckoning mean error: first quarter %.4f m, last quarter %.4f m\n", early, late);
  EXPECT_GT(late, 2.0 * early);
}

TEST(PaperScenario, DeterministicForASeed) {
  ScenarioConfig sc;
  sc.seed = 42;
  const auto a = runScenario(sc, filtersOf({"ukf_gated"}));
  const auto b = runScenario(sc, filtersOf({"ukf_gated"}));
  ASSERT_EQ(a.filters[0].track.size(), b.filters[0].track.size());
  for (std::size_t i = 0; i < a.filters[0].track.size(); ++i)
    ASSERT_EQ(a.filters[0].track[i].estimate.x, b.filters[0].track[i].estimate.x) << i;
  sc.seed = 43;
  const auto c = runScenario(sc, filtersOf({"ukf_gated"}));
  EXPECT_NE(a.filters[0].rmse_m, c.filters[0].rmse_m);
}

TEST(PaperScenario, ValidMarkersRejectedAtMostAtTheGateRate) {
  ScenarioConfig sc;
  sc.faults.clear();
  const auto filters = filtersOf({"ukf_gated"});
  const double p = filters[0].gate.probability;
  int decisions = 0, rejected = 0;
  double maha_sum = 0.0;
  for (uint64_t seed = 1; seed <= 50; ++seed) {
    sc.seed = seed;
    const auto& r = runScenario(sc, filters).filters[0];
    EXPECT_EQ(r.faults_total, 0);
    EXPECT_EQ(r.decisions.size(), 20u) << "seed " << seed;
    decisions += static_cast<int>(r.decisions.size());
    rejected += r.valid_rejected;
    for (const auto& d : r.decisions) maha_sum += d.mahalanobis;
  }
  const double expected = (1.0 - p) * decisions;
  std::printf("valid markers rejected: %d of %d (gate p = %.2f expects %.1f if the filter were "
              "consistent); mean Mahalanobis %.3f (chi2 with 2 dof: 2)\n",
              rejected, decisions, p, expected, maha_sum / decisions);
  // The filter's noise (paper Pv, Pw per 2 m) is conservative for this ruler (mean Mahalanobis
  // below 2), so fewer than (1 - p) are rejected; a rate clearly above (1 - p) would be a bug.
  EXPECT_LE(rejected, 3.0 * expected + 3.0);
  EXPECT_LT(maha_sum / decisions, 2.0 * 1.5);
}

TEST(RealisticEncoders, CalibratedFilterDoesNotLockOut) {
  ScenarioConfig sc;
  sc.odometry.scale_error = 0.01;        // 1 % odometer scale error
  sc.odometry.steering_bias = 0.008727;  // 0.5 deg steering bias
  const auto filters = filtersOf({"dead_reckoning", "ukf_gated", "ukf_calib"});
  constexpr int kSeeds = 30;
  int lock_gated = 0, lock_calib = 0, faults_calib = 0, valid_rej_calib = 0;
  std::vector<double> rmse_gated, rmse_calib, final_dr;
  for (uint64_t seed = 1; seed <= kSeeds; ++seed) {
    sc.seed = seed;
    const auto res = runScenario(sc, filters);
    final_dr.push_back(res.filters[0].final_error_m);
    lock_gated += res.filters[1].locked_out;
    rmse_gated.push_back(res.filters[1].rmse_m);
    const auto& c = res.filters[2];
    lock_calib += c.locked_out;
    rmse_calib.push_back(c.rmse_m);
    faults_calib += c.faults_rejected;
    valid_rej_calib += c.valid_rejected;
  }
  std::printf("%d seeds, 1%% scale error + 0.5 deg bias: dead reckoning final error median "
              "%.3f m (min %.3f)\n", kSeeds, median(final_dr),
              *std::min_element(final_dr.begin(), final_dr.end()));
  std::printf("  ukf_gated: lock-outs %d, RMSE median %.4f max %.4f m\n", lock_gated,
              median(rmse_gated), *std::max_element(rmse_gated.begin(), rmse_gated.end()));
  std::printf("  ukf_calib: lock-outs %d, RMSE median %.4f max %.4f m, faults rejected %d/%d, "
              "valid rejected %d\n", lock_calib, median(rmse_calib),
              *std::max_element(rmse_calib.begin(), rmse_calib.end()), faults_calib, 2 * kSeeds,
              valid_rej_calib);
  // Dead reckoning drifts by tens of centimetres with these encoder errors.
  EXPECT_GT(*std::min_element(final_dr.begin(), final_dr.end()), 0.2);
  // Calibrating filter: no lock-out, RMSE of a few mm (measured median 0.75 cm, max 0.9 cm).
  EXPECT_EQ(lock_calib, 0);
  EXPECT_EQ(faults_calib, 2 * kSeeds);
  EXPECT_EQ(valid_rej_calib, 0);
  EXPECT_LT(median(rmse_calib), 0.02);
  EXPECT_LT(*std::max_element(rmse_calib.begin(), rmse_calib.end()), 0.03);
  // The calibrating filter beats the plain gated one when the encoders are biased.
  EXPECT_LT(median(rmse_calib), median(rmse_gated));
}
