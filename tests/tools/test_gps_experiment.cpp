// §3 scenario of seeds/002 (small version of lcmloc-gps-experiment): bounds measured with
// config/gps_paper.yaml, seed 1 (tvekf: converged at 0.0 s, steady RMSE 1.02 m vs raw GPS
// 3.97 m; ukf_gps 1.06 m; with the simulator's magnetic disturbance and the magnetometer bias
// state 1.57 m and 1.40 m; without the self-calibration states and with the paper's noise
// defaults 2.07 m and 1.75 m).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "lcmloc/app/config.hpp"
#include "lcmloc/gps_experiment/monte_carlo.hpp"
#include "lcmloc/gps_experiment/printing.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

using namespace lcmloc;

TEST(GpsExperiment, ConvergesFromOriginAndBeatsRawGps) {
  auto cfg = simconfig::loadSimSystemConfig(LCMLOC_GPS_PAPER_YAML);
  ASSERT_NEAR(cfg.scenario.path.x0, 150.0, 1e-9);
  ASSERT_NEAR(cfg.fusion.filter.initial_pose[0], 0.0, 1e-9);
  std::vector<core::FilterConfig> filters;
  for (const char* t : {"tvekf", "ukf_gps"}) {
    core::FilterConfig f = cfg.fusion.filter;
    f.type = t;
    filters.push_back(f);
  }
  gps_experiment::Options opt;
  const auto r = gps_experiment::run(cfg.scenario, filters, opt);
  ASSERT_EQ(r.filters.size(), 2u);
  EXPECT_GT(r.gps_rmse_all_m, 3.0);  // uniform +-5 m per axis: 4.08 m expected
  EXPECT_LT(r.gps_rmse_all_m, 5.0);
  for (const auto& s : r.filters) {
    EXPECT_GE(s.convergence_s, 0.0) << s.filter;
    EXPECT_LE(s.convergence_s, 1.0) << s.filter;        // the paper: within about 1 s
    EXPECT_LT(s.steady_rmse_m, 1.4) << s.filter;        // measured 1.02 / 1.06
    EXPECT_LT(s.steady_rmse_m, 0.7 * s.gps_rmse_m) << s.filter;
    EXPECT_LT(s.steady_max_m, 5.0) << s.filter;         // measured 3.81
    EXPECT_EQ(s.gps_rejected, 0) << s.filter;
  }
  const std::string dir = (std::filesystem::temp_directory_path() / "lcmloc_gps_experiment_test").string();
  gps_experiment::writeReport(r, opt, dir);
  EXPECT_TRUE(std::filesystem::exists(dir + "/report.json"));
}

TEST(GpsExperiment, DeadReckoningNeverConvergesAndHasNoSteadyStateInTheReport) {
  auto cfg = simconfig::loadSimSystemConfig(LCMLOC_GPS_PAPER_YAML);
  core::FilterConfig f = cfg.fusion.filter;
  f.type = "dead_reckoning";  // starts 158 m off and never sees a fix
  gps_experiment::Options opt;
  const auto r = gps_experiment::run(cfg.scenario, {f}, opt);
  ASSERT_EQ(r.filters.size(), 1u);
  EXPECT_FALSE(r.filters[0].converged());
  const std::string dir = (std::filesystem::temp_directory_path() / "lcmloc_gps_experiment_dr").string();
  gps_experiment::writeReport(r, opt, dir);
  std::ifstream in(dir + "/report.json");
  const auto j = nlohmann::json::parse(in);
  const auto& dr = j.at("filters").at("dead_reckoning");
  EXPECT_FALSE(dr.at("converged").get<bool>());
  for (const char* k : {"convergence_s", "steady_rmse_m", "steady_max_m", "gps_rmse_same_period_m", "ratio_to_gps"})
    EXPECT_TRUE(dr.at(k).is_null()) << k;  // not a zero error
  std::filesystem::remove_all(dir);
}

TEST(GpsExperiment, ExtendedPathRepeatsTheSegmentsUntilTheDriveIsLongEnough) {
  auto cfg = simconfig::loadSimSystemConfig(LCMLOC_GPS_PAPER_YAML);
  const auto& sc = cfg.scenario;
  double lap = 0;
  for (const auto& s : sc.path.segments) lap += s.length;
  const auto p = gps_experiment::extendedPath(sc, 240.0);
  double length = 0;
  for (const auto& s : p.segments) length += s.length;
  EXPECT_GE(length / sc.vehicle.speed, 240.0);
  EXPECT_LT((length - lap) / sc.vehicle.speed, 240.0);  // not one lap more than needed
  EXPECT_EQ(p.segments.size() % sc.path.segments.size(), 0u);
  EXPECT_EQ(gps_experiment::extendedPath(sc, 0.0).segments.size(), sc.path.segments.size());
}

