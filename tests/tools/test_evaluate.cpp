// lcmloc-evaluate on hand-made logs with known errors: constant offsets, heading offsets across
// +-pi, interpolation of 10 Hz truth at odd estimate times, NEES of errors drawn with a known
// covariance, gate statistics, TUM lines, and the bad-input errors of the command line.
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Cholesky>
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>

#include "lcmloc/eval/trajectory.hpp"
#include "lcmloc/eval/trajectory_report.hpp"
#include "lcmloc/gate_decision_t.hpp"
#include "lcmloc/gps_fix_t.hpp"
#include "lcmloc/ground_truth_t.hpp"
#include "lcmloc/landmark_obs_t.hpp"
#include "lcmloc/pose_t.hpp"
#include "test_log_writer.hpp"

namespace fs = std::filesystem;
using namespace lcmloc;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int64_t kT0 = 5000000;  // utime of the first truth sample [us]

using testlog::LogWriter;

ground_truth_t truthMsg(int64_t utime, double x, double y, double heading) {
  ground_truth_t m{};
  m.utime = utime;
  m.x = x;
  m.y = y;
  m.heading = heading;
  return m;
}

pose_t poseMsg(int64_t utime, double x, double y, double theta, const Eigen::Matrix3d& cov,
               const std::string& filter = "ukf_gated") {
  pose_t m{};
  m.utime = utime;
  m.filter = filter;
  m.dim = 3;
  m.state = {x, y, theta};
  m.state_names = {"x", "y", "theta"};
  m.covariance.assign(3, std::vector<double>(3, 0.0));
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m.covariance[static_cast<size_t>(r)][static_cast<size_t>(c)] = cov(r, c);
  return m;
}

gate_decision_t gateMsg(const std::string& filter, const std::string& sensor, int dim, double nis, bool accepted,
                        const std::string& reason) {
  gate_decision_t m{};
  m.filter = filter;
  m.sensor = sensor;
  m.dim = dim;
  m.innovation.assign(static_cast<size_t>(dim), 0.0);
  m.mahalanobis = nis;
  m.gate = 9.21;
  m.accepted = accepted;
  m.marker_id = -1;
  m.reason = reason;
  return m;
}

/// Straight drive along x at 1 m/s for 20 s, truth at 100 Hz; estimates at the same times with
/// a constant error (dx, dy, dtheta); the true heading is near +pi so that the heading error
/// wraps (the estimate's theta is wrapped to (-pi, pi]).
void writeOffsetRun(const std::string& path, double dx, double dy, double dtheta) {
  LogWriter w(path);
  const double heading = kPi - 0.02;
  const Eigen::Matrix3d cov = Eigen::Vector3d(0.01, 0.01, 0.001).asDiagonal();
  for (int i = 0; i <= 2000; ++i) {
    const int64_t t = kT0 + i * 10000;
    const double x = 0.01 * i;
    w.add("GROUND_TRUTH", truthMsg(t, x, 0.0, heading), t);
    double th = std::remainder(heading + dtheta, 2 * kPi);
    if (th <= -kPi) th += 2 * kPi;
    w.add("POSE", poseMsg(t, x + dx, dy, th, cov), t);
  }
}

class EvaluateTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("lcmloc_test_evaluate_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }

  /// Runs lcmloc-evaluate with args; stdout+stderr to output_; returns its exit status.
  int evaluate(const std::string& args) {
    const std::string cmd = std::string(LCMLOC_EVALUATE_BIN) + " " + args + " > " + file("out.txt") + " 2>&1";
    const int rc = std::system(cmd.c_str());
    std::ifstream f(file("out.txt"));
    std::stringstream s;
    s << f.rdbuf();
    output_ = s.str();
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
  }
  nlohmann::json report(const std::string& dir) {
    std::ifstream f(dir + "/report.json");
    return nlohmann::json::parse(f);
  }

  fs::path dir_;
  std::string output_;
};

TEST_F(EvaluateTest, ConstantOffsetGivesExactErrors) {
  writeOffsetRun(file("run.lcmlog"), 0.3, -0.4, 0.05);
  const auto log = eval::readTrajectoryLog(file("run.lcmlog"), {});
  ASSERT_EQ(log.tracks.size(), 1u);
  ASSERT_EQ(log.tracks[0].poses.size(), 2001u);
  EXPECT_EQ(log.truth.size(), 2001u);
  EXPECT_EQ(log.truth_type, "ground_truth_t");
  const auto s = eval::scoreTrack(log.tracks[0], log.truth, {});
  EXPECT_EQ(s.scored, 2001);
  EXPECT_NEAR(s.position.rmse, 0.5, 1e-9);
  EXPECT_NEAR(s.position.median, 0.5, 1e-9);
  EXPECT_NEAR(s.position.p95, 0.5, 1e-9);
  EXPECT_NEAR(s.position.max, 0.5, 1e-9);
  EXPECT_NEAR(s.final_error_m, 0.5, 1e-9);
  ASSERT_TRUE(s.has_heading);
  EXPECT_NEAR(s.heading.rmse, 0.05, 1e-9);  // across +-pi: wrapped, not 2 pi - 0.05
  EXPECT_NEAR(s.heading.max, 0.05, 1e-9);
  EXPECT_NEAR(s.path_length_m, 20.0, 1e-9);
  EXPECT_NEAR(s.final_error_pct, 100.0 * 0.5 / 20.0, 1e-9);
  ASSERT_EQ(s.drift.size(), 3u);  // 10, 50, 100 m
  EXPECT_GT(s.drift[0].segments, 900);
  EXPECT_NEAR(s.drift[0].max_pct, 0.0, 1e-9);   // a constant offset does not drift
  EXPECT_EQ(s.drift[1].segments, 0);           // the run is 20 m long
}

TEST_F(EvaluateTest, ALogOfTwoRunsSaysSoAsAWholeLogIssue) {
  // A restarted simulator: the same run twice in one log, truth utimes repeated.
  {
    LogWriter w(file("twice.lcmlog"));
    for (int run = 0; run < 2; ++run)
      for (int i = 0; i < 100; ++i) w.add("GROUND_TRUTH", truthMsg(kT0 + i * 10000, 0.01 * i, 0.0, 0.0), kT0 + i * 10000);
  }
  const auto log = eval::readTrajectoryLog(file("twice.lcmlog"), {});
  ASSERT_EQ(log.issues.size(), 1u);
  const std::string d = log.issues[0].describe();
  EXPECT_EQ(d.rfind("whole log: truth channel GROUND_TRUTH: 100 samples with a duplicate utime", 0), 0u) << d;
  EXPECT_NE(d.find("lcmloc-log cut"), std::string::npos) << d;
  EXPECT_EQ((logio::LogIssue{7, 1234, "x"}.describe()), "event 7 at byte 1234: x");
  std::ostringstream os;
  std::vector<logio::LogIssue> many(12, logio::LogIssue{1, 2, "bad"});
  logio::printIssues(os, many);
  EXPECT_EQ(os.str().find("  event 1 at byte 2: bad\n"), 0u) << os.str();
  EXPECT_NE(os.str().find("  ... and 2 more (see report.json)\n"), std::string::npos) << os.str();
}

