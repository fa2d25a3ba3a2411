// lcmloc-fit-noise: noise fitted against the truth recovers the noise a recording was made with.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>

#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/vehicle_model.hpp"
#include "lcmloc/fit/innovation_fit.hpp"
#include "lcmloc/fit/noise_fit.hpp"

using namespace lcmloc;

namespace {

/// A robot driving a circle of radius 3 m at 0.3 m/s for 600 s: truth at 100 Hz, odometry at
/// 50 Hz with white speed and yaw-rate noise, range-bearing observations of 4 landmarks at 5 Hz
/// with the given noise (range bias range_bias), beacon ranges with a per-beacon bias.
fit::Recording circle(double range_std, double bearing_std, double range_bias, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  fit::Recording r;
  r.pw_distance = 1.0;
  r.map = {{1, 5.0, 0.0}, {2, 0.0, 5.0}, {3, -5.0, 0.0}, {4, 0.0, -5.0}};
  const double v = 0.3, w = v / 3.0;
  for (int64_t k = 0; k <= 60000; ++k) {
    const double t = k * 0.01, th = w * t;
    r.truth.push_back({1000000 + k * 10000, 3.0 * std::sin(th), 3.0 - 3.0 * std::cos(th), core::wrapAngle(th), true});
    if (k % 2 == 0 && k > 0) {
      core::OdometryInput o;
      o.utime = 1000000 + k * 10000;
      o.delta_s = (v + 0.02 * n(rng)) * 0.02;
      o.delta_theta = (w + 0.01 * n(rng)) * 0.02;
      r.odometry.push_back(o);
    }
    if (k % 20 == 0) {
      const auto& p = r.truth.back();
      for (const auto& m : r.map) {
        const double dx = m.x - p.x, dy = m.y - p.y;
        core::LandmarkObservation o;
        o.utime = p.utime;
        o.landmark_id = m.id;
        o.range = std::hypot(dx, dy) + range_bias + range_std * n(rng);
        o.bearing = core::wrapAngle(std::atan2(dy, dx) - p.heading + bearing_std * n(rng));
        r.landmarks.push_back(o);
        core::BeaconRange b;
        b.utime = p.utime;
        b.beacon_id = m.id;
        b.range = std::hypot(dx, dy) + 0.1 * m.id + range_std * n(rng);
        r.beacons.push_back(b);
      }
    }
  }
  return r;
}

}  // namespace

TEST(FitNoise, RecoversTheMeasurementNoiseAndTheBeaconBiases) {
  const auto r = circle(0.05, 0.02, 0.0, 7);
  const auto f = fit::fitAgainstTruth(r);
  ASSERT_TRUE(f.landmark_range && f.landmark_bearing && f.beacon_range);
  EXPECT_EQ(f.landmark_range->n, 12004);
  EXPECT_NEAR(f.landmark_range->sigma, 0.05, 0.003);
  EXPECT_NEAR(f.landmark_range->median, 0.0, 0.003);
  EXPECT_NEAR(f.landmark_bearing->sigma, 0.02, 0.0012);
  ASSERT_EQ(f.beacon_range_by_id.size(), 4u);
  for (const auto& [id, s] : f.beacon_range_by_id) {
    EXPECT_NEAR(s.median, 0.1 * id, 0.01) << id;  // each beacon's bias
    EXPECT_NEAR(s.sigma, 0.05, 0.005) << id;
  }
  EXPECT_FALSE(f.gps);  // no fix in the recording
}

// The circle's beacons read 0.1 m per id long (0.1 to 0.4 m): every one's bias is significant,
// and the prior for the filter's bias states covers them all. The same ranges with the bias
// taken out give none.
TEST(FitNoise, ASignificantBeaconRangeBiasGivesAPriorForTheBiasStates) {
  auto r = circle(0.05, 0.02, 0.0, 17);
  const auto f = fit::fitAgainstTruth(r);
  ASSERT_TRUE(f.beacon_bias);
  EXPECT_EQ(f.beacon_bias->beacons, 4);
  EXPECT_EQ(f.beacon_bias->of, 4);
  EXPECT_GT(f.beacon_bias->mean, 0.15);
  EXPECT_LT(f.beacon_bias->mean, 0.35);
  EXPECT_GE(f.beacon_bias->mean + f.beacon_bias->std, 0.39);  // the farthest beacon within one sigma
  EXPECT_LE(f.beacon_bias->mean - f.beacon_bias->std, 0.11);
  for (auto& b : r.beacons) b.range -= 0.1 * b.beacon_id;
  EXPECT_FALSE(fit::fitAgainstTruth(r).beacon_bias);
}

