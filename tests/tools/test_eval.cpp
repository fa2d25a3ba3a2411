// lcmloc-eval on a small hand-made log: a straight run north at 1 m/s with exact odometry,
// four genuine marker detections, one wrong-offset fault (instead of the genuine detection of
// the marker at y = 6) and one phantom marker between markers, plus live POSE/GATE messages.
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>

#include "lcmloc/app/config.hpp"
#include "lcmloc/eval/evaluate.hpp"
#include "lcmloc/eval/gnuplot.hpp"
#include "lcmloc/eval/report.hpp"
#include "lcmloc/eval/log_reader.hpp"
#include "lcmloc/fault_event_t.hpp"
#include "lcmloc/gate_decision_t.hpp"
#include "lcmloc/ground_truth_t.hpp"
#include "lcmloc/magruler_t.hpp"
#include "lcmloc/sim/world.hpp"
#include "lcmloc/odometry_t.hpp"
#include "lcmloc/pose_t.hpp"
#include "test_log_writer.hpp"

namespace fs = std::filesystem;
using namespace lcmloc;

namespace {

constexpr int64_t kT0 = 1000000;        // utime of the first sample [us]
constexpr int64_t kDt = 10000;          // 100 Hz
constexpr int kSteps = 1000;            // 10 s at 1 m/s: y from 0 to 10 m
constexpr double kLiveOffsetX = 0.1;    // the fake live daemon's constant x error [m]

using testlog::LogLayout;
using testlog::LogWriter;

struct Detection { int step; double offset; std::string channel; int64_t seq; const char* fault; };

/// Genuine detections where the ruler (1.5 m ahead of M) passes markers 2, 4, 8, 10; a
/// wrong-offset fault over marker 6; a phantom 1 m from any marker (out of the ruler's reach).
const std::vector<Detection> kDetections{{50, 0.0, "MAGRULER", 0, nullptr},
                                         {250, 0.0, "MAGRULER", 1, nullptr},
                                         {450, 0.35, "MAGRULER_FAULT", 0, "wrong_offset"},
                                         {650, 0.0, "MAGRULER", 2, nullptr},
                                         {750, 0.0, "MAGRULER_FAULT", 1, "phantom_marker"},
                                         {850, 0.0, "MAGRULER", 3, nullptr}};

lcmloc::magruler_t ruler(int64_t utime, int64_t seq, double offset) {
  lcmloc::magruler_t m;
  m.utime = utime;
  m.seq = seq;
  m.num_sensors = 13;
  m.readings.assign(13, -0.45);
  m.detected = true;
  m.lateral_offset = offset;
  m.quality = 1.0;
  return m;
}

/// What writeRun may change (for the tests of hostile logs).
struct RunOptions {
  std::string fault_kind;                      ///< kind of every fault (empty: the detection's own)
  std::string live_filter = "ukf_gated";       ///< filter named by the live POSE messages
  int64_t truth_shift_us = 0;                  ///< ground truth's utimes moved by this
  std::function<void(LogWriter&)> first;       ///< writes events before the run
};

/// Writes the whole run; with_live adds POSE (x off by kLiveOffsetX) and GATE messages.
LogLayout writeRun(const std::string& path, bool with_live, const RunOptions& o = {}) {
  LogWriter w(path);
  if (o.first) o.first(w);
  int64_t pose_seq = 0, gate_seq = 0, fault_seq = 0;
  size_t next_det = 0;
  for (int k = 0; k <= kSteps; ++k) {
    const int64_t t = kT0 + k * kDt;
    const double y = 0.01 * k;
    lcmloc::ground_truth_t gt{};
    gt.utime = t + o.truth_shift_us; gt.seq = k; gt.x = 0.0; gt.y = y; gt.heading = M_PI / 2; gt.speed = 1.0;
    gt.distance = y;
    w.add("GROUND_TRUTH", gt, t);
    if (k > 0) {
      lcmloc::odometry_t od{};
      od.utime = t; od.seq = k - 1; od.delta_s = 0.01; od.ticks = 10; od.has_steering = true;
      w.add("ODOMETRY", od, t);
    }
    if (next_det < kDetections.size() && kDetections[next_det].step == k) {
      const Detection& d = kDetections[next_det++];
      w.add(d.channel, ruler(t, d.seq, d.offset), t);
      if (d.fault) {
        lcmloc::fault_event_t f{};
        f.utime = t; f.seq = fault_seq++; f.kind = o.fault_kind.empty() ? d.fault : o.fault_kind; f.channel = d.channel;
        f.measurement_seq = d.seq; f.x = 0.0; f.y = y; f.lateral_offset = d.offset;
        w.add("FAULT_EVENTS", f, t);
      }
      if (with_live) {
        lcmloc::gate_decision_t g{};
        g.utime = t; g.seq = gate_seq++; g.filter = "ukf_gated"; g.sensor = d.channel;
        g.measurement_seq = d.seq; g.dim = 2; g.innovation = {0.0, 0.0};
        g.mahalanobis = d.fault ? 50.0 : 1.0; g.gate = 9.21; g.accepted = d.fault == nullptr;
        g.marker_id = -1; g.reason = d.fault ? "gate" : "accepted";
        w.add("GATE", g, t);
      }
    }
    if (with_live && k > 0 && k % 10 == 0) {
      lcmloc::pose_t p{};
      p.utime = t; p.seq = pose_seq++; p.filter = o.live_filter; p.status = 0; p.dim = 3;
      p.state = {kLiveOffsetX, y, M_PI / 2};
      p.state_names = {"x", "y", "theta"};
      p.covariance.assign(3, std::vector<double>(3, 0.0));
      w.add("POSE", p, t);
    }
  }
  return w.layout;  // the file is closed (and flushed) when w goes out of scope
}

class EvalTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("lcmloc_test_eval_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    cfg_ = common::loadSystemConfig(LCMLOC_TEST_DATA_DIR "/eval_straight.yaml");
    setup_.filter = cfg_.fusion.filter;
    setup_.map = models::makeMarkerMap(models::Path(cfg_.scenario.path), cfg_.scenario.markers);
    setup_.reorder_window_us = static_cast<int64_t>(std::llround(cfg_.fusion.reorder_window * 1e6));
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }
  const eval::FilterRun& run(const eval::Evaluation& ev, const std::string& name) {
    for (const auto& r : ev.filters) if (r.name == name) return r;
    throw std::runtime_error("no run " + name);
  }