TEST_F(EvaluateTest, ErrorStatisticsOfKnownSamples) {
  const auto s = eval::errorStats({1, 2, 3, 4, -5, 6, 7, 8, 9, 10});
  EXPECT_EQ(s.n, 10);
  EXPECT_NEAR(s.rmse, std::sqrt(385.0 / 10.0), 1e-12);
  EXPECT_NEAR(s.mean, 5.5, 1e-12);
  EXPECT_NEAR(s.median, 5.5, 1e-12);
  EXPECT_NEAR(s.p95, 9.55, 1e-12);  // linear between order statistics
  EXPECT_NEAR(s.max, 10.0, 1e-12);
}

TEST_F(EvaluateTest, DriftOfALinearlyGrowingError) {
  // The x error grows 1 cm per metre: 1 % drift on every segment; the final error is 1 % too.
  {
    LogWriter w(file("run.lcmlog"));
    for (int i = 0; i <= 300; ++i) {
      const int64_t t = kT0 + i * 100000;
      const double x = 0.1 * i;
      w.add("GROUND_TRUTH", truthMsg(t, x, 0.0, 0.0), t);
      w.add("POSE", poseMsg(t, x * 1.01, 0.0, 0.0, Eigen::Matrix3d::Identity()), t);
    }
  }
  const auto log = eval::readTrajectoryLog(file("run.lcmlog"), {});
  eval::EvaluateOptions opt;
  opt.segment_lengths = {5.0, 10.0};
  const auto s = eval::scoreTrack(log.tracks[0], log.truth, opt);
  for (const auto& d : s.drift) {
    EXPECT_GT(d.segments, 200);
    EXPECT_NEAR(d.mean_pct, 1.0, 1e-9);
    EXPECT_NEAR(d.max_pct, 1.0, 1e-9);
  }
  EXPECT_NEAR(s.final_error_pct, 1.0, 1e-9);
}

TEST_F(EvaluateTest, TruthAt10HzIsInterpolatedAtOddEstimateTimes) {
  // Truth at 10 Hz on x = 2 t, y = -t + 3; heading turns at 1 rad/s from 2.9 rad through +-pi.
  auto heading = [](double t) { return std::remainder(2.9 + t, 2 * kPi); };
  int n = 0, before = 0, after = 0;
  {
    LogWriter w(file("run.lcmlog"));
    for (int i = 0; i <= 50; ++i) {
      const double t = 0.1 * i;
      w.add("GROUND_TRUTH", truthMsg(kT0 + i * 100000, 2 * t, -t + 3, heading(t)), kT0 + i * 100000);
    }
    // Estimates every 37 ms from 0.2 s before the truth to 0.3 s after it, exactly on the truth.
    for (int64_t u = kT0 - 200000; u <= kT0 + 5300000; u += 37000, ++n) {
      const double t = static_cast<double>(u - kT0) * 1e-6;
      w.add("POSE", poseMsg(u, 2 * t, -t + 3, heading(t), Eigen::Matrix3d::Identity() * 0.01), u);
      before += u < kT0;
      after += u > kT0 + 5000000;
    }
  }  // the log is closed
  const auto log = eval::readTrajectoryLog(file("run.lcmlog"), {});
  const auto s = eval::scoreTrack(log.tracks[0], log.truth, {});
  EXPECT_EQ(s.estimates, n);
  EXPECT_EQ(s.before_truth, before);
  EXPECT_EQ(s.after_truth, after);
  EXPECT_EQ(s.scored, n - before - after);
  EXPECT_LT(s.position.max, 1e-9);          // linear truth: interpolation is exact
  // Heading changes linearly too; the shortest-angle interpolation is exact across +-pi
  // (interpolating the raw numbers would give errors of several radians there).
  EXPECT_LT(s.heading.max, 1e-9);
  EXPECT_NEAR(s.path_length_m, std::sqrt(5.0) * (s.points.back().utime - s.points.front().utime) * 1e-6, 1e-6);

  // A gap in the truth longer than max_truth_gap: the estimates inside it are skipped.
  std::vector<eval::TruthPose> gappy{{0, 0, 0, 0, true}, {100000, 0.1, 0, 0, true}, {2100000, 2.1, 0, 0, true}};
  eval::TruthMiss why{};
  EXPECT_TRUE(eval::interpolateTruth(gappy, 50000, 1000000, &why).has_value());
  EXPECT_FALSE(eval::interpolateTruth(gappy, 1000000, 1000000, &why).has_value());
  EXPECT_EQ(why, eval::TruthMiss::kGap);
  const auto mid = eval::interpolateTruth(gappy, 1000000, 0, &why);  // no limit
  ASSERT_TRUE(mid.has_value());
  EXPECT_NEAR(mid->x, 1.0, 1e-12);
  EXPECT_FALSE(eval::interpolateTruth(gappy, 2100001, 0, &why).has_value());
  eval::EstimateTrack across{"POSE", {}, {}, {}};
  for (int64_t u : {50000, 1000000, 2100000}) across.poses.push_back({u, 0, 0, 0, Eigen::Matrix3d::Identity(), true, 0});
  eval::EvaluateOptions opt;
  const auto g = eval::scoreTrack(across, gappy, opt);
  EXPECT_EQ(g.in_truth_gap, 1);
  ASSERT_EQ(g.points.size(), 2u);
  EXPECT_FALSE(g.points[0].after_skip);
  EXPECT_TRUE(g.points[1].after_skip);  // figures break the line there
  EXPECT_EQ(why, eval::TruthMiss::kAfter);
}

/// Truth on a circle; each estimate = truth + error drawn from N(0, P) (seeded); recorded
/// covariance = scale * P.
eval::TrackScore neesRun(const std::string& path, double scale, uint32_t seed) {
  Eigen::Matrix3d p;
  p << 0.04, 0.01, 0.002, 0.01, 0.09, -0.003, 0.002, -0.003, 0.0025;
  const Eigen::Matrix3d l = p.llt().matrixL();
  std::mt19937 rng(seed);
  std::normal_distribution<double> n01;
  {
    LogWriter w(path);
    for (int i = 0; i < 2000; ++i) {
      const int64_t t = kT0 + i * 100000;
      const double a = 0.01 * i, x = 20 * std::cos(a), y = 20 * std::sin(a);
      const double heading = std::remainder(a + kPi / 2, 2 * kPi);
      w.add("GROUND_TRUTH", truthMsg(t, x, y, heading), t);
      const Eigen::Vector3d e = l * Eigen::Vector3d(n01(rng), n01(rng), n01(rng));
      w.add("POSE", poseMsg(t, x + e[0], y + e[1], std::remainder(heading + e[2], 2 * kPi), scale * p), t);
    }
  }
  const auto log = eval::readTrajectoryLog(path, {});
  return eval::scoreTrack(log.tracks[0], log.truth, {});
}