// A small version of the steady-state Monte Carlo (the command runs 100 seeds over 20 minutes).
TEST(GpsExperiment, MonteCarloScoresEverySeedAtEveryRateAfterSettling) {
  auto cfg = simconfig::loadSimSystemConfig(LCMLOC_GPS_PAPER_YAML);
  std::vector<core::FilterConfig> filters;
  for (const char* t : {"ukf_gps", "dead_reckoning"}) {
    core::FilterConfig f = cfg.fusion.filter;
    f.type = t;
    filters.push_back(f);
  }
  gps_experiment::MonteCarloOptions opt;
  opt.runs = 3;
  opt.min_drive_s = 60.0;
  int calls = 0;
  const auto m = gps_experiment::monteCarlo(cfg.scenario, filters, opt, [&](int done, int total) {
    EXPECT_EQ(done, ++calls);
    EXPECT_EQ(total, 6);
  });
  EXPECT_EQ(calls, 6);
  EXPECT_GE(m.drive_s, 60.0);
  ASSERT_EQ(m.groups.size(), 4u);  // rate-major: (1 Hz, ukf_gps), (1 Hz, dr), (10 Hz, ukf_gps), (10 Hz, dr)
  for (std::size_t g = 0; g < 4; ++g) {
    ASSERT_EQ(m.groups[g].runs.size(), 3u);
    EXPECT_EQ(m.groups[g].rate_hz, g < 2 ? 1.0 : 10.0);
    for (int i = 0; i < 3; ++i) EXPECT_EQ(m.groups[g].runs[i].seed, cfg.scenario.seed + static_cast<uint64_t>(i));
  }
  const auto& ukf1 = m.groups[0];
  const auto& ukf10 = m.groups[2];
  EXPECT_EQ(ukf1.filter, "ukf_gps");
  EXPECT_EQ(ukf1.converged, 3);
  EXPECT_EQ(ukf10.converged, 3);
  EXPECT_EQ(m.groups[1].converged, 0);  // dead reckoning starts 158 m off and never sees a fix
  for (const auto& r : ukf1.runs) {
    EXPECT_GT(r.rmse_m, 0.0);
    EXPECT_LT(r.rmse_m, 5.0);  // after settling the error stays about the 5 m threshold or below
    EXPECT_GT(r.nees_mean, 0.0);
  }
  // The seeds differ: three runs do not give one result.
  EXPECT_NE(ukf1.runs[0].rmse_m, ukf1.runs[1].rmse_m);
  // Ten times the fixes: a smaller error at the median.
  EXPECT_LT(ukf10.rmse_median, ukf1.rmse_median);
  EXPECT_LE(ukf1.rmse_median, ukf1.rmse_p95);

  // Deterministic: the same seeds give the same figures.
  const auto again = gps_experiment::monteCarlo(cfg.scenario, filters, opt);
  EXPECT_EQ(again.groups[0].rmse_median, ukf1.rmse_median);
  EXPECT_EQ(again.groups[2].nees_mean, ukf10.nees_mean);

  const std::string dir = (std::filesystem::temp_directory_path() / "lcmloc_gps_experiment_mc").string();
  std::filesystem::create_directories(dir);
  gps_experiment::writeMonteCarlo(m, opt, dir);
  std::ifstream in(dir + "/montecarlo.json");
  const auto j = nlohmann::json::parse(in);
  ASSERT_EQ(j.at("groups").size(), 4u);
  EXPECT_EQ(j.at("groups")[0].at("runs").size(), 3u);
  EXPECT_DOUBLE_EQ(j.at("groups")[0].at("rmse_median_m").get<double>(), ukf1.rmse_median);
  EXPECT_TRUE(j.at("groups")[1].at("rmse_median_m").is_null());  // no run of dead reckoning settled
  std::filesystem::remove_all(dir);
}

namespace {

std::vector<core::FilterConfig> tvekfAndUkf(const core::FilterConfig& base) {
  return gps_experiment::filterConfigs({"tvekf", "ukf_gps"}, base);  // as the command's --filters
}

/// What every run of a steady-state group must show: settled, no lock-out, below 5 m by the
/// second fix, the odometer scale and steering bias found (the simulator's odometer measures
/// 1.01 of the truth, so true = (1 + k) measured with k = 1/1.01 - 1; its steering reads 0.5 deg
/// too much).
void expectSettledAndCalibrated(const gps_experiment::McGroup& g, const sim::ScenarioConfig& sc, int runs) {
  EXPECT_EQ(g.converged, runs) << g.filter;
  EXPECT_EQ(g.with_lockout, 0) << g.filter;
  const double k_true = 1.0 / (1.0 + sc.odometry.scale_error) - 1.0;
  for (const auto& r : g.runs) {
    EXPECT_GE(r.second_fix_error_m, 0.0) << g.filter << " seed " << r.seed;
    EXPECT_LT(r.second_fix_error_m, 5.0) << g.filter << " seed " << r.seed;
    for (const auto& c : r.calibration) {
      if (c.name == "odo_scale") {
        EXPECT_NEAR(c.value, k_true, std::max(3.0 * c.sigma, 0.002)) << g.filter << " seed " << r.seed;
      } else if (c.name == "steering_bias") {
        EXPECT_NEAR(c.value, sc.odometry.steering_bias, std::max(3.0 * c.sigma, 3e-4)) << g.filter << " seed " << r.seed;
      }
    }
  }
}

}  // namespace