// Range errors that follow each landmark from one observation to the next (AR(1), rho 0.8 at the
// circle's 0.2 s per landmark) and white bearing errors: the correlation factor is
// (1 + 0.8) / (1 - 0.8) = 9. White errors in both give about 1.
TEST(FitNoise, TheCorrelationOfSuccessiveObservationsGivesTheCorrelationFactor) {
  const auto white = fit::fitAgainstTruth(circle(0.05, 0.02, 0.0, 21));
  ASSERT_TRUE(white.landmark_correlation);
  EXPECT_NEAR(white.landmark_correlation->range_rho, 0.0, 0.05);
  EXPECT_NEAR(white.landmark_correlation->bearing_rho, 0.0, 0.05);
  EXPECT_LT(white.landmark_correlation->factor, 1.15);
  auto r = circle(0.05, 0.02, 0.0, 22);
  std::mt19937_64 rng(23);
  std::normal_distribution<double> n(0.0, 1.0);
  const double rho = 0.8, sigma = 0.05;
  std::map<int, double> e;  // each landmark's current range error
  for (auto& o : r.landmarks) {
    const auto& p = r.truth[static_cast<std::size_t>((o.utime - 1000000) / 10000)];
    ASSERT_EQ(p.utime, o.utime);
    const auto& m = r.map[static_cast<std::size_t>(o.landmark_id - 1)];
    double& err = e[o.landmark_id];
    err = rho * err + std::sqrt(1.0 - rho * rho) * sigma * n(rng);
    o.range = std::hypot(m.x - p.x, m.y - p.y) + err;
  }
  const auto f = fit::fitAgainstTruth(r);
  ASSERT_TRUE(f.landmark_correlation);
  EXPECT_EQ(f.landmark_correlation->pairs, 12000);  // 3001 observations of each of 4, less the first
  EXPECT_NEAR(f.landmark_correlation->range_rho, rho, 0.03);
  EXPECT_NEAR(f.landmark_correlation->bearing_rho, 0.0, 0.05);
  EXPECT_NEAR(f.landmark_correlation->factor, 9.0, 1.5);
  EXPECT_NE(fit::configFragment(f, 1.0).find("correlation_factor: "), std::string::npos);
}

TEST(FitNoise, ARangeBiasIsTheMedianNotTheSpread) {
  const auto f = fit::fitAgainstTruth(circle(0.05, 0.02, 0.3, 8));
  ASSERT_TRUE(f.landmark_range);
  EXPECT_NEAR(f.landmark_range->median, 0.3, 0.005);
  EXPECT_NEAR(f.landmark_range->sigma, 0.05, 0.003);
}

TEST(FitNoise, OdometryProcessNoiseGrowsWithTheOdometryNoise) {
  const auto f = fit::fitAgainstTruth(circle(0.05, 0.02, 0.0, 9));
  ASSERT_TRUE(f.pw_diag && f.pw_turn);
  EXPECT_GT(f.odometry_windows, 100);
  // Heading: yaw-rate noise 0.01 rad/s white at 50 Hz: variance 0.01^2 * 0.02 per second, i.e.
  // 2e-6 rad^2 per second, 6.7e-6 per metre at 0.3 m/s; the fit splits it between distance and
  // turn (the circle turns at a constant rate per metre): their sum per metre is what counts.
  const double per_metre = (*f.pw_diag)[2] / 1.0 + *f.pw_turn * (0.1 / 0.3);
  EXPECT_GT(per_metre, 3e-6);
  EXPECT_LT(per_metre, 1.5e-5);
  // Position: speed noise 0.02 m/s at 50 Hz: 0.02^2 * 0.02 / 0.3 = 2.7e-5 m^2 per metre along
  // track, shared over two axes, plus the heading error's lever: of that order.
  EXPECT_GT((*f.pw_diag)[0], 5e-6);
  EXPECT_LT((*f.pw_diag)[0], 1e-4);
}