TEST_F(EvaluateTest, NeesOfHonestCovarianceIsNearItsDof) {
  const auto s = neesRun(file("run.lcmlog"), 1.0, 42);
  ASSERT_EQ(s.nees3.samples, 2000);
  ASSERT_EQ(s.nees2.samples, 2000);
  EXPECT_EQ(s.nees3.dof, 3);
  EXPECT_EQ(s.nees2.dof, 2);
  // Bounds of the mean over 2000 samples: chi2(6000) / 2000 at 2.5 % and 97.5 %.
  EXPECT_NEAR(s.nees3.mean_lo, 2.893, 0.01);
  EXPECT_NEAR(s.nees3.mean_hi, 3.109, 0.01);
  EXPECT_NEAR(s.nees3.sample_lo, 0.2158, 1e-3);
  EXPECT_NEAR(s.nees3.sample_hi, 9.3484, 1e-3);
  EXPECT_GT(s.nees3.mean, s.nees3.mean_lo);
  EXPECT_LT(s.nees3.mean, s.nees3.mean_hi);
  EXPECT_EQ(s.nees3.verdict, "honest");
  EXPECT_EQ(s.nees2.verdict, "honest");
  EXPECT_GT(s.nees3.effective_samples, 1500.0);  // independent draws: about 2000
  EXPECT_EQ(s.nees3.verdict_effective, "honest");
  EXPECT_NEAR(s.nees3.fraction_inside, 0.95, 0.015);
  EXPECT_NEAR(s.nees2.fraction_inside, 0.95, 0.015);
}

TEST_F(EvaluateTest, EffectiveSampleSizeOfCorrelatedSeries) {
  std::mt19937 rng(7);
  std::normal_distribution<double> n01;
  std::vector<double> iid(20000), ar(20000);
  double a = 0;
  for (std::size_t i = 0; i < iid.size(); ++i) {
    iid[i] = n01(rng);
    a = 0.9 * a + n01(rng);  // AR(1), phi 0.9: integrated autocorrelation time (1 + phi) / (1 - phi) = 19
    ar[i] = a;
  }
  EXPECT_NEAR(eval::effectiveSampleSize(iid), 20000.0, 2000.0);
  EXPECT_NEAR(eval::effectiveSampleSize(ar), 20000.0 / 19.0, 200.0);
  // The bounds of the mean widen with the effective sample size.
  std::vector<double> nees(ar.size());
  for (std::size_t i = 0; i < ar.size(); ++i) nees[i] = 2.0 + 0.1 * ar[i];
  const auto c = eval::consistency(nees, std::vector<int>(nees.size(), 2), 0.95);
  EXPECT_LT(c.effective_samples, 1300.0);
  EXPECT_LT(c.mean_lo_effective, c.mean_lo);
  EXPECT_GT(c.mean_hi_effective, c.mean_hi);
}

TEST_F(EvaluateTest, NeesFlagsConservativeAndOptimisticCovariance) {
  const auto big = neesRun(file("big.lcmlog"), 4.0, 42);   // covariance 4x too large
  EXPECT_NEAR(big.nees3.mean, 0.75, 0.08);
  EXPECT_EQ(big.nees3.verdict, "conservative");
  EXPECT_EQ(big.nees2.verdict, "conservative");
  EXPECT_EQ(big.nees3.verdict_effective, "conservative");
  const auto small = neesRun(file("small.lcmlog"), 0.25, 42);  // 4x too small
  EXPECT_NEAR(small.nees3.mean, 12.0, 1.2);
  EXPECT_EQ(small.nees3.verdict, "optimistic");
  EXPECT_EQ(small.nees3.verdict_effective, "optimistic");
  EXPECT_LT(small.nees3.fraction_inside, 0.7);
}

TEST_F(EvaluateTest, GateStatisticsPerFilterAndSensor) {
  std::vector<eval::GateRecord> g;
  for (double nis : {1.0, 2.0, 3.0}) g.push_back({0, "ukf_gated", "MAGRULER", "accepted", 2, nis, true});
  g.push_back({0, "ukf_gated", "MAGRULER", "gate", 2, 50.0, false});
  g.push_back({0, "ukf_gated", "MAGRULER_FAULT", "gate", 2, 40.0, false});
  g.push_back({0, "ukf_gated", "GPS", "no_candidate", 0, std::nan(""), false});
  g.push_back({0, "tvekf", "GPS", "accepted", 2, 4.0, true});
  g.push_back({0, "dead_reckoning", "GPS", "dead_reckoning", 0, 0.0, false});
  const auto st = eval::gateStatistics(g, 0.95);
  ASSERT_EQ(st.by_filter_sensor.size(), 5u);
  const auto& m = st.by_filter_sensor[3];  // sorted: dead_reckoning, tvekf, then ukf_gated GPS, MAGRULER, ...
  EXPECT_EQ(m.filter, "ukf_gated");
  EXPECT_EQ(m.sensor, "MAGRULER");
  EXPECT_EQ(m.decisions, 4);
  EXPECT_EQ(m.accepted, 3);
  EXPECT_EQ(m.rejected, 1);
  EXPECT_EQ(m.reasons.at("gate"), 1);
  EXPECT_EQ(m.reasons.at("accepted"), 3);
  EXPECT_EQ(m.nis.samples, 3);
  EXPECT_NEAR(m.nis.mean, 2.0, 1e-12);
  EXPECT_NEAR(m.nis_mean_all, 14.0, 1e-12);
  EXPECT_NEAR(m.mean_dof, 2.0, 1e-12);
  EXPECT_EQ(m.nis.verdict, "honest");
  EXPECT_EQ(st.by_filter_sensor[0].ignored, 1);
  EXPECT_EQ(st.by_filter_sensor[0].rejected, 0);
  ASSERT_EQ(st.by_filter.size(), 3u);
  EXPECT_EQ(st.by_filter[2].filter, "ukf_gated");
  EXPECT_EQ(st.by_filter[2].sensor, "*");
  EXPECT_EQ(st.by_filter[2].decisions, 6);
  EXPECT_EQ(st.by_filter[2].rejected, 3);
  EXPECT_EQ(st.by_filter[2].reasons.at("no_candidate"), 1);
  ASSERT_EQ(st.by_sensor.size(), 3u);
  EXPECT_EQ(st.by_sensor[0].sensor, "GPS");
  EXPECT_EQ(st.by_sensor[0].decisions, 3);
  EXPECT_EQ(st.by_sensor[0].accepted, 1);
  EXPECT_NEAR(st.by_sensor[0].nis.mean, 4.0, 1e-12);
}