  fs::path dir_;
  common::SystemConfig cfg_;
  eval::EvalSetup setup_;
};

TEST_F(EvalTest, MarkerMapOfTheTestWorld) {
  ASSERT_EQ(setup_.map.size(), 5u);
  EXPECT_NEAR(setup_.map[2].x, 0.0, 1e-9);
  EXPECT_NEAR(setup_.map[2].y, 6.0, 1e-9);
}

TEST_F(EvalTest, ReadsEveryChannel) {
  const auto w = writeRun(file("run.lcmlog"), false);
  const auto data = eval::readLog(file("run.lcmlog"), cfg_.channels);
  EXPECT_EQ(data.events_read, static_cast<int64_t>(w.starts.size()));
  EXPECT_FALSE(data.damaged);
  EXPECT_TRUE(data.issues.empty());
  EXPECT_EQ(data.truth.size(), static_cast<size_t>(kSteps + 1));
  EXPECT_EQ(data.odometry_messages, kSteps);
  EXPECT_EQ(data.ruler_detections, 6);
  EXPECT_EQ(data.inputs.size(), static_cast<size_t>(kSteps + 6));
  ASSERT_EQ(data.faults.size(), 2u);
  EXPECT_EQ(data.faults[0].channel, "MAGRULER_FAULT");
  EXPECT_EQ(data.faults[1].measurement_seq, 1);
}

TEST_F(EvalTest, CountsAndMetricsOfEachFilter) {
  writeRun(file("run.lcmlog"), false);
  const auto data = eval::readLog(file("run.lcmlog"), cfg_.channels);
  const auto ev = eval::evaluate(data, setup_);
  ASSERT_EQ(ev.filters.size(), 3u);
  EXPECT_NEAR(ev.gate_threshold, 9.21, 0.01);  // default: 99 % on the innovation's 2 dof
  EXPECT_FALSE(ev.live.has_value());

  const auto& dr = run(ev, "dead_reckoning").metrics;  // exact odometry on a straight line
  EXPECT_LT(dr.rmse_m, 1e-9);
  EXPECT_EQ(dr.accepted, 0);
  EXPECT_EQ(dr.rejected, 0);
  EXPECT_EQ(dr.ignored, 6);
  EXPECT_EQ(dr.faults_total, 2);
  EXPECT_GE(dr.samples, kSteps);

  const auto& ukf = run(ev, "ukf").metrics;  // ungated: takes the wrong offset
  EXPECT_EQ(ukf.accepted, 5);
  EXPECT_EQ(ukf.rejected, 1);  // the phantom has no reachable marker
  EXPECT_EQ(ukf.faults_total, 2);
  EXPECT_EQ(ukf.faults_accepted, 1);
  EXPECT_EQ(ukf.faults_rejected, 1);
  EXPECT_EQ(ukf.valid_rejected, 0);
  EXPECT_GT(ukf.max_error_m, 0.05);

  const auto& gated = run(ev, "ukf_gated").metrics;
  EXPECT_EQ(gated.accepted, 4);
  EXPECT_EQ(gated.rejected, 2);
  EXPECT_EQ(gated.faults_total, 2);
  EXPECT_EQ(gated.faults_rejected, 2);
  EXPECT_EQ(gated.faults_accepted, 0);
  EXPECT_EQ(gated.valid_rejected, 0);
  EXPECT_LT(gated.max_error_m, 0.02);
  EXPECT_LT(gated.final_error_m, 0.01);
  EXPECT_GT(ukf.max_error_m, 3 * gated.max_error_m);

  // The wrong offset is far outside the gate, the valid markers inside it.
  const auto& decisions = run(ev, "ukf_gated").decisions;
  ASSERT_EQ(decisions.size(), 6u);
  EXPECT_TRUE(decisions[2].is_fault);
  EXPECT_EQ(decisions[2].decision.reason, "gate");
  EXPECT_GT(decisions[2].decision.mahalanobis, ev.gate_threshold);
  EXPECT_EQ(decisions[4].decision.reason, "no_candidate");
  for (int i : {0, 1, 3, 5}) {
    EXPECT_FALSE(decisions[i].is_fault);
    EXPECT_LT(decisions[i].decision.mahalanobis, ev.gate_threshold) << i;
  }
}