TEST(FitNoise, WithoutTruthOrHeadingItSaysWhatItCouldNotFit) {
  fit::Recording none;
  none.landmarks.push_back({});
  const auto f = fit::fitAgainstTruth(none);
  EXPECT_FALSE(f.landmark_range);
  ASSERT_FALSE(f.notes.empty());
  EXPECT_NE(f.notes[0].find("no ground truth"), std::string::npos);

  auto r = circle(0.05, 0.02, 0.0, 10);
  for (auto& t : r.truth) t.has_heading = false;  // position only
  const auto g = fit::fitAgainstTruth(r);
  EXPECT_TRUE(g.landmark_range);
  EXPECT_FALSE(g.landmark_bearing);
  bool said = false;
  for (const auto& n : g.notes) said |= n.find("bearing") != std::string::npos;
  EXPECT_TRUE(said);
  // The process noise is fitted all the same, the heading taken as the direction of travel:
  // the position's of the order OdometryProcessNoiseGrowsWithTheOdometryNoise finds with it.
  ASSERT_TRUE(g.pw_diag);
  EXPECT_GT((*g.pw_diag)[0], 5e-6);
  EXPECT_LT((*g.pw_diag)[0], 1e-4);
}

// A recording with a position-only truth and odometry whose turn is reversed and twice the
// truth's (as the UWB recording's columns give it): the turn scale is fitted, and the process
// noise is what is left after it (the filter's scale state starts there), not the metres of a
// dead reckoning that turns the wrong way.
TEST(FitNoise, ProcessNoiseAfterTheFittedScalesFromAPositionOnlyTruth) {
  auto r = circle(0.05, 0.02, 0.0, 16);
  for (auto& t : r.truth) t.has_heading = false;
  for (auto& o : r.odometry) o.delta_theta *= -2.0;
  const auto f = fit::fitAgainstTruth(r);
  ASSERT_TRUE(f.yaw_rate_scale);
  EXPECT_TRUE(f.yaw_rate_scale->significant());
  EXPECT_NEAR(f.yaw_rate_scale->ratio, -0.5, 0.03);
  ASSERT_TRUE(f.pw_diag) << (f.notes.empty() ? "" : f.notes.back());
  EXPECT_GT(f.odometry_windows, 1000);
  EXPECT_GT((*f.pw_diag)[0], 5e-6);
  EXPECT_LT((*f.pw_diag)[0], 1e-4);
}

TEST(FitNoise, TheFragmentNamesTheFittedKeysOnly) {
  const auto f = fit::fitAgainstTruth(circle(0.05, 0.02, 0.0, 11));
  const std::string y = fit::configFragment(f, 1.0);
  for (const char* k : {"pw_diag:", "pw_turn:", "range_std:", "bearing_std:", "beacon_std:"})
    EXPECT_NE(y.find(k), std::string::npos) << k << "\n" << y;
  EXPECT_EQ(y.find("gps_std"), std::string::npos) << y;
}

namespace {

/// ukf_landmarks started at the circle's first truth pose, with the process noise fitted
/// against the truth and the landmark and beacon sigmas given.
core::EngineConfig landmarkEngine(const fit::Recording& r, double range_std, double bearing_std, double beacon_std) {
  const auto truth_fit = fit::fitAgainstTruth(r);
  core::EngineConfig e;
  e.filter.type = "ukf_landmarks";
  e.filter.initial_pose = core::Vec3(r.truth.front().x, r.truth.front().y, r.truth.front().heading);
  e.filter.p0_diag = core::Vec3(1e-4, 1e-4, 1e-4);
  e.filter = fit::withFit(e.filter, truth_fit, r.pw_distance);
  e.filter.landmarks.range_std = range_std;
  e.filter.landmarks.bearing_std = bearing_std;
  e.filter.landmarks.beacon_std = beacon_std;
  return e;
}

}  // namespace