TEST_F(EvaluateTest, TumLinesAndFiles) {
  EXPECT_EQ(eval::tumLine(1234567890123456, 1.5, -2.25, kPi / 2),
            "1234567890.123456 1.500000 -2.250000 0 0 0 0.707106781 0.707106781");
  EXPECT_EQ(eval::tumLine(5000001, 0, 0, 0), "5.000001 0.000000 0.000000 0 0 0 0.000000000 1.000000000");
  EXPECT_EQ(eval::tumLine(7, 0, 0, kPi), "0.000007 0.000000 0.000000 0 0 0 1.000000000 0.000000000");
  const double yaw = -2.0;  // negative yaw: qz < 0, qw > 0
  std::istringstream line(eval::tumLine(kT0, 3, 4, yaw));
  double ts, tx, ty, tz, qx, qy, qz, qw;
  line >> ts >> tx >> ty >> tz >> qx >> qy >> qz >> qw;
  EXPECT_DOUBLE_EQ(ts, 5.0);
  EXPECT_NEAR(qz, std::sin(-1.0), 1e-9);
  EXPECT_NEAR(qw, std::cos(-1.0), 1e-9);
  EXPECT_NEAR(2 * std::atan2(qz, qw), yaw, 1e-8);

  writeOffsetRun(file("run.lcmlog"), 0.3, -0.4, 0.05);
  ASSERT_EQ(evaluate(file("run.lcmlog") + " --no-plots -o " + file("out") + " --tum-dir " + file("tum")), 0) << output_;
  for (const char* name : {"estimate.tum", "truth.tum"}) {
    std::ifstream f(file("tum/") + name);
    std::string header, first;
    std::getline(f, header);
    std::getline(f, first);
    EXPECT_EQ(header, "# timestamp tx ty tz qx qy qz qw") << name;
    std::istringstream fl(first);
    std::vector<double> v;
    for (double d; fl >> d;) v.push_back(d);
    ASSERT_EQ(v.size(), 8u) << name;
    EXPECT_DOUBLE_EQ(v[0], 5.0);
    EXPECT_NEAR(v[1], name[0] == 'e' ? 0.3 : 0.0, 1e-9);
    EXPECT_NEAR(v[4] * v[4] + v[5] * v[5] + v[6] * v[6] + v[7] * v[7], 1.0, 1e-8);
    int lines = 1;
    for (std::string l; std::getline(f, l);) ++lines;
    EXPECT_EQ(lines, 2001) << name;
  }
}

TEST_F(EvaluateTest, TumExportKeepsOneLinePerTimestampAndSkipsBadPoses) {
  {
    LogWriter w(file("run.lcmlog"));
    for (int i = 0; i < 5; ++i) {
      w.add("POSE", poseMsg(kT0 + i * 1000, i, 0, 0, Eigen::Matrix3d::Identity()), kT0);
      w.add("POSE", poseMsg(kT0 + i * 1000, i + 0.5, 0, 0, Eigen::Matrix3d::Identity()), kT0);  // same utime
    }
    pose_t two = poseMsg(kT0 + 9000, 9, 9, 0, Eigen::Matrix3d::Identity());
    two.dim = 2;
    two.state.resize(2);
    two.state_names.resize(2);
    two.covariance = {{1, 0}, {0, 1}};
    w.add("POSE", two, kT0);
  }
  ASSERT_EQ(evaluate(file("run.lcmlog") + " --export-only --tum-dir " + file("tum")), 0) << output_;
  EXPECT_NE(output_.find("fewer than 3 states"), std::string::npos) << output_;
  std::ifstream f(file("tum/estimate.tum"));
  std::vector<std::string> lines;
  for (std::string l; std::getline(f, l);) lines.push_back(l);
  ASSERT_EQ(lines.size(), 6u);  // header + 5 unique stamps
  EXPECT_EQ(lines[1], eval::tumLine(kT0, 0.5, 0, 0));  // the last of the two at kT0
}

TEST_F(EvaluateTest, CommandLineReportsEverything) {
  {
    // A straight run with a constant offset, a shadow channel and gate decisions.
    LogWriter w(file("run.lcmlog"));
    for (int i = 0; i <= 2000; ++i) {
      const int64_t t = kT0 + i * 10000;
      w.add("GROUND_TRUTH", truthMsg(t, 0.01 * i, 0.0, 0.0), t);
      w.add("POSE", poseMsg(t, 0.01 * i + 0.3, -0.4, 0.0, Eigen::Matrix3d::Identity() * 0.01), t);
      w.add("POSE_DEAD_RECKONING", poseMsg(t, 0.01 * i, 1.0, 0.0, Eigen::Matrix3d::Identity(), "dead_reckoning"), t);
      if (i % 100 == 0) w.add("GATE", gateMsg("ukf_gated", "MAGRULER", 2, 2.5, true, "accepted"), t);
    }
    w.add("GATE", gateMsg("ukf_gated", "MAGRULER_FAULT", 2, 80.0, false, "gate"), kT0);
  }
  ASSERT_EQ(evaluate(file("run.lcmlog") + " --all-poses -o " + file("out")), 0) << output_;
  const auto j = report(file("out"));
  ASSERT_EQ(j.at("tracks").size(), 2u);
  const auto& t = j["tracks"][0];
  EXPECT_EQ(t["channel"], "POSE");
  EXPECT_EQ(t["filters"][0], "ukf_gated");
  EXPECT_EQ(t["scored"], 2001);
  EXPECT_NEAR(t["position_error_m"]["rmse"].get<double>(), 0.5, 1e-9);
  EXPECT_NEAR(t["heading_error_rad"]["max_abs"].get<double>(), 0.0, 1e-12);
  EXPECT_NEAR(t["relative"]["path_length_m"].get<double>(), 20.0, 1e-9);
  EXPECT_NEAR(t["nees_xy"]["mean"].get<double>(), 25.0, 1e-9);  // 0.25 / 0.01
  EXPECT_EQ(t["nees_xy"]["verdict"], "optimistic");
  EXPECT_EQ(t["nees_xytheta"]["dof"], 3);
  EXPECT_EQ(j["tracks"][1]["channel"], "POSE_DEAD_RECKONING");
  EXPECT_NEAR(j["tracks"][1]["position_error_m"]["max"].get<double>(), 1.0, 1e-9);
  EXPECT_NEAR(j["tracks"][1]["nees_xy"]["mean"].get<double>(), 1.0, 1e-9);
  EXPECT_EQ(j["truth"]["type"], "ground_truth_t");
  EXPECT_EQ(j["gate"]["decisions"], 22);
  ASSERT_EQ(j["gate"]["by_filter_sensor"].size(), 2u);
  EXPECT_EQ(j["gate"]["by_filter_sensor"][0]["accepted"], 21);
  EXPECT_EQ(j["gate"]["by_filter_sensor"][1]["reasons"]["gate"], 1);
  EXPECT_EQ(j["gate"]["by_sensor"].size(), 2u);
  EXPECT_FALSE(j["log"]["damaged"].get<bool>());
  if (std::system("command -v gnuplot > /dev/null") == 0) {
    for (const char* png : {"trajectory_POSE.png", "errors_POSE.png", "nees_POSE.png", "nees_POSE_DEAD_RECKONING.png"})
      EXPECT_GT(fs::file_size(file("out/") + png), 1000u) << png;
  }

  // Another pose channel chosen by name, without the shadows.
  ASSERT_EQ(evaluate(file("run.lcmlog") + " --pose-channel POSE_DEAD_RECKONING --no-plots -o " + file("out2")), 0);
  EXPECT_EQ(report(file("out2"))["tracks"].size(), 1u);
  EXPECT_NEAR(report(file("out2"))["tracks"][0]["position_error_m"]["rmse"].get<double>(), 1.0, 1e-9);
}