// lcmloc-eval replays with the daemon's engine configuration (common::engineConfig), not the
// engine's defaults: a config that turns the odometry-gap bridge off is obeyed, as live.
TEST_F(EvalTest, TheEngineConfigurationIsTheDaemons) {
  writeRun(file("run.lcmlog"), false);
  auto data = eval::readLog(file("run.lcmlog"), cfg_.channels);
  // 0.5 s of odometry lost in transit (the seq numbers were used up).
  std::vector<core::EngineInput> kept;
  for (const auto& in : data.inputs)
    if (!(std::holds_alternative<core::OdometryInput>(in.payload) && in.utime > kT0 + 100 * kDt &&
          in.utime <= kT0 + 150 * kDt))
      kept.push_back(in);
  data.inputs = kept;
  auto lastY = [&](bool bridge) {
    auto c = cfg_;
    c.fusion.max_odometry_gap = bridge ? 0.1 : 0.0;
    setup_.engine = common::engineConfig(c);
    setup_.filters = {"dead_reckoning"};
    const auto ev = eval::evaluate(data, setup_);
    return run(ev, "dead_reckoning").track.back().y;
  };
  const double bridged = lastY(true), off = lastY(false);
  EXPECT_NEAR(bridged - off, 0.5, 0.02) << "the 0.5 m of the gap at 1 m/s, bridged only when the config says so";
}

TEST_F(EvalTest, ReportWithInvalidUtf8FromTheLogIsWrittenWithReplacements) {
  // A channel or filter name from a damaged log may hold any bytes.
  nlohmann::json j;
  j["filter"] = std::string("ukf\xC1\x80");
  ASSERT_NO_THROW(eval::writeJson(j, file("r.json")));
  std::ifstream in(file("r.json"));
  const auto back = nlohmann::json::parse(in);
  EXPECT_EQ(back["filter"].get<std::string>(), "ukf\xEF\xBF\xBD\xEF\xBF\xBD");  // U+FFFD twice
  EXPECT_THROW(eval::writeJson(j, file("no/such/dir/r.json")), std::runtime_error);
}

TEST_F(EvalTest, FiltersNeedingOtherSensorsAreRefusedNotScoredOnOdometryAlone) {
  writeRun(file("run.lcmlog"), false);
  const auto data = eval::readLog(file("run.lcmlog"), cfg_.channels);
  for (const std::string f : {"tvekf", "ukf_gps", "ukf_landmarks", "odo_ins"}) {
    auto setup = setup_;
    setup.filters = {"ukf_gated", f};
    try {
      eval::evaluate(data, setup);
      ADD_FAILURE() << f << " was evaluated";
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("filter '" + f + "' needs"), std::string::npos) << what;
      EXPECT_NE(what.find("lcmloc-replay"), std::string::npos) << what;
    }
  }
  auto setup = setup_;
  setup.filters = {"ukf_calib"};
  EXPECT_EQ(eval::evaluate(data, setup).filters.size(), 1u);
}