TEST(FitInnovations, SigmasFourTimesTooLargeOrTooSmallAreScaledToTheNoiseTheRecordingHas) {
  auto r = circle(0.05, 0.02, 0.0, 12);
  r.beacons.clear();  // (their per-beacon biases would add to the spread)
  for (const double wrong : {4.0, 0.25}) {
    const auto f = fit::fitByInnovations(r, landmarkEngine(r, 0.05 * wrong, 0.02 * wrong, 0.1));
    ASSERT_EQ(f.before.size(), 1u);
    EXPECT_EQ(f.before[0].sensor, "LANDMARKS");
    EXPECT_EQ(f.before[0].dof, 2);
    // Before: the median NIS off by about wrong^-2; after: near the chi-square median.
    if (wrong > 1) EXPECT_LT(f.before[0].median, 0.3 * f.before[0].expected_median) << wrong;
    else EXPECT_GT(f.before[0].median, 3.0 * f.before[0].expected_median) << wrong;
    ASSERT_EQ(f.after.size(), 1u);
    EXPECT_NEAR(f.after[0].median / f.after[0].expected_median, 1.0, 0.1) << wrong;
    EXPECT_NEAR(f.filter.landmarks.range_std, 0.05, 0.0125) << wrong;
    EXPECT_NEAR(f.filter.landmarks.bearing_std, 0.02, 0.005) << wrong;
    EXPECT_DOUBLE_EQ(f.filter.landmarks.beacon_std, 0.1);  // no beacon in the recording: kept
    ASSERT_EQ(f.fitted.size(), 1u);
    EXPECT_EQ(f.fitted[0], "landmarks.range_std, landmarks.bearing_std");
    const std::string y = fit::configFragment(f);
    EXPECT_NE(y.find("range_std:"), std::string::npos) << y;
    EXPECT_EQ(y.find("beacon_std"), std::string::npos) << y;
  }
}

TEST(FitInnovations, RightSigmasAreKeptAndTheTableSaysConsistent) {
  auto r = circle(0.05, 0.02, 0.0, 13);
  r.beacons.clear();
  const auto f = fit::fitByInnovations(r, landmarkEngine(r, 0.05, 0.02, 0.1));
  EXPECT_NEAR(f.filter.landmarks.range_std, 0.05, 0.005);
  ASSERT_EQ(f.after.size(), 1u);
  // The mean NIS of a right filter is within its band for thousands of decisions only
  // approximately (the UKF's S is approximate): within 15 % of the dof.
  EXPECT_NEAR(f.after[0].mean, 2.0, 0.3);
  EXPECT_LT(f.after[0].band_lo, 2.0);
  EXPECT_GT(f.after[0].band_hi, 2.0);
  const std::string t = fit::nisTable(f.after);
  EXPECT_NE(t.find("LANDMARKS"), std::string::npos) << t;
}

TEST(FitInnovations, RowsWithTheirOwnSigmaAndTooFewDecisionsAreNotFittedAndSaid) {
  auto r = circle(0.05, 0.02, 0.0, 14);
  for (auto& o : r.landmarks) o.range_std = 0.05;
  r.beacons.resize(8);  // two observations of each beacon: too few
  const auto f = fit::fitByInnovations(r, landmarkEngine(r, 0.2, 0.08, 0.1));
  EXPECT_TRUE(f.fitted.empty());
  EXPECT_DOUBLE_EQ(f.filter.landmarks.range_std, 0.2);
  EXPECT_DOUBLE_EQ(f.filter.landmarks.beacon_std, 0.1);
  std::string notes;
  for (const auto& n : f.notes) notes += n + "\n";
  EXPECT_NE(notes.find("carry their own sigma"), std::string::npos) << notes;
  EXPECT_NE(notes.find("fewer than 20"), std::string::npos) << notes;
}

// The odometry's distance and turn scales against the truth: an odometry whose turn is -2 times
// the truth's (a wheel distance wrong and the wheels swapped) and whose distance is 1.1 times
// it, against a truth of position only (its direction of travel gives the turn).
TEST(FitNoise, TheOdometrysScalesAreFittedAgainstAPositionOnlyTruth) {
  auto r = circle(0.05, 0.02, 0.0, 15);
  for (auto& o : r.odometry) {
    o.delta_theta *= -2.0;
    o.delta_s *= 1.1;
  }
  for (auto& t : r.truth) t.has_heading = false;
  const auto f = fit::fitAgainstTruth(r);
  ASSERT_TRUE(f.odometry_scale && f.yaw_rate_scale);
  EXPECT_NEAR(f.odometry_scale->ratio, 1.0 / 1.1, 0.01);
  EXPECT_NEAR(f.yaw_rate_scale->ratio, -0.5, 0.03);
  EXPECT_TRUE(f.odometry_scale->significant());
  EXPECT_TRUE(f.yaw_rate_scale->significant());
  // The same odometry unscaled: 1 within its uncertainty.
  const auto g = fit::fitAgainstTruth(circle(0.05, 0.02, 0.0, 16));
  ASSERT_TRUE(g.odometry_scale && g.yaw_rate_scale);
  EXPECT_FALSE(g.odometry_scale->significant()) << g.odometry_scale->ratio << " +- " << g.odometry_scale->se;
  EXPECT_FALSE(g.yaw_rate_scale->significant()) << g.yaw_rate_scale->ratio << " +- " << g.yaw_rate_scale->se;
}