// Observations without identity (landmark_id -1: other robots in a recording) are counted apart
// from known ones: which of them each filter accepted.
TEST_F(EvaluateTest, AcceptedObservationsWithoutIdentityAreCountedApart) {
  {
    LogWriter w(file("run.lcmlog"));
    for (int i = 0; i <= 200; ++i) {
      const int64_t t = kT0 + i * 10000;
      w.add("GROUND_TRUTH", truthMsg(t, 0.01 * i, 0.0, 0.0), t);
      w.add("POSE", poseMsg(t, 0.01 * i, 0.0, 0.0, Eigen::Matrix3d::Identity() * 0.01, "ukf_landmarks"), t);
      if (i % 10 != 0) continue;
      const int seq = i / 10;  // 21 observations, every third (seq 0, 3, ..., 18) without identity
      landmark_obs_t o{};
      o.utime = t;
      o.seq = seq;
      o.landmark_id = seq % 3 == 0 ? -1 : 5;
      o.range = 2.0;
      w.add("LANDMARKS", o, t);
      // The filter accepts every known one but seq 1, and the unknown ones with seq 0 and 9.
      const bool accepted = o.landmark_id >= 0 ? seq != 1 : (seq == 0 || seq == 9);
      gate_decision_t d = gateMsg("ukf_landmarks", "LANDMARKS", 2, 1.0, accepted, accepted ? "accepted" : "gate");
      d.measurement_seq = seq;
      w.add("GATE", d, t);
      gate_decision_t other = gateMsg("ukf_landmarks", "BEACONS", 1, 1.0, true, "accepted");
      other.measurement_seq = seq;  // another sensor's seq: not a landmark observation
      w.add("GATE", other, t);
    }
  }
  ASSERT_EQ(evaluate(file("run.lcmlog") + " --no-plots -o " + file("out")), 0) << output_;
  const auto u = report(file("out")).at("unknown_identity");
  EXPECT_EQ(u.at("landmark_observations"), 21);
  EXPECT_EQ(u.at("without_identity"), 7);
  ASSERT_EQ(u.at("by_filter").size(), 1u);
  const auto& f = u["by_filter"][0];
  EXPECT_EQ(f.at("filter"), "ukf_landmarks");
  EXPECT_EQ(f.at("known_decided"), 14);
  EXPECT_EQ(f.at("known_accepted"), 13);
  EXPECT_EQ(f.at("unknown_decided"), 7);
  EXPECT_EQ(f.at("unknown_accepted"), 2);
  EXPECT_NE(output_.find("7 of 21 landmark observation(s) without identity"), std::string::npos) << output_;
  EXPECT_NE(output_.find("2 of 7"), std::string::npos) << output_;
}

TEST_F(EvaluateTest, GpsFixTruthNeedsADatum) {
  {
    LogWriter w(file("run.lcmlog"));
    // Fixes at the datum and 0.001 deg east; poses on the line between them.
    bus::Datum datum;
    datum.latitude = -33.883;
    datum.longitude = 151.195;
    const bus::LocalFrame frame(datum);
    double east = 0, north = 0, up = 0;
    frame.toLocal(-33.883, 151.196, 0.0, east, north, up);
    ASSERT_NEAR(east, 92.5, 0.5);
    for (int i = 0; i < 2; ++i) {
      gps_fix_t f{};
      f.utime = kT0 + i * 1000000;
      f.latitude = -33.883;
      f.longitude = 151.195 + 0.001 * i;
      f.fix_type = 3;
      w.add("GPS_HELDOUT", f, f.utime);
    }
    for (int i = 0; i <= 10; ++i)
      w.add("POSE", poseMsg(kT0 + i * 100000, 0.1 * east * i, 0.1 * north * i, 0.0, Eigen::Matrix3d::Identity()), kT0 + i * 100000);
  }
  EXPECT_EQ(evaluate(file("run.lcmlog") + " --truth-channel GPS_HELDOUT --no-plots -o " + file("out")), 1);
  EXPECT_NE(output_.find("datum"), std::string::npos) << output_;
  ASSERT_EQ(evaluate(file("run.lcmlog") + " --truth-channel GPS_HELDOUT --datum -33.883,151.195 --no-plots -o " +
                     file("out")), 0) << output_;
  const auto j = report(file("out"));
  EXPECT_EQ(j["truth"]["type"], "gps_fix_t");
  EXPECT_FALSE(j["truth"]["has_heading"].get<bool>());
  EXPECT_TRUE(j["tracks"][0]["heading_error_rad"].is_null());
  EXPECT_EQ(j["tracks"][0]["nees_xytheta"]["samples"], 0);
  EXPECT_EQ(j["tracks"][0]["nees_xy"]["samples"], 11);
  EXPECT_LT(j["tracks"][0]["position_error_m"]["max"].get<double>(), 1e-6);
}