TEST_F(EvalTest, LivePoseIsScoredAndComparedWithReplay) {
  writeRun(file("run.lcmlog"), true);
  const auto data = eval::readLog(file("run.lcmlog"), cfg_.channels);
  const auto ev = eval::evaluate(data, setup_);
  ASSERT_TRUE(ev.live.has_value());
  EXPECT_EQ(ev.live->filter, "ukf_gated");
  const auto& m = ev.live->run.metrics;
  EXPECT_EQ(m.samples, kSteps / 10);
  EXPECT_NEAR(m.rmse_m, kLiveOffsetX, 1e-9);
  EXPECT_NEAR(m.final_error_m, kLiveOffsetX, 1e-9);
  EXPECT_EQ(m.accepted, 4);
  EXPECT_EQ(m.faults_rejected, 2);
  EXPECT_EQ(ev.live->matched_poses, kSteps / 10);
  EXPECT_NEAR(ev.live->max_diff_to_replay_m, kLiveOffsetX, 0.02);
}

TEST_F(EvalTest, TruncatedLogReportsOffsetAndKeepsWhatWasRead) {
  const auto w = writeRun(file("run.lcmlog"), false);
  const auto size = static_cast<int64_t>(fs::file_size(file("run.lcmlog")));
  fs::resize_file(file("run.lcmlog"), static_cast<uintmax_t>(size - 5));  // cut the last event
  const auto data = eval::readLog(file("run.lcmlog"), cfg_.channels);
  EXPECT_EQ(data.events_read, static_cast<int64_t>(w.starts.size()) - 1);
  EXPECT_TRUE(data.damaged);
  ASSERT_EQ(data.issues.size(), 1u);
  EXPECT_EQ(data.issues[0].byte_offset, w.starts.back());
  EXPECT_EQ(data.issues[0].event_index, static_cast<int64_t>(w.starts.size()) - 1);
  EXPECT_NE(data.issues[0].what.find("truncated"), std::string::npos) << data.issues[0].what;
  EXPECT_EQ(data.bytes_unreadable, size - 5 - w.starts.back());
  // What was read is still evaluated.
  const auto ev = eval::evaluate(data, setup_);
  EXPECT_EQ(run(ev, "ukf_gated").metrics.faults_rejected, 2);
}