namespace {

TEST(NoiseFit, TheHeadingsGrowthPerDistanceAndPerTurnIsFittedByMaximumLikelihood) {
  // Windows of very different size (log-uniform distance and turn, as a robot that mostly turns
  // on the spot and sometimes drives): the error of each is Gaussian with variance a s + b r.
  for (const unsigned seed : {1u, 2u, 3u}) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> n(0.0, 1.0);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double a = 0.003, b = 0.02;
    std::vector<double> e2, s, r;
    for (int i = 0; i < 3000; ++i) {
      s.push_back(std::pow(10.0, -2.0 + 2.5 * u(rng)));  // 0.01 .. 3 (per pw_distance)
      r.push_back(std::pow(10.0, -2.5 + 3.0 * u(rng)));  // 0.003 .. 3 rad
      e2.push_back(std::pow(std::sqrt(a * s.back() + b * r.back()) * n(rng), 2));
    }
    const auto [fa, fb] = fit::fitVarianceGrowth(e2, s, r);
    EXPECT_NEAR(fa, a, 0.15 * a) << seed;
    EXPECT_NEAR(fb, b, 0.15 * b) << seed;
  }
  // No growth at all, or growth with the turn only: no negative term, none made up.
  const std::vector<double> s{1, 2, 1, 3}, r{0.5, 0.1, 2, 1};
  EXPECT_EQ(fit::fitVarianceGrowth({0, 0, 0, 0}, s, r), std::make_pair(0.0, 0.0));
  const auto [fa, fb] = fit::fitVarianceGrowth({0.05, 0.01, 0.2, 0.1}, s, r);
  EXPECT_EQ(fa, 0.0);
  EXPECT_NEAR(fb, 0.1, 1e-9);
}

}  // namespace

namespace {

/// A robot weaving (turn rate 0.6 sin(2 pi t / 6) rad/s at 0.3 m/s) for 300 s, truth at 100 Hz;
/// its odometry at 50 Hz is stamped `lag` seconds before the motion it reports (a vehicle that
/// reports its commands), with a little white noise.
fit::Recording weave(double lag, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  const double kPi = 3.14159265358979323846, v = 0.3, a = 0.6, period = 6.0;
  auto heading = [&](double t) { return a * period / (2 * kPi) * (1 - std::cos(2 * kPi * t / period)); };
  fit::Recording r;
  r.pw_distance = 1.0;
  double x = 0, y = 0;
  for (int64_t k = 0; k <= 30000; ++k) {
    const double t = k * 0.01;
    if (k > 0) {
      x += v * 0.01 * std::cos(heading(t - 0.005));
      y += v * 0.01 * std::sin(heading(t - 0.005));
    }
    r.truth.push_back({1000000 + k * 10000, x, y, core::wrapAngle(heading(t)), true});
    if (k % 2 == 0 && k > 0) {
      core::OdometryInput o;
      o.utime = 1000000 + k * 10000;
      o.delta_s = (v + 0.01 * n(rng)) * 0.02;
      o.delta_theta = heading(t + lag) - heading(t + lag - 0.02) + 0.002 * n(rng);
      r.odometry.push_back(o);
    }
  }
  return r;
}

}  // namespace

