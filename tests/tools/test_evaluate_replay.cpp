// lcmloc-evaluate --filters on a small hand-made log: a straight run north at 1 m/s with exact
// odometry, four genuine marker detections, one wrong-offset fault (instead of the genuine
// detection of the marker at y = 6) and one phantom marker between markers, plus live POSE/GATE
// messages. The log is replayed through the fusion daemon's code once per filter and scored; the
// log's estimates, truth, gate decisions and announced faults are read by readTrajectoryLog.
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
#include "lcmloc/eval/gnuplot.hpp"
#include "lcmloc/eval/report.hpp"
#include "lcmloc/logio/log_reader.hpp"
#include "lcmloc/eval/trajectory.hpp"
#include "lcmloc/fault_event_t.hpp"
#include "lcmloc/gate_decision_t.hpp"
#include "lcmloc/ground_truth_t.hpp"
#include "lcmloc/magruler_t.hpp"
#include "lcmloc/sim/world.hpp"
#include "lcmloc/odometry_t.hpp"
#include "lcmloc/pose_t.hpp"
#include "lcmloc/simconfig/sim_config.hpp"
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
  std::string live_filter = "ukf_gated";       ///< filter named by the live POSE and GATE messages
  int64_t truth_shift_us = 0;                  ///< ground truth's utimes moved by this
  std::function<void(LogWriter&)> first;       ///< writes events before the run
  std::function<bool(int)> odometry_lost;      ///< true: the odometry of this step is not recorded
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
    if (k > 0 && !(o.odometry_lost && o.odometry_lost(k))) {
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
        g.utime = t; g.seq = gate_seq++; g.filter = o.live_filter; g.sensor = d.channel;
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

/// Contents of a file ("" when missing).
std::string slurp(const std::string& path) {
  std::ifstream f(path);
  return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

/// Runs a command; returns its exit status.
int shell(const std::string& cmd) {
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

const std::string kConfig = LCMLOC_TEST_DATA_DIR "/eval_straight.yaml";
const std::string kAllFilters = "dead_reckoning,ukf,ukf_gated";

class EvaluateReplayTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("lcmloc_test_evaluate_replay_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    cfg_ = simconfig::loadSimSystemConfig(kConfig);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }

  /// lcmloc-evaluate on the log `log` with args; its output in file("stdout.txt").
  int evaluate(const std::string& log, const std::string& args) {
    return shell(std::string(LCMLOC_EVALUATE_BIN) + " " + log + " " + args + " > " + file("stdout.txt") + " 2>&1");
  }
  /// lcmloc-evaluate --config kConfig --filters `filters` into file("out"); report.json parsed.
  nlohmann::json replayAndScore(const std::string& log, const std::string& filters, int expected_rc = 0,
                                const std::string& more = "--no-plots") {
    const int rc = evaluate(log, "--config " + kConfig + " --filters " + filters + " " + more + " --overwrite -o " + file("out"));
    EXPECT_EQ(rc, expected_rc) << slurp(file("stdout.txt"));
    std::ifstream f(file("out") + "/report.json");
    if (!f.good()) return nullptr;
    return nlohmann::json::parse(f);
  }
  eval::TrajectoryLog read(const std::string& log) {
    eval::TrajectoryLogOptions o;
    return eval::readTrajectoryLog(log, o);
  }

  fs::path dir_;
  simconfig::SimSystemConfig cfg_;
};

/// The report's entry of `name` in the list `list` (by `key`); null when missing.
nlohmann::json entry(const nlohmann::json& list, const std::string& key, const std::string& name) {
  for (const auto& e : list)
    if (e[key] == name) return e;
  return nullptr;
}
nlohmann::json trackOf(const nlohmann::json& j, const std::string& channel) { return entry(j["tracks"], "channel", channel); }
nlohmann::json gateOf(const nlohmann::json& j, const std::string& filter) { return entry(j["gate"]["by_filter"], "filter", filter); }
nlohmann::json faultsOf(const nlohmann::json& j, const std::string& filter) { return entry(j["faults"]["by_filter"], "filter", filter); }

TEST_F(EvaluateReplayTest, MarkerMapOfTheTestWorld) {
  const auto map = sim::makeMarkerMap(sim::Path(cfg_.scenario.path), cfg_.scenario.markers);
  ASSERT_EQ(map.size(), 5u);
  EXPECT_NEAR(map[2].x, 0.0, 1e-9);
  EXPECT_NEAR(map[2].y, 6.0, 1e-9);
}

TEST_F(EvaluateReplayTest, ReadsEstimatesTruthGatesAndFaults) {
  const auto w = writeRun(file("run.lcmlog"), true);
  const auto log = read(file("run.lcmlog"));
  EXPECT_EQ(log.events_read, static_cast<int64_t>(w.starts.size()));
  EXPECT_FALSE(log.damaged);
  EXPECT_TRUE(log.issues.empty());
  EXPECT_EQ(log.truth.size(), static_cast<size_t>(kSteps + 1));
  EXPECT_EQ(log.channel_counts.at("ODOMETRY"), kSteps);
  EXPECT_EQ(log.tracks.front().poses.size(), static_cast<size_t>(kSteps / 10));
  EXPECT_EQ(log.gates.size(), 6u);
  EXPECT_EQ(log.gates[2].measurement_seq, 0);
  ASSERT_EQ(log.faults.size(), 2u);
  EXPECT_EQ(log.faults[0].channel, "MAGRULER_FAULT");
  EXPECT_EQ(log.faults[0].kind, "wrong_offset");
  EXPECT_EQ(log.faults[1].measurement_seq, 1);
}

TEST_F(EvaluateReplayTest, CountsAndMetricsOfEachFilter) {
  writeRun(file("run.lcmlog"), false);
  const auto j = replayAndScore(file("run.lcmlog"), kAllFilters);
  ASSERT_FALSE(j.is_null());
  EXPECT_EQ(j["faults"]["announced"], 2);
  const auto dr = faultsOf(j, "replay:dead_reckoning"), ukf = faultsOf(j, "replay:ukf");
  const auto gated = faultsOf(j, "replay:ukf_gated");
  ASSERT_FALSE(dr.is_null() || ukf.is_null() || gated.is_null()) << j["faults"].dump();
  EXPECT_EQ(dr["accepted"], 0);
  EXPECT_EQ(dr["rejected"], 0);
  EXPECT_EQ(dr["ignored"], 6);
  EXPECT_EQ(ukf["accepted"], 5);  // ungated: takes the wrong offset
  EXPECT_EQ(ukf["rejected"], 1);  // the phantom has no reachable marker
  EXPECT_EQ(ukf["faults_accepted"], 1);
  EXPECT_EQ(ukf["faults_rejected"], 1);
  EXPECT_EQ(ukf["valid_rejected"], 0);
  EXPECT_EQ(gated["accepted"], 4);
  EXPECT_EQ(gated["rejected"], 2);
  EXPECT_EQ(gated["faults_rejected"], 2);
  EXPECT_EQ(gated["faults_accepted"], 0);
  EXPECT_EQ(gated["valid_rejected"], 0);
  // The wrong offset is far outside the gate, the valid markers inside it.
  const auto g = entry(j["gate"]["by_filter_sensor"], "filter", "replay:ukf_gated");
  EXPECT_FALSE(g.is_null());
  const auto gr = gateOf(j, "replay:ukf_gated");
  EXPECT_EQ(gr["reasons"]["gate"], 1);
  EXPECT_EQ(gr["reasons"]["no_candidate"], 1);
  EXPECT_LT(gr["nis_accepted"]["mean"].get<double>(), 9.21);
  const auto t_dr = trackOf(j, "replay:dead_reckoning"), t_gated = trackOf(j, "replay:ukf_gated");
  const auto t_ukf = trackOf(j, "replay:ukf");
  ASSERT_FALSE(t_dr.is_null() || t_gated.is_null() || t_ukf.is_null());
  EXPECT_LT(t_dr["position_error_m"]["rmse"].get<double>(), 1e-9);  // exact odometry on a straight line
  EXPECT_GE(t_dr["scored"].get<int>(), kSteps);
  EXPECT_LT(t_gated["position_error_m"]["max"].get<double>(), 0.02);
  EXPECT_LT(t_gated["position_error_m"]["final"].get<double>(), 0.01);
  EXPECT_GT(t_ukf["position_error_m"]["max"].get<double>(), 0.05);
  EXPECT_GT(t_ukf["position_error_m"]["max"].get<double>(), 3 * t_gated["position_error_m"]["max"].get<double>());
}

// The replay is the daemon's: a config that turns the odometry-gap bridge off is obeyed, as live.
TEST_F(EvaluateReplayTest, TheEngineConfigurationIsTheDaemons) {
  RunOptions o;  // 0.5 s of odometry lost in transit (the seq numbers were used up)
  o.odometry_lost = [](int k) { return k > 100 && k <= 150; };
  writeRun(file("run.lcmlog"), false, o);
  auto finalError = [&](double max_gap) {
    const std::string yaml = file("gap_" + std::to_string(max_gap) + ".yaml");
    {
      std::ofstream f(yaml);
      f << slurp(kConfig) << "  max_odometry_gap: " << max_gap << "\n";  // under fusion:
      // (its map file beside it: a relative map_file is read from the config's directory)
      fs::copy_file(LCMLOC_TEST_DATA_DIR "/eval_straight_map.csv", file("eval_straight_map.csv"),
                    fs::copy_options::overwrite_existing);
    }
    EXPECT_EQ(evaluate(file("run.lcmlog"), "--config " + yaml + " --filters dead_reckoning --no-plots --overwrite -o " +
                                              file("out")), 0) << slurp(file("stdout.txt"));
    std::ifstream f(file("out") + "/report.json");
    const auto j = nlohmann::json::parse(f);
    return trackOf(j, "replay:dead_reckoning")["position_error_m"]["final"].get<double>();
  };
  const double bridged = finalError(0.1), off = finalError(0.0);
  EXPECT_NEAR(off - bridged, 0.5, 0.02) << "the 0.5 m of the gap at 1 m/s, bridged only when the config says so";
}

TEST_F(EvaluateReplayTest, ReportWithInvalidUtf8FromTheLogIsWrittenWithReplacements) {
  // A channel or filter name from a damaged log may hold any bytes.
  nlohmann::json j;
  j["filter"] = std::string("ukf\xC1\x80");
  ASSERT_NO_THROW(eval::writeJson(j, file("r.json")));
  std::ifstream in(file("r.json"));
  const auto back = nlohmann::json::parse(in);
  EXPECT_EQ(back["filter"].get<std::string>(), "ukf\xEF\xBF\xBD\xEF\xBF\xBD");  // U+FFFD twice
  EXPECT_THROW(eval::writeJson(j, file("no/such/dir/r.json")), std::runtime_error);
}

// lcmloc-eval converted odometry and ruler detections itself and refused the filters of other
// sensors; the daemon's intake takes every sensor, so every filter type is replayed.
TEST_F(EvaluateReplayTest, FiltersOfOtherSensorsAreReplayedNotRefused) {
  writeRun(file("run.lcmlog"), false);
  const auto j = replayAndScore(file("run.lcmlog"), "ukf_gated,odo_ins");
  ASSERT_FALSE(j.is_null());
  EXPECT_FALSE(trackOf(j, "replay:ukf_gated").is_null());
  EXPECT_EQ(slurp(file("stdout.txt")).find("needs"), std::string::npos) << slurp(file("stdout.txt"));
}

TEST_F(EvaluateReplayTest, LivePoseIsScoredAndComparedWithReplay) {
  writeRun(file("run.lcmlog"), true);
  const auto j = replayAndScore(file("run.lcmlog"), kAllFilters);
  ASSERT_FALSE(j.is_null());
  const auto live = trackOf(j, "POSE");
  ASSERT_FALSE(live.is_null());
  EXPECT_EQ(live["filters"], nlohmann::json::array({"ukf_gated"}));
  EXPECT_EQ(live["scored"], kSteps / 10);
  EXPECT_NEAR(live["position_error_m"]["rmse"].get<double>(), kLiveOffsetX, 1e-9);
  EXPECT_NEAR(live["position_error_m"]["final"].get<double>(), kLiveOffsetX, 1e-9);
  const auto f = faultsOf(j, "ukf_gated");  // the recorded GATE messages
  ASSERT_FALSE(f.is_null());
  EXPECT_EQ(f["accepted"], 4);
  EXPECT_EQ(f["faults_rejected"], 2);
  EXPECT_EQ(j["live_vs_replay"]["filter"], "ukf_gated");
  EXPECT_EQ(j["live_vs_replay"]["matched_poses"], kSteps / 10);
  EXPECT_NEAR(j["live_vs_replay"]["max_diff_m"].get<double>(), kLiveOffsetX, 0.02);
  EXPECT_NE(slurp(file("stdout.txt")).find("recorded ukf_gated against its replay: 100 estimates"), std::string::npos)
      << slurp(file("stdout.txt"));
}

TEST_F(EvaluateReplayTest, TruncatedLogReportsOffsetAndKeepsWhatWasRead) {
  const auto w = writeRun(file("run.lcmlog"), false);
  const auto size = static_cast<int64_t>(fs::file_size(file("run.lcmlog")));
  fs::resize_file(file("run.lcmlog"), static_cast<uintmax_t>(size - 5));  // cut the last event
  const auto log = read(file("run.lcmlog"));
  EXPECT_EQ(log.events_read, static_cast<int64_t>(w.starts.size()) - 1);
  EXPECT_TRUE(log.damaged);
  ASSERT_EQ(log.issues.size(), 1u);
  EXPECT_EQ(log.issues[0].byte_offset, w.starts.back());
  EXPECT_EQ(log.issues[0].event_index, static_cast<int64_t>(w.starts.size()) - 1);
  EXPECT_NE(log.issues[0].what.find("truncated"), std::string::npos) << log.issues[0].what;
  EXPECT_EQ(log.bytes_unreadable, size - 5 - w.starts.back());
  // What was read is still replayed and scored.
  const auto j = replayAndScore(file("run.lcmlog"), "ukf_gated", 3);
  EXPECT_EQ(faultsOf(j, "replay:ukf_gated")["faults_rejected"], 2);
}

TEST_F(EvaluateReplayTest, CorruptEventIsSkippedAndReadingResumes) {
  const auto w = writeRun(file("run.lcmlog"), false);
  const size_t bad = 500;  // an event in the middle: corrupt its channel length
  {
    std::fstream f(file("run.lcmlog"), std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(w.starts[bad] + 20);
    const char huge[4] = {0x00, 0x00, 0x7f, 0x00};
    f.write(huge, 4);
  }
  const auto log = read(file("run.lcmlog"));
  EXPECT_EQ(log.events_read, static_cast<int64_t>(w.starts.size()) - 1);
  EXPECT_TRUE(log.damaged);
  ASSERT_EQ(log.issues.size(), 1u);
  EXPECT_EQ(log.issues[0].byte_offset, w.starts[bad]);
  EXPECT_EQ(log.issues[0].event_index, static_cast<int64_t>(bad));
  EXPECT_EQ(log.bytes_unreadable, w.starts[bad + 1] - w.starts[bad]);
  EXPECT_NE(log.issues[0].what.find("resumed at byte " + std::to_string(w.starts[bad + 1])), std::string::npos)
      << log.issues[0].what;
  EXPECT_EQ(log.truth.size() + static_cast<size_t>(log.channel_counts.at("ODOMETRY")),
            static_cast<size_t>(2 * kSteps));  // exactly one truth or odometry event lost
}

TEST_F(EvaluateReplayTest, UndecodablePayloadIsReportedAndSkipped) {
  const auto w = writeRun(file("run.lcmlog"), true);
  size_t bad = 0;
  while (w.channels[bad] != "POSE") ++bad;
  {
    std::fstream f(file("run.lcmlog"), std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(w.starts[bad] + 28 + static_cast<int64_t>(w.channels[bad].size()));  // fingerprint
    f.write("\xde\xad\xbe\xef", 4);
  }
  const auto log = read(file("run.lcmlog"));
  EXPECT_EQ(log.events_read, static_cast<int64_t>(w.starts.size()));
  EXPECT_FALSE(log.damaged);
  ASSERT_EQ(log.issues.size(), 1u);
  EXPECT_EQ(log.issues[0].byte_offset, w.starts[bad]);
  EXPECT_NE(log.issues[0].what.find("undecodable POSE"), std::string::npos) << log.issues[0].what;
  EXPECT_EQ(log.tracks.front().poses.size(), static_cast<size_t>(kSteps / 10 - 1));
}

TEST_F(EvaluateReplayTest, MissingFileThrows) {
  EXPECT_THROW(read(file("nope.lcmlog")), std::runtime_error);
}

TEST_F(EvaluateReplayTest, ADirectoryIsNotALog) {
  // It used to read as one damaged stretch of 4096 bytes and an empty log.
  try {
    read(dir_.string());
    FAIL() << "a directory was read as a log";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("is a directory"), std::string::npos) << e.what();
  }
  EXPECT_THROW(logio::scanLog(dir_.string(), [](const logio::RawEvent&) {}), std::runtime_error);
}

TEST(InterpolateTruthReplay, InterpolatesInsideAcrossPiAndRefusesOutside) {
  const std::vector<eval::TruthPose> truth{{1000000, 0.0, 0.0, 3.0, true}, {1010000, 1.0, 2.0, -3.0, true}};
  auto mid = eval::interpolateTruth(truth, 1005000, 0);
  ASSERT_TRUE(mid.has_value());
  EXPECT_DOUBLE_EQ(mid->x, 0.5);
  EXPECT_DOUBLE_EQ(mid->y, 1.0);
  EXPECT_NEAR(std::abs(mid->heading), M_PI, 1e-12);  // midway between 3 and -3 across +-pi
  eval::TruthMiss why = eval::TruthMiss::kNone;
  EXPECT_FALSE(eval::interpolateTruth(truth, 1050000, 0, &why).has_value());  // no tolerance past the end
  EXPECT_EQ(why, eval::TruthMiss::kAfter);
  EXPECT_FALSE(eval::interpolateTruth({}, 0, 0, &why).has_value());
  EXPECT_EQ(why, eval::TruthMiss::kBefore);
}

TEST(InterpolateTruthReplay, ExtremeUtimesNeitherOverflowNorHideTheTruth) {
  constexpr int64_t kMin = std::numeric_limits<int64_t>::min(), kMax = std::numeric_limits<int64_t>::max();
  const std::vector<eval::TruthPose> low{{kMin, 0.0, 0.0, 0.0, true}, {0, 2.0, 0.0, 0.0, true}};
  auto at = eval::interpolateTruth(low, 0, 0);
  ASSERT_TRUE(at.has_value());
  EXPECT_DOUBLE_EQ(at->x, 2.0);
  at = eval::interpolateTruth(low, kMin / 2, 0);  // halfway between the two samples
  ASSERT_TRUE(at.has_value());
  EXPECT_DOUBLE_EQ(at->x, 1.0);
  const std::vector<eval::TruthPose> high{{0, 0.0, 0.0, 0.0, true}, {kMax, 2.0, 0.0, 0.0, true}};
  at = eval::interpolateTruth(high, 50000, 0);
  ASSERT_TRUE(at.has_value());
  EXPECT_NEAR(at->x, 0.0, 1e-9);
  EXPECT_FALSE(eval::interpolateTruth({{kMax, 0.0, 0.0, 0.0, true}}, kMin, 0).has_value());
  EXPECT_FALSE(eval::interpolateTruth({{kMin, 0.0, 0.0, 0.0, true}}, kMax, 0).has_value());
  EXPECT_TRUE(eval::interpolateTruth({{kMax, 0.0, 0.0, 0.0, true}}, kMax, 0).has_value());
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
  EXPECT_EQ(logio::uniqueStems({"POSE_A.B", "POSE_A_B", "POSE_A:B"}),
            (std::vector<std::string>{"POSE_A_B_2", "POSE_A_B", "POSE_A_B_3"}));
  EXPECT_EQ(logio::uniqueStems({"replay:ukf_gated", "ukf", "ukf"}),
            (std::vector<std::string>{"replay_ukf_gated", "ukf", "ukf_2"}));
  EXPECT_EQ(logio::uniqueStems({"../x'\n`y`", ""}), (std::vector<std::string>{"___x___y_", "_"}));
}

TEST_F(EvaluateReplayTest, MessagesWithAbsurdUtimesAreSkippedCountedAndReported) {
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
    lcmloc::fault_event_t f{};
    f.utime = logio::kUtimeLimit;  // the first utime refused
    f.kind = "phantom_marker";
    f.channel = "MAGRULER";
    f.measurement_seq = 99;
    w.add("FAULT_EVENTS", f, kT0);
  };
  writeRun(file("run.lcmlog"), true, o);
  const auto log = read(file("run.lcmlog"));
  EXPECT_EQ(log.bad_utime, 3);
  ASSERT_EQ(log.issues.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(log.issues[i].event_index, static_cast<int64_t>(i));
    EXPECT_NE(log.issues[i].what.find("skipped: |utime| >= 2^62 us"), std::string::npos) << log.issues[i].what;
  }
  EXPECT_EQ(log.truth.size(), static_cast<size_t>(kSteps + 1));
  EXPECT_EQ(log.faults.size(), 2u);
  EXPECT_EQ(log.tracks.front().poses.size(), static_cast<size_t>(kSteps / 10));

  const auto j = replayAndScore(file("run.lcmlog"), kAllFilters, 0, "");  // scored as without the absurd messages
  const std::string text = slurp(file("stdout.txt"));
  EXPECT_NE(text.find("warning: 3 message(s) skipped for |utime| >= 2^62 us"), std::string::npos) << text;
  EXPECT_EQ(j["log"].value("bad_utime", -1), 3);
  EXPECT_EQ(j["log"]["issues"].size(), 3u);
  EXPECT_LT(trackOf(j, "replay:dead_reckoning")["position_error_m"]["rmse"].get<double>(), 1e-9);
  EXPECT_EQ(faultsOf(j, "replay:ukf_gated")["faults_rejected"], 2);
  EXPECT_NEAR(trackOf(j, "POSE")["position_error_m"]["rmse"].get<double>(), kLiveOffsetX, 1e-9);
}

TEST_F(EvaluateReplayTest, NoEstimateInsideTheTruthIsAnErrorNotAZeroError) {
  RunOptions o;
  o.truth_shift_us = int64_t{1000} * 1000000;  // the truth 1000 s after the run: nothing to score
  writeRun(file("run.lcmlog"), true, o);
  const auto j = replayAndScore(file("run.lcmlog"), kAllFilters, 1);
  EXPECT_TRUE(j.is_null()) << "no report without a scored estimate";
  const std::string text = slurp(file("stdout.txt"));
  EXPECT_NE(text.find("no estimate lies inside the ground truth"), std::string::npos) << text;
}

TEST_F(EvaluateReplayTest, StringsFromTheLogRunNoCommandInGnuplot) {
  if (shell("command -v gnuplot > /dev/null") != 0) GTEST_SKIP() << "gnuplot not installed";
  // A live filter name (of POSE and GATE) that ends the script's string and starts a command: on a
  // new line, and in backquotes (command substitution outside quotes).
  const std::string live_nl = file("PWNED_live_nl"), live_bq = file("PWNED_live_bq");
  const std::vector<std::string> names{"y'\nsystem 'touch " + live_nl + "'\n'", "y'`touch " + live_bq + "`'"};
  for (size_t v = 0; v < names.size(); ++v) {
    RunOptions o;
    o.live_filter = names[v];
    writeRun(file("run.lcmlog"), true, o);
    const auto j = replayAndScore(file("run.lcmlog"), "ukf_gated", 0, "");
    // The script ran through without an error (every figure drawn) and ran nothing else.
    EXPECT_NE(slurp(file("stdout.txt")).find("figures: "), std::string::npos) << slurp(file("out") + "/gnuplot.log");
    for (const char* png : {"trajectory_POSE.png", "trajectory_replay_ukf_gated.png", "errors_replay_ukf_gated.png",
                            "gate_replay_ukf_gated.png"})
      EXPECT_TRUE(fs::exists(file("out") + "/" + png)) << png;
  }
  for (const auto& x : {live_nl, live_bq}) EXPECT_FALSE(fs::exists(x)) << x;
}

TEST_F(EvaluateReplayTest, CommandLineWritesReportAndFigures) {
  writeRun(file("run.lcmlog"), true);
  const auto j = replayAndScore(file("run.lcmlog"), kAllFilters, 0, "");
  ASSERT_FALSE(j.is_null());
  for (const char* name : {"replay:dead_reckoning", "replay:ukf", "replay:ukf_gated", "POSE"}) {
    const auto t = trackOf(j, name);
    ASSERT_FALSE(t.is_null()) << name;
    for (const char* key : {"position_error_m", "heading_error_rad", "nees_xytheta", "relative"})
      EXPECT_TRUE(t.contains(key)) << name << "." << key;
  }
  EXPECT_EQ(gateOf(j, "replay:ukf")["rejected"], 1);
  EXPECT_EQ(faultsOf(j, "replay:ukf")["faults_rejected"], 1);
  EXPECT_TRUE(trackOf(j, "replay:ukf_gated")["nees_xytheta"]["samples"].get<int>() > 0);
  if (shell("command -v gnuplot > /dev/null") == 0) {
    for (const char* png : {"trajectory_replay_ukf_gated.png", "errors_replay_ukf.png", "nees_replay_ukf_gated.png",
                            "trajectory_POSE.png", "gate_replay_ukf_gated.png", "gate_replay_ukf.png", "gate_ukf_gated.png"})
      EXPECT_GT(fs::file_size(file("out") + "/" + png), 1000u) << png;
  }
  const std::string text = slurp(file("stdout.txt"));
  EXPECT_NE(text.find("\nreplay:ukf_gated "), std::string::npos) << text;
  EXPECT_NE(text.find("2 fault(s) announced on FAULT_EVENTS"), std::string::npos) << text;
}

TEST_F(EvaluateReplayTest, CommandLineOnADamagedLogWritesTheReportAndExits3) {
  const auto w = writeRun(file("run.lcmlog"), true);
  const auto size = static_cast<int64_t>(fs::file_size(file("run.lcmlog")));
  fs::resize_file(file("run.lcmlog"), static_cast<uintmax_t>(size - 5));  // cut the last event
  const auto j = replayAndScore(file("run.lcmlog"), kAllFilters, 3);
  const std::string text = slurp(file("stdout.txt"));
  EXPECT_NE(text.find("at byte " + std::to_string(w.starts.back())), std::string::npos) << text;
  ASSERT_FALSE(j.is_null());
  EXPECT_EQ(faultsOf(j, "replay:ukf_gated")["faults_rejected"], 2);  // the intact events are still scored
}

TEST_F(EvaluateReplayTest, CommandLineFailsWhenNothingIsUsable) {
  const std::string opts = " --filters " + kAllFilters + " --no-plots --overwrite -o " + file("out");
  EXPECT_EQ(evaluate(file("missing.lcmlog"), opts), 2);  // a usage error, as in every tool
  fs::create_directories(file("adir"));
  EXPECT_EQ(evaluate(file("adir"), opts), 2);
  EXPECT_NE(slurp(file("stdout.txt")).find("is a directory"), std::string::npos) << slurp(file("stdout.txt"));
  { std::ofstream empty(file("empty.lcmlog")); }
  EXPECT_EQ(evaluate(file("empty.lcmlog"), opts), 3);  // nothing to evaluate: an empty file is damaged input
  writeRun(file("run.lcmlog"), false);
  EXPECT_EQ(evaluate(file("run.lcmlog"), "--filters nope --no-plots --overwrite -o " + file("out")), 2);
  EXPECT_EQ(evaluate(file("run.lcmlog"), "--filters ukf,ukf --no-plots --overwrite -o " + file("out")), 2);
  EXPECT_EQ(evaluate(file("run.lcmlog"), "--config " + file("missing.yaml") + opts), 2);
  // A misspelt log level is refused (it used to switch logging off silently).
  EXPECT_NE(evaluate(file("run.lcmlog"), "--log-level loud" + opts), 0);
  const std::string text = slurp(file("stdout.txt"));
  EXPECT_NE(text.find("--log-level: loud not in"), std::string::npos) << text;
}

// A log of sensor channels has no estimate of its own: the error says how to score it (what
// lcmloc-eval did with it), and without the warning that the recorded POSE is empty.
TEST_F(EvaluateReplayTest, ASensorLogWithoutFiltersPointsToThem) {
  writeRun(file("run.lcmlog"), false);
  EXPECT_EQ(evaluate(file("run.lcmlog"), "--no-plots --overwrite -o " + file("out")), 1);
  EXPECT_NE(slurp(file("stdout.txt")).find("replayed and scored with --filters"), std::string::npos)
      << slurp(file("stdout.txt"));
  replayAndScore(file("run.lcmlog"), "ukf_gated");
  EXPECT_EQ(slurp(file("stdout.txt")).find("no estimates on POSE"), std::string::npos) << slurp(file("stdout.txt"));
}

TEST_F(EvaluateReplayTest, TheReplaysLogsAreNotLeftBehind) {
  writeRun(file("run.lcmlog"), false);
  replayAndScore(file("run.lcmlog"), kAllFilters);
  for (const auto& e : fs::directory_iterator(file("out")))
    EXPECT_NE(e.path().extension(), ".lcmlog") << e.path();
}

}  // namespace