TEST_F(EvaluateTest, BadInputsGiveClearErrors) {
  const std::string out = " --no-plots -o " + file("out");
  // Missing file: a usage error.
  EXPECT_EQ(evaluate(file("missing.lcmlog") + out), 2);
  EXPECT_NE(output_.find("no such file"), std::string::npos) << output_;
  // A directory: not read as a damaged log (a usage error too).
  fs::create_directories(file("adir"));
  EXPECT_EQ(evaluate(file("adir") + out), 2);
  EXPECT_NE(output_.find("is a directory"), std::string::npos) << output_;
  EXPECT_EQ(output_.find("DAMAGE"), std::string::npos) << output_;
  // Estimates but no truth: an error naming the channels; --export-only exports anyway.
  {
    LogWriter w(file("notruth.lcmlog"));
    for (int i = 0; i < 10; ++i) w.add("POSE", poseMsg(kT0 + i * 1000, i, 0, 0, Eigen::Matrix3d::Identity()), kT0);
  }
  EXPECT_EQ(evaluate(file("notruth.lcmlog") + out), 1);
  EXPECT_NE(output_.find("no ground truth on channel GROUND_TRUTH"), std::string::npos) << output_;
  EXPECT_NE(output_.find("POSE (10)"), std::string::npos) << output_;
  EXPECT_EQ(evaluate(file("notruth.lcmlog") + out + " --export-only"), 2);  // needs --tum-dir
  ASSERT_EQ(evaluate(file("notruth.lcmlog") + out + " --export-only --tum-dir " + file("tum")), 0) << output_;
  EXPECT_TRUE(fs::exists(file("tum/estimate.tum")));
  EXPECT_FALSE(fs::exists(file("tum/truth.tum")));
  // Truth but no estimates.
  {
    LogWriter w(file("noest.lcmlog"));
    for (int i = 0; i < 10; ++i) w.add("GROUND_TRUTH", truthMsg(kT0 + i * 1000, i, 0, 0), kT0);
  }
  EXPECT_EQ(evaluate(file("noest.lcmlog") + out), 1);
  EXPECT_NE(output_.find("no estimates (pose_t) on channel POSE"), std::string::npos) << output_;
  // No overlap: estimates after the truth ends.
  {
    LogWriter w(file("apart.lcmlog"));
    for (int i = 0; i < 10; ++i) w.add("GROUND_TRUTH", truthMsg(kT0 + i * 1000, i, 0, 0), kT0);
    for (int i = 0; i < 10; ++i)
      w.add("POSE", poseMsg(kT0 + 1000000 + i * 1000, i, 0, 0, Eigen::Matrix3d::Identity()), kT0);
  }
  EXPECT_EQ(evaluate(file("apart.lcmlog") + out), 1);
  EXPECT_NE(output_.find("no estimate lies inside the ground truth"), std::string::npos) << output_;
  // Bad options.
  EXPECT_EQ(evaluate(file("apart.lcmlog") + out + " --datum 95,0"), 2);
  EXPECT_EQ(evaluate(file("apart.lcmlog") + out + " --datum -33.9"), 2);
  EXPECT_NE(output_.find("--datum needs LAT,LON or LAT,LON,ALT"), std::string::npos) << output_;
  EXPECT_EQ(evaluate(file("apart.lcmlog") + out + " --datum 1,2,3,4"), 2);
  EXPECT_EQ(evaluate("--help"), 0);
  EXPECT_NE(output_.find("--datum LAT,LON[,ALT] "), std::string::npos) << output_;
  EXPECT_EQ(evaluate(file("apart.lcmlog") + out + " --config " + file("missing.yaml")), 2);
  // The estimates' channel as the truth: said so (it said "no estimates on POSE" though the log
  // lists POSE), for --all-poses a shadow's channel too.
  EXPECT_EQ(evaluate(file("apart.lcmlog") + out + " --truth-channel POSE"), 2);
  EXPECT_NE(output_.find("--truth-channel POSE is a channel of the estimates"), std::string::npos) << output_;
  EXPECT_EQ(evaluate(file("apart.lcmlog") + out + " --all-poses --truth-channel POSE_DEAD_RECKONING"), 2);
  EXPECT_NE(evaluate(file("apart.lcmlog") + out + " --log-level loud"), 0);
  EXPECT_NE(output_.find("--log-level: loud not in"), std::string::npos) << output_;
  // A channel of another type: --gate-channel GROUND_TRUTH printed one "undecodable" warning per
  // message and exited 0; --pose-channel too before its error.
  {
    LogWriter w(file("run.lcmlog"));
    for (int i = 0; i < 30; ++i) {
      w.add("GROUND_TRUTH", truthMsg(kT0 + i * 1000, 0.01 * i, 0, 0), kT0 + i * 1000);
      w.add("POSE", poseMsg(kT0 + i * 1000, 0.01 * i, 0, 0, Eigen::Matrix3d::Identity()), kT0 + i * 1000);
      w.add("TRUTH_COPY", truthMsg(kT0 + i * 1000, 0.01 * i, 0, 0), kT0 + i * 1000);
    }
  }
  EXPECT_EQ(evaluate(file("run.lcmlog") + out), 0) << output_;
  EXPECT_EQ(evaluate(file("run.lcmlog") + out + " --gate-channel TRUTH_COPY --overwrite"), 2);
  EXPECT_NE(output_.find("--gate-channel TRUTH_COPY: none of its 30 messages is of the type that option reads "
                         "(gate_decision_t): is it the right channel?"), std::string::npos) << output_;
  EXPECT_EQ(output_.find("undecodable"), std::string::npos) << output_;
  EXPECT_EQ(evaluate(file("run.lcmlog") + out + " --pose-channel TRUTH_COPY --overwrite"), 2);
  EXPECT_NE(output_.find("--pose-channel TRUTH_COPY: none of its 30 messages"), std::string::npos) << output_;
}

// Many bad messages: the first ten are warned about, then how many more (report.json has all).
TEST_F(EvaluateTest, ManyIssuesAreWarnedAboutTenAtATime) {
  {
    LogWriter w(file("run.lcmlog"));
    for (int i = 0; i < 40; ++i) {
      const int64_t t = kT0 + i * 10000;
      w.add("GROUND_TRUTH", truthMsg(t, 0.01 * i, 0, 0), t);
      w.add("POSE", poseMsg(t, 0.01 * i, 0, 0, Eigen::Matrix3d::Identity()), t);
      w.add("POSE", truthMsg(t, 0, 0, 0), t);  // 40 messages of another type on POSE
    }
  }
  ASSERT_EQ(evaluate(file("run.lcmlog") + " --no-plots -o " + file("out")), 0) << output_;
  std::size_t warned = 0;
  for (std::size_t p = output_.find("undecodable POSE message"); p != std::string::npos;
       p = output_.find("undecodable POSE message", p + 1))
    ++warned;
  EXPECT_EQ(warned, 10u + 10u) << output_;  // the warnings, and the summary's list of the first ten
  EXPECT_NE(output_.find("... and 30 more issue(s) (report.json lists them all)"), std::string::npos) << output_;
  EXPECT_EQ(report(file("out"))["log"]["issues"].size(), 40u);
}