TEST_F(EvalTest, CorruptEventIsSkippedAndReadingResumes) {
  const auto w = writeRun(file("run.lcmlog"), false);
  const size_t bad = 500;  // an event in the middle: corrupt its channel length
  {
    std::fstream f(file("run.lcmlog"), std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(w.starts[bad] + 20);
    const char huge[4] = {0x00, 0x00, 0x7f, 0x00};
    f.write(huge, 4);
  }
  const auto data = eval::readLog(file("run.lcmlog"), cfg_.channels);
  EXPECT_EQ(data.events_read, static_cast<int64_t>(w.starts.size()) - 1);
  EXPECT_TRUE(data.damaged);
  ASSERT_EQ(data.issues.size(), 1u);
  EXPECT_EQ(data.issues[0].byte_offset, w.starts[bad]);
  EXPECT_EQ(data.issues[0].event_index, static_cast<int64_t>(bad));
  EXPECT_EQ(data.bytes_unreadable, w.starts[bad + 1] - w.starts[bad]);
  EXPECT_NE(data.issues[0].what.find("resumed at byte " + std::to_string(w.starts[bad + 1])),
            std::string::npos) << data.issues[0].what;
  EXPECT_EQ(data.truth.size() + static_cast<size_t>(data.odometry_messages),
            static_cast<size_t>(2 * kSteps));  // exactly one truth or odometry event lost
}

TEST_F(EvalTest, UndecodablePayloadIsReportedAndSkipped) {
  const auto w = writeRun(file("run.lcmlog"), false);
  size_t bad = 0;
  while (w.channels[bad] != "ODOMETRY") ++bad;
  {
    std::fstream f(file("run.lcmlog"), std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(w.starts[bad] + 28 + static_cast<int64_t>(w.channels[bad].size()));  // fingerprint
    f.write("\xde\xad\xbe\xef", 4);
  }
  const auto data = eval::readLog(file("run.lcmlog"), cfg_.channels);
  EXPECT_EQ(data.events_read, static_cast<int64_t>(w.starts.size()));
  EXPECT_FALSE(data.damaged);
  ASSERT_EQ(data.issues.size(), 1u);
  EXPECT_EQ(data.issues[0].byte_offset, w.starts[bad]);
  EXPECT_NE(data.issues[0].what.find("undecodable ODOMETRY"), std::string::npos);
  EXPECT_EQ(data.odometry_messages, kSteps - 1);
}

TEST_F(EvalTest, MissingFileThrows) {
  EXPECT_THROW(eval::readLog(file("nope.lcmlog"), cfg_.channels), std::runtime_error);
}

TEST_F(EvalTest, ADirectoryIsNotALog) {
  // It used to read as one damaged stretch of 4096 bytes and an empty log.
  try {
    eval::readLog(dir_.string(), cfg_.channels);
    FAIL() << "a directory was read as a log";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("is a directory"), std::string::npos) << e.what();
  }
  EXPECT_THROW(eval::scanLog(dir_.string(), [](const eval::RawEvent&) {}), std::runtime_error);
}

TEST(TruthAt, InterpolatesInsideAndRefusesFarOutside) {
  std::vector<eval::TruthSample> truth{{1000000, 0.0, 0.0, 3.0, 0.0}, {1010000, 1.0, 2.0, -3.0, 1.0}};
  auto mid = eval::truthAt(truth, 1005000);
  ASSERT_TRUE(mid.has_value());
  EXPECT_DOUBLE_EQ(mid->x, 0.5);
  EXPECT_DOUBLE_EQ(mid->y, 1.0);
  EXPECT_NEAR(std::abs(mid->heading), M_PI, 1e-12);  // midway between 3 and -3 across +-pi
  EXPECT_TRUE(eval::truthAt(truth, 1050000).has_value());   // within 0.1 s of the end
  EXPECT_FALSE(eval::truthAt(truth, 1200000).has_value());
  EXPECT_FALSE(eval::truthAt({}, 0).has_value());
}

TEST(TruthAt, ExtremeUtimesNeitherOverflowNorHideTheTruth) {
  constexpr int64_t kMin = std::numeric_limits<int64_t>::min(), kMax = std::numeric_limits<int64_t>::max();
  const std::vector<eval::TruthSample> low{{kMin, 0.0, 0.0, 0.0, 0.0}, {0, 2.0, 0.0, 0.0, 0.0}};
  auto at = eval::truthAt(low, 0);
  ASSERT_TRUE(at.has_value());
  EXPECT_DOUBLE_EQ(at->x, 2.0);
  at = eval::truthAt(low, kMin / 2);  // halfway between the two samples
  ASSERT_TRUE(at.has_value());
  EXPECT_DOUBLE_EQ(at->x, 1.0);
  const std::vector<eval::TruthSample> high{{0, 0.0, 0.0, 0.0, 0.0}, {kMax, 2.0, 0.0, 0.0, 0.0}};
  at = eval::truthAt(high, 50000);
  ASSERT_TRUE(at.has_value());
  EXPECT_NEAR(at->x, 0.0, 1e-9);
  EXPECT_FALSE(eval::truthAt({{kMax, 0.0, 0.0, 0.0, 0.0}}, kMin).has_value());
  EXPECT_FALSE(eval::truthAt({{kMin, 0.0, 0.0, 0.0, 0.0}}, kMax).has_value());
  EXPECT_TRUE(eval::truthAt({{kMax, 0.0, 0.0, 0.0, 0.0}}, kMax).has_value());
}

TEST(GnuplotQuote, DoublesQuotesAndReplacesControlCharacters) {
  EXPECT_EQ(eval::gnuplotQuote("ukf gated"), "'ukf gated'");
  EXPECT_EQ(eval::gnuplotQuote("it's"), "'it''s'");
  EXPECT_EQ(eval::gnuplotQuote("x'\nsystem 'touch X'\r\n'"), "'x''?system ''touch X''?" "?'''");
  EXPECT_EQ(eval::gnuplotQuote(std::string("a\0\x01\x1f\t\x7f" "b", 7)), "'a?????b'");
  // Taken literally inside single quotes: backquotes, macros, backslashes; other bytes kept.
  EXPECT_EQ(eval::gnuplotQuote("`touch X` @cmd \\n \\' \xc3\xa9"), "'`touch X` @cmd \\n \\'' \xc3\xa9'");
  EXPECT_EQ(eval::gnuplotQuote(""), "''");
  EXPECT_EQ(eval::withoutControlCharacters("a\nb\x7f"), "a?b?");
}

/// Contents of a file ("" when missing).
std::string slurp(const std::string& path) {
  std::ifstream f(path);
  return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

TEST(GnuplotQuote, GnuplotPrintsTheTextAndRunsNothing) {
  if (!eval::findInPath("gnuplot")) GTEST_SKIP() << "gnuplot not installed";
  const fs::path dir = fs::temp_directory_path() / ("lcmloc_test_quote_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::vector<std::string> texts{"x'\nsystem 'touch X1'\n'", "x'\rsystem 'touch X2'\r'", "x'`touch X3`'",
                                       "`touch X4`", "x' . @cmd . 'y", "a\\'b\\\\", "it's"};
  {
    std::ofstream gp(dir / "q.gp");
    gp << "cmd = \"system('touch X5')\"\n";
    for (const auto& t : texts) gp << "print " << eval::gnuplotQuote(t) << "\n";
  }
  ASSERT_EQ(eval::runGnuplot(dir.string(), "q.gp"), 0) << slurp((dir / "gnuplot.log").string());
  std::string expected;
  for (const auto& t : texts) expected += eval::withoutControlCharacters(t) + "\n";
  EXPECT_EQ(slurp((dir / "gnuplot.log").string()), expected);
  for (const char* x : {"X1", "X2", "X3", "X4", "X5"}) EXPECT_FALSE(fs::exists(dir / x)) << x;
  fs::remove_all(dir);
}

TEST(UniqueStems, SafeDistinctFileNames) {
  // A name that is a stem already keeps it, even when an earlier name would map onto it.
  EXPECT_EQ(eval::uniqueStems({"POSE_A.B", "POSE_A_B", "POSE_A:B"}),
            (std::vector<std::string>{"POSE_A_B_2", "POSE_A_B", "POSE_A_B_3"}));
  EXPECT_EQ(eval::uniqueStems({"live:ukf_gated", "ukf", "ukf"}),
            (std::vector<std::string>{"live_ukf_gated", "ukf", "ukf_2"}));
  EXPECT_EQ(eval::uniqueStems({"../x'\n`y`", ""}), (std::vector<std::string>{"___x___y_", "_"}));
}

/// Runs a command; returns its exit status.
int shell(const std::string& cmd) {
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

TEST_F(EvalTest, MessagesWithAbsurdUtimesAreSkippedCountedAndReported) {
  constexpr int64_t kMin = std::numeric_limits<int64_t>::min(), kMax = std::numeric_limits<int64_t>::max();
  RunOptions o;
  o.first = [&](LogWriter& w) {
    lcmloc::ground_truth_t gt{};
    gt.utime = kMin;
    gt.x = 100.0;
    w.add("GROUND_TRUTH", gt, kT0);
    lcmloc::pose_t p{};
    p.utime = kMax;
    p.filter = "ukf_gated";
    p.dim = 3;
    p.state = {0.0, 0.0, 0.0};
    p.state_names = {"x", "y", "theta"};
    p.covariance.assign(3, std::vector<double>(3, 0.0));
    w.add("POSE", p, kT0);
    lcmloc::odometry_t od{};
    od.utime = kMax - 1;
    od.delta_s = 0.01;
    od.ticks = 10;
    od.has_steering = true;
    w.add("ODOMETRY", od, kT0);
    lcmloc::fault_event_t f{};
    f.utime = eval::kUtimeLimit;  // the first utime refused
    f.kind = "phantom_marker";
    f.channel = "MAGRULER";
    f.measurement_seq = 99;
    w.add("FAULT_EVENTS", f, kT0);
  };
  writeRun(file("run.lcmlog"), true, o);
  const auto data = eval::readLog(file("run.lcmlog"), cfg_.channels);
  EXPECT_EQ(data.bad_utime, 4);
  ASSERT_EQ(data.issues.size(), 4u);
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(data.issues[i].event_index, static_cast<int64_t>(i));
    EXPECT_NE(data.issues[i].what.find("skipped: |utime| >= 2^62 us"), std::string::npos) << data.issues[i].what;
  }
  EXPECT_EQ(data.truth.size(), static_cast<size_t>(kSteps + 1));
  EXPECT_EQ(data.inputs.size(), static_cast<size_t>(kSteps + 6));
  EXPECT_EQ(data.faults.size(), 2u);
  EXPECT_EQ(data.live_poses.size(), static_cast<size_t>(kSteps / 10));
  const auto ev = eval::evaluate(data, setup_);  // scored as without the absurd messages
  EXPECT_GE(run(ev, "dead_reckoning").metrics.samples, kSteps);
  EXPECT_LT(run(ev, "dead_reckoning").metrics.rmse_m, 1e-9);
  EXPECT_EQ(run(ev, "ukf_gated").metrics.faults_rejected, 2);
  EXPECT_EQ(ev.live->run.metrics.samples, kSteps / 10);

  const std::string out = file("out");
  ASSERT_EQ(shell(std::string(LCMLOC_EVAL_BIN) + " " + file("run.lcmlog") + " --config " LCMLOC_TEST_DATA_DIR
                  "/eval_straight.yaml --out " + out + " > " + file("stdout.txt") + " 2>&1"), 0);
  const std::string text = slurp(file("stdout.txt"));
  EXPECT_NE(text.find("warning: 4 message(s) skipped for |utime| >= 2^62 us"), std::string::npos) << text;
  std::ifstream f(out + "/report.json");
  const auto j = nlohmann::json::parse(f);
  EXPECT_EQ(j["log"].value("bad_utime", -1), 4);
  EXPECT_EQ(j["log"]["issues"].size(), 4u);
  EXPECT_LT(j["filters"]["dead_reckoning"]["rmse_m"].get<double>(), 1e-9);
  EXPECT_NEAR(j["live"]["rmse_m"].get<double>(), kLiveOffsetX, 1e-9);
}

TEST_F(EvalTest, FilterWithoutAScoredEstimateHasNoErrorRatherThanZero) {
  RunOptions o;
  o.truth_shift_us = int64_t{1000} * 1000000;  // the truth 1000 s after the run: nothing to score
  writeRun(file("run.lcmlog"), true, o);
  const std::string out = file("out");
  ASSERT_EQ(shell(std::string(LCMLOC_EVAL_BIN) + " " + file("run.lcmlog") + " --config " LCMLOC_TEST_DATA_DIR
                  "/eval_straight.yaml --no-plots --out " + out + " > " + file("stdout.txt") + " 2>&1"), 0);
  const std::string text = slurp(file("stdout.txt"));
  for (const std::string name : {"dead_reckoning", "ukf", "ukf_gated", "live:ukf_gated"}) {
    const auto row = text.find("\n" + name + " ");
    ASSERT_NE(row, std::string::npos) << name << "\n" << text;
    EXPECT_EQ(text.compare(row + 23, 28, "        -        -         -"), 0) << name << "\n" << text;
    EXPECT_NE(text.find("warning: " + name + ": no estimate within 0.1 s of the ground truth"), std::string::npos)
        << name << "\n" << text;
  }
  std::ifstream f(out + "/report.json");
  const auto j = nlohmann::json::parse(f);
  for (const char* name : {"dead_reckoning", "ukf", "ukf_gated"}) {
    EXPECT_EQ(j["filters"][name]["samples"], 0) << name;
    for (const char* key : {"rmse_m", "max_error_m", "final_error_m"})
      EXPECT_TRUE(j["filters"][name][key].is_null()) << name << "." << key;
  }
  EXPECT_TRUE(j["live"]["rmse_m"].is_null());
}

TEST_F(EvalTest, StringsFromTheLogRunNoCommandInGnuplot) {
  if (shell("command -v gnuplot > /dev/null") != 0) GTEST_SKIP() << "gnuplot not installed";
  // A fault kind and a live filter name that end the script's string and start a command:
  // on a new line, and in backquotes (command substitution outside quotes).
  const std::string kind_nl = file("PWNED_kind_nl"), live_nl = file("PWNED_live_nl");
  const std::string kind_bq = file("PWNED_kind_bq"), live_bq = file("PWNED_live_bq");
  const std::vector<std::pair<std::string, std::string>> variants{
      {"x'\nsystem 'touch " + kind_nl + "'\n'", "y'\nsystem 'touch " + live_nl + "'\n'"},
      {"x'`touch " + kind_bq + "`'", "y'`touch " + live_bq + "`'"}};
  for (size_t v = 0; v < variants.size(); ++v) {
    RunOptions o;
    o.fault_kind = variants[v].first;
    o.live_filter = variants[v].second;
    writeRun(file("run.lcmlog"), true, o);
    const std::string out = file("out" + std::to_string(v));
    ASSERT_EQ(shell(std::string(LCMLOC_EVAL_BIN) + " " + file("run.lcmlog") + " --config " LCMLOC_TEST_DATA_DIR
                    "/eval_straight.yaml --out " + out + " > " + file("stdout.txt") + " 2>&1"), 0);
    // The script ran through without an error (every figure drawn) and ran nothing else.
    EXPECT_NE(slurp(file("stdout.txt")).find("figures: "), std::string::npos) << slurp(out + "/gnuplot.log");
    for (const char* png : {"trajectories.png", "trajectories_faults.png", "innovation.png", "error_x.png"})
      EXPECT_TRUE(fs::exists(out + "/" + png)) << png;
  }
  for (const auto& x : {kind_nl, live_nl, kind_bq, live_bq}) EXPECT_FALSE(fs::exists(x)) << x;
}

TEST_F(EvalTest, CommandLineWritesReportAndFigures) {
  writeRun(file("run.lcmlog"), true);
  const std::string out = file("out");
  const int rc = shell(std::string(LCMLOC_EVAL_BIN) + " " + file("run.lcmlog") +
                     " --config " LCMLOC_TEST_DATA_DIR "/eval_straight.yaml --out " + out +
                     " > " + file("stdout.txt") + " 2>&1");
  ASSERT_EQ(rc, 0);
  std::ifstream f(out + "/report.json");
  ASSERT_TRUE(f.good());
  const auto j = nlohmann::json::parse(f);
  for (const char* name : {"dead_reckoning", "ukf", "ukf_gated"}) {
    const auto& m = j.at("filters").at(name);
    for (const char* key : {"rmse_m", "max_error_m", "final_error_m", "accepted", "rejected",
                            "faults_total", "faults_rejected", "valid_rejected"})
      EXPECT_TRUE(m.contains(key)) << name << "." << key;
    EXPECT_EQ(m.at("measurements").size(), 6u);
    EXPECT_EQ(m.at("faults_total"), 2);
  }
  EXPECT_EQ(j["filters"]["ukf_gated"]["faults_rejected"], 2);
  EXPECT_EQ(j["filters"]["ukf"]["faults_rejected"], 1);
  EXPECT_TRUE(j["filters"]["ukf"]["measurements"][0]["gate"].is_null());  // ungated: +inf
  EXPECT_NEAR(j["gate_threshold"].get<double>(), 9.21, 0.01);
  EXPECT_EQ(j["live"]["filter"], "ukf_gated");
  EXPECT_NEAR(j["live"]["rmse_m"].get<double>(), kLiveOffsetX, 1e-9);
  if (shell("command -v gnuplot > /dev/null") == 0) {
    for (const char* png : {"trajectories.png", "innovation.png", "error_x.png", "error_y.png"})
      EXPECT_GT(fs::file_size(out + "/" + png), 1000u) << png;
  }
}

TEST_F(EvalTest, CommandLineOnADamagedLogWritesTheReportAndExits3) {
  const auto w = writeRun(file("run.lcmlog"), true);
  const auto size = static_cast<int64_t>(fs::file_size(file("run.lcmlog")));
  fs::resize_file(file("run.lcmlog"), static_cast<uintmax_t>(size - 5));  // cut the last event
  const std::string out = file("out");
  const int rc = shell(std::string(LCMLOC_EVAL_BIN) + " " + file("run.lcmlog") + " --config " LCMLOC_TEST_DATA_DIR
                       "/eval_straight.yaml --no-plots --out " + out + " > " + file("stdout.txt") + " 2>&1");
  const std::string text = slurp(file("stdout.txt"));
  ASSERT_EQ(rc, 3) << text;
  EXPECT_NE(text.find("at byte " + std::to_string(w.starts.back())), std::string::npos) << text;
  std::ifstream f(out + "/report.json");
  ASSERT_TRUE(f.good());
  const auto j = nlohmann::json::parse(f);
  EXPECT_EQ(j["filters"]["ukf_gated"]["faults_rejected"], 2);  // the intact events are still scored
}

TEST_F(EvalTest, CommandLineFailsWhenNothingIsUsable) {
  EXPECT_NE(shell(std::string(LCMLOC_EVAL_BIN) + " " + file("missing.lcmlog") + " --no-plots --out " +
                file("out") + " > /dev/null 2>&1"), 0);
  fs::create_directories(file("adir"));
  EXPECT_EQ(shell(std::string(LCMLOC_EVAL_BIN) + " " + file("adir") + " --no-plots --out " + file("out") + " > " +
                  file("dir.txt") + " 2>&1"), 1);
  std::ifstream dir_out(file("dir.txt"));
  const std::string dir_text((std::istreambuf_iterator<char>(dir_out)), std::istreambuf_iterator<char>());
  EXPECT_NE(dir_text.find("is a directory"), std::string::npos) << dir_text;
  { std::ofstream empty(file("empty.lcmlog")); }
  EXPECT_EQ(shell(std::string(LCMLOC_EVAL_BIN) + " " + file("empty.lcmlog") + " --no-plots --out " +
                file("out") + " > /dev/null 2>&1"), 1);
  writeRun(file("run.lcmlog"), false);
  EXPECT_EQ(shell(std::string(LCMLOC_EVAL_BIN) + " " + file("run.lcmlog") +
                " --filters nope --no-plots --out " + file("out") + " > /dev/null 2>&1"), 2);
  EXPECT_EQ(shell(std::string(LCMLOC_EVAL_BIN) + " " + file("run.lcmlog") + " --config " +
                file("missing.yaml") + " --no-plots --out " + file("out") + " > /dev/null 2>&1"), 2);
  EXPECT_EQ(shell(std::string(LCMLOC_EVAL_BIN) + " " + file("run.lcmlog") +
                " --filters ukf_gated,tvekf --no-plots --out " + file("out") + " > /dev/null 2>&1"), 2);
  // A misspelt log level is refused (it used to switch logging off silently).
  EXPECT_NE(shell(std::string(LCMLOC_EVAL_BIN) + " " + file("run.lcmlog") + " --log-level loud --no-plots --out " +
                file("out") + " > " + file("level.txt") + " 2>&1"), 0);
  std::ifstream level(file("level.txt"));
  const std::string text((std::istreambuf_iterator<char>(level)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("--log-level: loud not in"), std::string::npos) << text;
}

}  // namespace