// The steady state of the Monte Carlo, small: 4 seeds at 1 Hz over the default 20-minute drive
// with config/gps_paper.yaml (the paper's white-noise magnetometer; odometer scale, steering
// bias and accelerometer bias states on). Measured: tvekf 0.32-0.46 m per seed (median 0.42 m),
// ukf_gps 0.28-0.43 m (median 0.41 m), mean NEES 1.8-3.3; 100 seeds: docs/tvekf.md.
TEST(GpsExperiment, SteadyStateAtOneHertzOverTwentyMinutes) {
  auto cfg = simconfig::loadSimSystemConfig(LCMLOC_GPS_PAPER_YAML);
  ASSERT_EQ(cfg.scenario.imu.mag_disturbance_std, 0.0);
  ASSERT_TRUE(cfg.fusion.filter.calibration.odo_scale);
  ASSERT_TRUE(cfg.fusion.filter.calibration.steering_bias);
  gps_experiment::MonteCarloOptions opt;
  opt.runs = 4;
  opt.rates_hz = {1.0};
  ASSERT_GE(opt.min_drive_s, 1200.0);
  const auto m = gps_experiment::monteCarlo(cfg.scenario, tvekfAndUkf(cfg.fusion.filter), opt);
  ASSERT_EQ(m.groups.size(), 2u);
  EXPECT_GE(m.drive_s, 1200.0);
  for (const auto& g : m.groups) {
    expectSettledAndCalibrated(g, cfg.scenario, 4);
    const bool tvekf = g.filter == "tvekf";
    EXPECT_LE(g.rmse_median, tvekf ? 0.6 : 0.5) << g.filter;  // the bounds of the 100-seed median
    EXPECT_LE(g.nees_mean, 3.0) << g.filter;
    for (const auto& r : g.runs) {
      EXPECT_LT(r.rmse_m, tvekf ? 0.75 : 0.65) << g.filter << " seed " << r.seed;
      EXPECT_LT(r.nees_mean, 4.5) << g.filter << " seed " << r.seed;
      ASSERT_EQ(r.calibration.size(), 3u) << g.filter;  // odometer scale, steering and accelerometer bias
    }
  }
}

// A disturbed magnetometer (the simulator's 0.005 G over 0.2 G, correlated over 10 s; not in
// the paper's model) with the magnetometer bias state on: 4 seeds at 1 Hz over 240 s. Measured:
// tvekf 1.12-1.44 m per seed (median 1.38 m), ukf_gps 0.82-1.26 m (median 1.04 m), mean NEES
// 1.2-3.9. The heading it leaves (about 0.012 rad)
// holds the 1 Hz error near 1 m at any drive length (docs/tvekf.md "A disturbed magnetometer").
// Without the bias state (and with the paper's noise defaults) the medians were 3.70 m and
// 3.05 m with mean NEES 58 and 45, which these bounds refuse.
TEST(GpsExperiment, DisturbedMagnetometerWithTheBiasState) {
  auto cfg = simconfig::loadSimSystemConfig(LCMLOC_GPS_PAPER_YAML);
  cfg.scenario.imu.mag_disturbance_std = 0.005;
  cfg.scenario.imu.mag_disturbance_tau = 10.0;
  auto& cal = cfg.fusion.filter.calibration;
  cal.mag_bias = true;
  cal.mag_bias_std = 0.025;
  cal.mag_bias_tau = 10.0;
  gps_experiment::MonteCarloOptions opt;
  opt.runs = 4;
  opt.rates_hz = {1.0};
  opt.min_drive_s = 240.0;
  const auto m = gps_experiment::monteCarlo(cfg.scenario, tvekfAndUkf(cfg.fusion.filter), opt);
  ASSERT_EQ(m.groups.size(), 2u);
  for (const auto& g : m.groups) {
    expectSettledAndCalibrated(g, cfg.scenario, 4);
    EXPECT_LT(g.rmse_median, g.filter == "tvekf" ? 1.7 : 1.35) << g.filter;
    EXPECT_LT(g.nees_mean, 3.5) << g.filter;  // consistent: 3 for (x, y, theta)
    for (const auto& r : g.runs) {
      EXPECT_LT(r.rmse_m, g.filter == "tvekf" ? 2.0 : 1.6) << g.filter << " seed " << r.seed;
      EXPECT_LT(r.nees_mean, 6.0) << g.filter << " seed " << r.seed;
      ASSERT_EQ(r.calibration.size(), 4u) << g.filter;
      for (const auto& c : r.calibration) {
        if (c.name == "mag_bias") {
          EXPECT_LT(c.sigma, cal.mag_bias_std) << g.filter;
        }
      }
    }
  }
}