TEST_F(EvaluateTest, DamagedLogIsReportedAndTheRestUsed) {
  std::vector<int64_t> starts;
  {
    LogWriter w(file("run.lcmlog"));
    for (int i = 0; i <= 200; ++i) {
      const int64_t t = kT0 + i * 10000;
      w.add("GROUND_TRUTH", truthMsg(t, 0.01 * i, 0.0, 0.0), t);
      w.add("POSE", poseMsg(t, 0.01 * i + 0.1, 0.0, 0.0, Eigen::Matrix3d::Identity()), t);
    }
    starts = w.layout.starts;
  }
  // Corrupt the sync word of event 100 (a truth sample) and cut the file inside the last event.
  const int64_t bad = starts[100];
  {
    std::fstream f(file("run.lcmlog"), std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(bad);
    f.write("XXXX", 4);
  }
  fs::resize_file(file("run.lcmlog"), static_cast<uintmax_t>(starts.back() + 20));
  // Done from the intact events, and said so in the exit status (3), as every log-reading tool does.
  ASSERT_EQ(evaluate(file("run.lcmlog") + " --no-plots -o " + file("out")), 3) << output_;
  EXPECT_NE(output_.find("damaged"), std::string::npos) << output_;
  EXPECT_NE(output_.find("at byte " + std::to_string(bad)), std::string::npos) << output_;
  const auto j = report(file("out"));
  EXPECT_TRUE(j["log"]["damaged"].get<bool>());
  ASSERT_EQ(j["log"]["issues"].size(), 2u);
  EXPECT_EQ(j["log"]["issues"][0]["byte_offset"], bad);
  EXPECT_EQ(j["log"]["issues"][0]["event_index"], 100);
  EXPECT_EQ(j["truth"]["samples"], 200);                // 201 minus the damaged one
  EXPECT_EQ(j["tracks"][0]["estimates"], 200);          // 201 minus the cut last one
  EXPECT_NEAR(j["tracks"][0]["position_error_m"]["rmse"].get<double>(), 0.1, 1e-9);
}

TEST(InterpolateTruth, ExtremeUtimesDoNotOverflow) {
  constexpr int64_t kMin = std::numeric_limits<int64_t>::min(), kMax = std::numeric_limits<int64_t>::max();
  const std::vector<eval::TruthPose> truth{{kMin, 0.0, 0.0, 0.0, true}, {0, 2.0, 0.0, 0.0, true},
                                           {kMax, 4.0, 0.0, 0.0, true}};
  auto t = eval::interpolateTruth(truth, kMin / 2, 0);
  ASSERT_TRUE(t.has_value());
  EXPECT_DOUBLE_EQ(t->x, 1.0);
  t = eval::interpolateTruth(truth, -1, 0);
  ASSERT_TRUE(t.has_value());
  EXPECT_NEAR(t->x, 2.0, 1e-9);
  t = eval::interpolateTruth(truth, kMax / 2, 0);
  ASSERT_TRUE(t.has_value());
  EXPECT_NEAR(t->x, 3.0, 1e-9);
  eval::TruthMiss why = eval::TruthMiss::kNone;
  EXPECT_FALSE(eval::interpolateTruth(truth, -1, 1000000, &why).has_value());  // a gap of 2^63 us
  EXPECT_EQ(why, eval::TruthMiss::kGap);
}

TEST_F(EvaluateTest, AbsurdUtimesAreSkippedCountedAndReported) {
  constexpr int64_t kMin = std::numeric_limits<int64_t>::min(), kMax = std::numeric_limits<int64_t>::max();
  {
    LogWriter w(file("run.lcmlog"));
    w.add("GROUND_TRUTH", truthMsg(kMin, 100.0, 0.0, 0.0), kT0);
    w.add("POSE", poseMsg(kMax, 0.0, 0.0, 0.0, Eigen::Matrix3d::Identity()), kT0);
    gate_decision_t g = gateMsg("ukf_gated", "MAGRULER", 2, 1.0, true, "accepted");
    g.utime = -logio::kUtimeLimit;  // the first negative utime refused
    w.add("GATE", g, kT0);
    for (int i = 0; i <= 200; ++i) {
      const int64_t t = kT0 + i * 10000;
      w.add("GROUND_TRUTH", truthMsg(t, 0.01 * i, 0.0, 0.0), t);
      w.add("POSE", poseMsg(t, 0.01 * i + 0.1, 0.0, 0.0, Eigen::Matrix3d::Identity()), t);
    }
  }
  ASSERT_EQ(evaluate(file("run.lcmlog") + " -o " + file("out")), 0) << output_;
  EXPECT_NE(output_.find("warning: 3 message(s) skipped for |utime| >= 2^62 us"), std::string::npos) << output_;
  EXPECT_NE(output_.find("GROUND_TRUTH message with utime -9223372036854775808 skipped"), std::string::npos)
      << output_;
  const auto j = report(file("out"));
  EXPECT_EQ(j["log"].value("bad_utime", -1), 3);
  EXPECT_EQ(j["log"]["issues"].size(), 3u);
  EXPECT_EQ(j["truth"]["samples"], 201);
  EXPECT_EQ(j["truth"]["first_utime"], kT0);
  EXPECT_EQ(j["gate"]["decisions"], 0);
  EXPECT_EQ(j["tracks"][0]["estimates"], 201);
  EXPECT_EQ(j["tracks"][0]["scored"], 201);
  EXPECT_NEAR(j["tracks"][0]["position_error_m"]["rmse"].get<double>(), 0.1, 1e-9);
}

TEST_F(EvaluateTest, ChannelsWhoseStemsCollideGetFilesOfTheirOwn) {
  {
    LogWriter w(file("run.lcmlog"));
    for (int i = 0; i <= 200; ++i) {
      const int64_t t = kT0 + i * 10000;
      w.add("GROUND_TRUTH", truthMsg(t, 0.01 * i, 0.0, 0.0), t);
      w.add("POSE", poseMsg(t, 0.01 * i, 0.1, 0.0, Eigen::Matrix3d::Identity()), t);
      w.add("POSE_A.B", poseMsg(t, 0.01 * i, 0.2, 0.0, Eigen::Matrix3d::Identity()), t);
      w.add("POSE_A_B", poseMsg(t, 0.01 * i, 0.3, 0.0, Eigen::Matrix3d::Identity()), t);
    }
  }
  ASSERT_EQ(evaluate(file("run.lcmlog") + " --all-poses -o " + file("out") + " --tum-dir " + file("tum")), 0)
      << output_;
  // TUM files too: one per channel, none over another.
  for (const char* tum : {"estimate.tum", "estimate_POSE_A_B.tum", "estimate_POSE_A_B_2.tum"})
    EXPECT_TRUE(fs::exists(file("tum/") + tum)) << tum;
  // The position error (column 5) tells whose track a file holds.
  auto error = [&](const std::string& name) {
    std::ifstream f(file("out/" + name));
    std::string line;
    std::getline(f, line);  // header
    std::getline(f, line);
    std::istringstream s(line);
    double v[5] = {-1, -1, -1, -1, -1};
    for (double& x : v) s >> x;
    return v[4];
  };
  EXPECT_NEAR(error("track_POSE.dat"), 0.1, 1e-9);
  EXPECT_NEAR(error("track_POSE_A_B.dat"), 0.3, 1e-9);    // POSE_A_B keeps its own name
  EXPECT_NEAR(error("track_POSE_A_B_2.dat"), 0.2, 1e-9);  // POSE_A.B
  EXPECT_TRUE(fs::exists(file("out/ellipses_POSE_A_B_2.dat")));
  if (std::system("command -v gnuplot > /dev/null") == 0) {
    for (const char* png : {"trajectory_POSE_A_B.png", "trajectory_POSE_A_B_2.png", "errors_POSE_A_B_2.png",
                            "nees_POSE_A_B_2.png"})
      EXPECT_GT(fs::file_size(file("out/") + png), 1000u) << png;
  }
}

TEST_F(EvaluateTest, ChannelNamesRunNoCommandInGnuplot) {
  if (std::system("command -v gnuplot > /dev/null") != 0) GTEST_SKIP() << "gnuplot not installed";
  // Channel names that end the script's string and start a command: on a new line, and in
  // backquotes (command substitution outside quotes).
  const std::string nl = file("PWNED_nl"), bq = file("PWNED_bq");
  {
    LogWriter w(file("run.lcmlog"));
    for (int i = 0; i <= 200; ++i) {
      const int64_t t = kT0 + i * 10000;
      w.add("GROUND_TRUTH", truthMsg(t, 0.01 * i, 0.0, 0.0), t);
      w.add("POSE", poseMsg(t, 0.01 * i, 0.1, 0.0, Eigen::Matrix3d::Identity()), t);
      w.add("POSE_x'\nsystem 'touch " + nl + "'\n'", poseMsg(t, 0.01 * i, 0.2, 0.0, Eigen::Matrix3d::Identity()), t);
      w.add("POSE_y'`touch " + bq + "`'", poseMsg(t, 0.01 * i, 0.3, 0.0, Eigen::Matrix3d::Identity()), t);
    }
  }
  ASSERT_EQ(evaluate(file("run.lcmlog") + " --all-poses -o " + file("out")), 0) << output_;
  EXPECT_NE(output_.find("figures: "), std::string::npos) << output_;  // the script ran through
  EXPECT_EQ(report(file("out"))["tracks"].size(), 3u);
  EXPECT_FALSE(fs::exists(nl));
  EXPECT_FALSE(fs::exists(bq));
  // The terminal summary shows the newlines of the name as '?': no line of it is the log's to write.
  EXPECT_NE(output_.find("POSE_x'?system 'touch"), std::string::npos) << output_;
  EXPECT_EQ(output_.find("\nsystem 'touch"), std::string::npos) << output_;
}

}  // namespace