TEST(FitNoise, TheLagOfTheTruthsMotionBehindTheOdometryIsFitted) {
  for (const double lag : {0.3, -0.15}) {
    const auto f = fit::fitAgainstTruth(weave(lag, 3));
    ASSERT_TRUE(f.odometry_lag) << lag;
    EXPECT_NEAR(f.odometry_lag->seconds, lag, 0.011) << lag;
    EXPECT_TRUE(f.odometry_lag->significant()) << lag;
    EXPECT_LT(f.odometry_lag->rms, 0.5 * f.odometry_lag->rms_at_zero) << lag;
    // The turn scale, fitted to the odometry moved by the lag, is the truth's 1.
    ASSERT_TRUE(f.yaw_rate_scale);
    EXPECT_NEAR(f.yaw_rate_scale->ratio, 1.0, 0.02) << lag;
  }
  const auto none = fit::fitAgainstTruth(weave(0.0, 4));
  ASSERT_TRUE(none.odometry_lag);
  EXPECT_FALSE(none.odometry_lag->significant()) << none.odometry_lag->seconds;
  EXPECT_LT(std::abs(none.odometry_lag->seconds), 0.011);
}

namespace {

/// A car driving a circle of radius 30 m at 5 m/s for 200 s: odometry at 50 Hz (distance and
/// heading increments), GPS at 5 Hz whose error is white (white_std per axis) plus a wander
/// (a random walk of wander_rw per axis per sqrt(s), kept within 3 m by a slow pull back).
fit::Recording gpsDrive(double white_std, double wander_rw, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  fit::Recording r;
  const double v = 5.0, w = v / 30.0, dt = 0.02;
  double wx = 0, wy = 0;
  for (int64_t k = 1; k <= 10000; ++k) {
    const double t = k * dt, th = w * t;
    const int64_t utime = 1000000 + k * 20000;
    core::OdometryInput o;
    o.utime = utime;
    o.has_steering = false;
    o.delta_s = v * dt;
    o.delta_theta = w * dt;
    r.odometry.push_back(o);
    wx += wander_rw * std::sqrt(dt) * n(rng) - 0.01 * dt * wx;
    wy += wander_rw * std::sqrt(dt) * n(rng) - 0.01 * dt * wy;
    if (k % 10 == 0) {
      core::GpsInput g;
      g.utime = utime;
      g.x = 30.0 * std::sin(th) + wx + white_std * n(rng);
      g.y = 30.0 - 30.0 * std::cos(th) + wy + white_std * n(rng);
      r.gps.push_back(g);
    }
  }
  return r;
}

core::EngineConfig gnssEngine(const std::string& type, double position_rw, double gps_std) {
  core::EngineConfig e;
  e.filter.type = type;
  e.filter.initial_pose = core::Vec3(0.0, 0.0, 0.0);
  e.filter.p0_diag = core::Vec3(1.0, 1.0, 0.01);
  e.filter.gnss.use_magnetometer = false;
  e.filter.gnss.position_rw = position_rw;
  e.filter.gnss.gps_std = gps_std;
  return e;
}

}  // namespace

// Fixes whose error wanders (0.5 m per sqrt(s)) beside a filter whose position process noise
// says the car follows its odometry to 0.05 m per sqrt(s): the filter lags the fixes, and the
// fit raises position_rw until it predicts them best. Fixes with a white error only keep the
// process noise low.
TEST(FitInnovations, ThePositionProcessNoiseOfAGnssFilterIsFittedToTheFixesPredictionError) {
  for (const std::string type : {"tvekf", "ukf_gps"}) {
    SCOPED_TRACE(type);
    const auto wander = gpsDrive(0.2, 0.5, 31);
    const auto f = fit::fitByInnovations(wander, gnssEngine(type, 0.05, 0.5));
    EXPECT_GE(f.filter.gnss.position_rw, 0.05 * 4.0);
    EXPECT_LT(f.rw_error.second, 0.8 * f.rw_error.first);
    EXPECT_NE(std::find(f.fitted.begin(), f.fitted.end(), "gnss.position_rw"), f.fitted.end());
    EXPECT_NE(fit::configFragment(f).find("position_rw: "), std::string::npos);
    const auto white = fit::fitByInnovations(gpsDrive(0.2, 0.0, 32), gnssEngine(type, 0.05, 0.5));
    EXPECT_LT(white.filter.gnss.position_rw, f.filter.gnss.position_rw / 2.0);
    fit::InnovationFitOptions off;
    off.position_rw = false;
    EXPECT_DOUBLE_EQ(fit::fitByInnovations(wander, gnssEngine(type, 0.05, 0.5), off).filter.gnss.position_rw, 0.05);
  }
}