TEST_F(EvaluateTest, TheLockOutTimelineGivesEachSpanAndTheReLocalizationsOfTheTracksFilters) {
  {
    LogWriter w(file("run.lcmlog"));
    // 10 s at 10 Hz: ok until 2 s, lock-out 2..5 s, ok, dead reckoning 6..7 s, lock-out 8..8.5 s, ok.
    auto statusAt = [](int i) -> int32_t {
      if (i >= 20 && i < 50) return pose_t::STATUS_LOCKOUT;
      if (i >= 60 && i < 70) return pose_t::STATUS_DEAD_RECKONING;
      if (i >= 80 && i < 85) return pose_t::STATUS_LOCKOUT;
      return pose_t::STATUS_OK;
    };
    for (int i = 0; i <= 100; ++i) {
      const int64_t t = kT0 + i * 100000;
      w.add("GROUND_TRUTH", truthMsg(t, 0.1 * i, 0.0, 0.0), t);
      pose_t p = poseMsg(t, 0.1 * i, 0.0, 0.0, Eigen::Matrix3d::Identity() * 0.01, "ukf_landmarks");
      p.status = statusAt(i);
      w.add("POSE", p, t);
    }
    // Re-localized at 5 s and 8.5 s; another filter's re-localization is not this track's.
    auto relocalized = [&](const char* filter, const char* sensor, int64_t at) {
      gate_decision_t d = gateMsg(filter, sensor, 2, 1.0, true, "relocalized");
      d.utime = at;
      w.add("GATE", d, at);
    };
    relocalized("ukf_landmarks", "LANDMARKS", kT0 + 5000000);
    relocalized("ukf_landmarks", "LANDMARKS", kT0 + 8500000);
    relocalized("tvekf", "GPS", kT0 + 3000000);
  }
  ASSERT_EQ(evaluate(file("run.lcmlog") + " -o " + file("out")), 0) << output_;
  const auto st = report(file("out")).at("tracks").at(0).at("status_timeline");
  EXPECT_EQ(st.at("lockouts"), 2);
  EXPECT_NEAR(st.at("lockout_s").get<double>(), 3.5, 1e-9);
  EXPECT_NEAR(st.at("longest_lockout_s").get<double>(), 3.0, 1e-9);
  EXPECT_NEAR(st.at("dead_reckoning_s").get<double>(), 1.0, 1e-9);
  ASSERT_EQ(st.at("spans").size(), 7u);
  EXPECT_EQ(st["spans"][1]["status"], "lockout");
  EXPECT_NEAR(st["spans"][1]["from_s"].get<double>(), 2.0, 1e-9);
  EXPECT_NEAR(st["spans"][1]["to_s"].get<double>(), 5.0, 1e-9);
  EXPECT_EQ(st["spans"][1]["estimates"], 30);
  EXPECT_EQ(st["spans"][3]["status"], "dead_reckoning");
  ASSERT_EQ(st.at("relocalizations").size(), 2u);
  EXPECT_NEAR(st["relocalizations"][0]["t_s"].get<double>(), 5.0, 1e-9);
  EXPECT_EQ(st["relocalizations"][1]["filter"], "ukf_landmarks");
  EXPECT_NE(output_.find("POSE status: 2 lock-out(s), 3.5 s in lock-out (longest 3.0 s), 1.0 s dead reckoning, 2 "
                         "re-localization(s) at 5.0 s, 8.5 s"),
            std::string::npos)
      << output_;
  if (std::system("command -v gnuplot > /dev/null") == 0) {
    EXPECT_GT(fs::file_size(file("out/status_POSE.png")), 1000u);
  }
}

TEST_F(EvaluateTest, ATrackThatNeverLeftTrackingHasNoStatusLineNorFigure) {
  {
    LogWriter w(file("run.lcmlog"));
    for (int i = 0; i <= 20; ++i) {
      const int64_t t = kT0 + i * 100000;
      w.add("GROUND_TRUTH", truthMsg(t, 0.1 * i, 0.0, 0.0), t);
      w.add("POSE", poseMsg(t, 0.1 * i, 0.0, 0.0, Eigen::Matrix3d::Identity() * 0.01), t);
    }
  }
  ASSERT_EQ(evaluate(file("run.lcmlog") + " -o " + file("out")), 0) << output_;
  const auto st = report(file("out"))["tracks"][0]["status_timeline"];
  EXPECT_EQ(st.at("lockouts"), 0);
  EXPECT_EQ(st.at("spans").size(), 1u);
  EXPECT_EQ(output_.find("POSE status:"), std::string::npos) << output_;
  EXPECT_FALSE(fs::exists(file("out/status_POSE.png")));
}
