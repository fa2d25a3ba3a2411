// Canonical ordering and the fusion engine: control commands, shadows, events, bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "lcmloc/core/engine.hpp"
#include "lcmloc/core/filter.hpp"
#include "lcmloc/core/odometry_batch.hpp"
#include "lcmloc/core/vehicle_model.hpp"
#include "lcmloc/core/reorder.hpp"
#include "lcmloc/core/time_guard.hpp"

using namespace lcmloc::core;

namespace {

constexpr double kL1 = 1.5;

MarkerMap straightMap(int n) {
  MarkerMap m;
  for (int i = 0; i < n; ++i) m.push_back(Marker{i, 0.0, 2.0 * (i + 1) + kL1});
  return m;
}

EngineInput odoIn(int64_t utime, int64_t seq, double ds) {
  OdometryInput o;
  o.utime = utime;
  o.delta_s = ds;
  o.has_steering = true;
  return EngineInput{"ODOMETRY", seq, utime, o};
}

EngineInput rulerIn(int64_t utime, int64_t seq, double dm) {
  RulerDetection d;
  d.utime = utime;
  d.seq = seq;
  d.lateral_offset = dm;
  return EngineInput{"MAGRULER", seq, utime, d};
}

EngineInput controlIn(int64_t utime, int64_t seq, ControlCommand c) {
  return EngineInput{"FUSION_CONTROL", seq, utime, std::move(c)};
}

/// Everything the engine emitted, in order.
struct Recorder {
  struct Event { std::string name, detail; int64_t utime; };
  std::vector<std::string> log;  // "state:<filter>", "decision:<filter>:<reason>", "event:<name>"
  std::vector<Event> events;
  std::vector<GateDecision> decisions;
  std::map<std::string, FilterState> last_state;
  EngineOutputs outputs() {
    EngineOutputs o;
    o.on_state = [this](const std::string& f, bool active, const FilterState& st) {
      log.push_back("state:" + f + (active ? "" : "(shadow)"));
      last_state[f] = st;
    };
    o.on_decision = [this](const std::string& f, bool active, const GateDecision& d) {
      log.push_back("decision:" + f + ":" + d.reason);
      if (active) decisions.push_back(d);
    };
    o.on_event = [this](const EngineEvent& e) {
      log.push_back(std::string("event:") + eventName(e.kind));
      events.push_back({eventName(e.kind), eventText(e), e.utime});
    };
    return o;
  }
  int count(const std::string& name) const {
    int n = 0;
    for (const auto& e : events) n += e.name == name;
    return n;
  }
};

EngineConfig engineConfig(const std::string& type = "ukf_gated") {
  EngineConfig c;
  c.filter.type = type;
  return c;
}

/// Drives `metres` north in 2 cm steps at 100 Hz from *utime, detecting markers (dm = 0) every
/// 2 m of travel, i.e. whenever the travelled distance is a multiple of 2 m.
void driveWithMarkers(FusionEngine& e, double metres, int64_t& utime, int64_t& seq,
                      double& travelled) {
  for (int k = 0; k < static_cast<int>(std::lround(metres / 0.02)); ++k) {
    utime += 10000;
    ASSERT_TRUE(e.push(odoIn(utime, ++seq, 0.02)));
    travelled += 0.02;
    if (std::abs(travelled / 2.0 - std::round(travelled / 2.0)) < 1e-6) {
      ASSERT_TRUE(e.push(rulerIn(utime, ++seq, 0.0)));
    }
  }
}

}  // namespace

TEST(ReorderBuffer, CanonicalOrderAndTooOld) {
  ReorderBuffer<char> buf(100);
  std::string out;
  auto sink = [&](const OrderKey&, char c) { out.push_back(c); };
  EXPECT_TRUE(buf.push({50, 2, 1}, 'A'));
  EXPECT_TRUE(buf.push({50, 1, 5}, 'B'));
  EXPECT_TRUE(buf.push({10, 2, 0}, 'C'));
  EXPECT_TRUE(buf.push({50, 1, 4}, 'D'));
  buf.releaseReady(sink);
  EXPECT_EQ(out, "");  // nothing older than newest - window yet
  EXPECT_TRUE(buf.push({200, 0, 0}, 'E'));
  buf.releaseReady(sink);
  EXPECT_EQ(out, "CDBA");  // utime, then rank, then seq
  EXPECT_FALSE(buf.push({40, 0, 0}, 'F'));   // older than released
  EXPECT_FALSE(buf.push({50, 2, 1}, 'G'));   // equal to the last released key
  EXPECT_TRUE(buf.push({120, 0, 0}, 'H'));   // late but not yet released past: still in order
  EXPECT_FALSE(buf.push({200, 0, 0}, 'I'));  // duplicate key
  buf.flush(sink);
  EXPECT_EQ(out, "CDBAHE");
  EXPECT_EQ(buf.size(), 0u);
}

namespace {
/// Counts the values alive: what a ReorderBuffer keeps (released or not) holds memory.
struct Counted {
  static inline int64_t alive = 0;
  Counted() { ++alive; }
  Counted(const Counted&) { ++alive; }
  Counted(Counted&&) noexcept { ++alive; }
  Counted& operator=(const Counted&) = default;
  Counted& operator=(Counted&&) noexcept = default;
  ~Counted() { --alive; }
};
}  // namespace

TEST(ReorderBuffer, StorageStaysBoundedWhenTwoSourcesRaceAtEqualUtimes) {
  // Odometry and IMU at 100 Hz from two processes and GPS at 1 Hz (the GNSS system): at each utime
  // either may come first, and the IMU first makes the odometry after it an out-of-order insert.
  // An insert out of order that found the storage full grew it (doubled) without dropping the
  // released items at its front, so the storage kept growing over a long run: the live daemon went
  // from 9 to 60 MB in 2100 s of message time. What the buffer keeps must stay about twice what
  // the window holds (here 12 items), whatever the order.
  Counted::alive = 0;
  {
    ReorderBuffer<Counted> buf(50000);  // 50 ms
    std::mt19937 rng(7);
    std::bernoulli_distribution imu_first(0.5);
    int64_t most = 0, released = 0;
    auto sink = [&](const OrderKey&, const Counted&) { ++released; };
    const OrderKey odo{0, 1, 0}, imu{0, 3, 0};
    for (int64_t k = 0; k < 1000000; ++k) {  // 10000 s of message time
      const int64_t t = 1000000 + 10000 * k;
      OrderKey a = imu_first(rng) ? imu : odo, b = a.rank == imu.rank ? odo : imu;
      a.utime = b.utime = t;
      a.seq = b.seq = k;
      ASSERT_TRUE(buf.push(a, Counted()));
      ASSERT_TRUE(buf.push(b, Counted()));
      if (k % 100 == 0) {
        ASSERT_TRUE(buf.push({t, 4, k}, Counted()));  // a 1 Hz GPS fix
      }
      buf.releaseReady(sink);
      most = std::max(most, Counted::alive);
    }
    EXPECT_EQ(released, 2 * 1000000 + 10000 - 12);  // the last 6 utimes are still in the window
    EXPECT_LE(most, 64) << "items kept (released or waiting) at most";
  }
  EXPECT_EQ(Counted::alive, 0);
}

TEST(Engine, CanonicalOrderAtEqualUtimeControlOdometryRuler) {
  Recorder rec;
  FusionEngine e(engineConfig(), straightMap(3), rec.outputs());
  const int64_t t = 1000000;
  ASSERT_TRUE(e.push(rulerIn(t, 1, 0.0)));
  ASSERT_TRUE(e.push(odoIn(t, 1, 0.02)));
  ASSERT_TRUE(e.push(controlIn(t, 1, SetPose{Pose(0, 0.48, M_PI / 2), Vec3(0.1, 0.1, 0.05)})));
  EXPECT_TRUE(rec.log.empty());  // held in the reorder window
  e.flush();
  const std::vector<std::string> expected{"event:ack", "state:ukf_gated",
                                          "decision:ukf_gated:no_candidate", "state:ukf_gated"};
  EXPECT_EQ(rec.log, expected);
  EXPECT_EQ(e.counters().processed, 3);
}

TEST(Engine, TooOldInputIsRejectedAndReported) {
  Recorder rec;
  EngineConfig cfg = engineConfig();
  cfg.reorder_window_us = 50000;
  FusionEngine e(cfg, straightMap(3), rec.outputs());
  ASSERT_TRUE(e.push(odoIn(1000000, 1, 0.02)));
  ASSERT_TRUE(e.push(odoIn(1100000, 2, 0.02)));     // releases 1.0 s
  EXPECT_TRUE(e.push(odoIn(1060000, 3, 0.02)));     // late, but within the window: kept
  EXPECT_FALSE(e.push(odoIn(990000, 4, 0.02)));     // older than what was processed
  EXPECT_EQ(rec.count("too_old"), 1);
  EXPECT_EQ(rec.events.back().utime, 990000);
  EXPECT_EQ(e.counters().too_old, 1);
  e.flush();
  EXPECT_EQ(e.counters().processed, 3);
}

TEST(Engine, SwitchFilterKeepsStateContinuity) {
  Recorder rec;
  EngineConfig cfg = engineConfig("ukf_gated");
  cfg.reorder_window_us = 0;
  FusionEngine e(cfg, straightMap(10), rec.outputs());
  int64_t t = 1000000, seq = 0;
  double s = 0;
  driveWithMarkers(e, 5.0, t, seq, s);
  e.flush();
  ASSERT_EQ(rec.decisions.size(), 2u);
  EXPECT_TRUE(rec.decisions[1].accepted);
  const FilterState before = e.activeState();
  SwitchFilter sw;
  sw.config = cfg.filter;
  sw.config.type = "ukf_calib";
  ASSERT_TRUE(e.push(controlIn(t + 1, ++seq, sw)));
  e.flush();
  EXPECT_EQ(e.activeFilter(), "ukf_calib");
  ASSERT_EQ(rec.count("ack"), 1);
  const FilterState after = e.activeState();
  ASSERT_EQ(after.x.size(), 5);
  EXPECT_EQ(Eigen::VectorXd(after.x.head(3)), before.x);
  EXPECT_EQ(Eigen::MatrixXd(after.P.topLeftCorner(3, 3)), before.P);
  // The new filter runs on: its states are published as the active ones.
  rec.log.clear();
  t += 10;
  driveWithMarkers(e, 1.0, t, seq, s);
  e.flush();
  ASSERT_FALSE(rec.log.empty());
  for (const auto& line : rec.log) EXPECT_EQ(line.find("ukf_gated"), std::string::npos) << line;
  EXPECT_EQ(rec.log.back(), "state:ukf_calib");
  EXPECT_TRUE(rec.decisions.back().accepted);
}

TEST(Engine, CommandsWaitForTheSensorsTimeAndNeverCarryItAhead) {
  // Several tools sending at once each time their command one reorder window after the newest
  // answer they saw: the commands' times climb ahead of the sensors. They used to move the reorder
  // window's time with them, so the odometry after them came "too old" and was lost.
  Recorder rec;
  EngineConfig cfg = engineConfig("ukf_gated");  // reorder window 50 ms, max_time_jump 1 s
  FusionEngine e(cfg, straightMap(10), rec.outputs());
  int64_t t = 1000000, seq = 0;
  double s = 0;
  driveWithMarkers(e, 2.0, t, seq, s);  // t = 2 s
  const int64_t sent_at = t;
  for (int k = 1; k <= 5; ++k) {
    SwitchFilter sw;
    sw.config = cfg.filter;
    sw.config.type = k % 2 ? "ukf" : "ukf_gated";
    ASSERT_TRUE(e.push(controlIn(sent_at + k * cfg.reorder_window_us, 100 + k, sw)));
  }
  driveWithMarkers(e, 1.0, t, seq, s);  // 0.5 s more odometry, all of it older than the last command
  EXPECT_EQ(e.counters().too_old, 0);
  EXPECT_EQ(rec.count("too_old"), 0);
  ASSERT_EQ(rec.count("ack"), 5) << "each applied once the odometry passed it by the window";
  int k = 0;
  for (const auto& ev : rec.events)
    if (ev.name == "ack") {
      ++k;
      EXPECT_EQ(ev.utime, sent_at + k * cfg.reorder_window_us);
      EXPECT_EQ(ev.detail.rfind("FUSION_CONTROL seq " + std::to_string(100 + k) + ": switched ", 0), 0u) << ev.detail;
    }
  EXPECT_EQ(e.activeFilter(), "ukf");
  // A command alone never releases anything: it waits for the sensors' time, or the end.
  SwitchFilter back;
  back.config = cfg.filter;
  ASSERT_TRUE(e.push(controlIn(t + 20000, 200, back)));
  ASSERT_TRUE(e.push(controlIn(t + 900000, 201, ResetFilter{})));
  EXPECT_EQ(rec.count("ack"), 5);
  // One beyond fusion.max_time_jump would wait for a time that may never come: refused at once.
  EXPECT_FALSE(e.push(controlIn(t + 1500000, 202, ResetFilter{})));
  ASSERT_EQ(rec.events.back().name, "too_new");
  EXPECT_NE(rec.events.back().detail.find("FUSION_CONTROL seq 202 utime"), std::string::npos) << rec.events.back().detail;
  EXPECT_EQ(e.counters().too_new, 1);
  e.flush();
  EXPECT_EQ(rec.count("ack"), 7);
  EXPECT_EQ(e.activeFilter(), "ukf_gated");
}

TEST(Engine, UnknownFilterIsRefusedAndTheRunningFilterContinues) {
  Recorder rec;
  EngineConfig cfg = engineConfig("ukf_gated");
  cfg.reorder_window_us = 0;
  FusionEngine e(cfg, straightMap(10), rec.outputs());
  int64_t t = 1000000, seq = 0;
  double s = 0;
  driveWithMarkers(e, 1.0, t, seq, s);
  e.flush();
  const FilterState before = e.activeState();
  SwitchFilter sw;
  sw.config.type = "kalman_magic";
  ASSERT_TRUE(e.push(controlIn(t + 1, ++seq, sw)));
  SwitchFilter bad;
  bad.config.type = "ukf";
  bad.config.pv_diag = Vec2(-1, 1);  // invalid parameter: refused too
  ASSERT_TRUE(e.push(controlIn(t + 2, ++seq, bad)));
  e.flush();
  EXPECT_EQ(rec.count("refused"), 2);
  EXPECT_NE(rec.events[0].detail.find("kalman_magic"), std::string::npos);
  EXPECT_NE(rec.events[1].detail.find("pv_diag"), std::string::npos);
  EXPECT_EQ(rec.count("ack"), 0);
  EXPECT_EQ(e.activeFilter(), "ukf_gated");
  EXPECT_EQ(e.activeState().x, before.x);
  t += 10;
  driveWithMarkers(e, 1.0, t, seq, s);  // reaches the first marker at 2 m
  e.flush();
  EXPECT_GT(e.activeState().x[1], before.x[1] + 0.9);
  ASSERT_FALSE(rec.decisions.empty());
  EXPECT_TRUE(rec.decisions.back().accepted);
}

TEST(Engine, SetPoseAndResetApplyToActiveAndShadowFilters) {
  Recorder rec;
  EngineConfig cfg = engineConfig("ukf_calib");
  cfg.shadow = {"dead_reckoning", "ukf"};
  cfg.reorder_window_us = 0;
  FusionEngine e(cfg, straightMap(10), rec.outputs());
  int64_t t = 1000000, seq = 0;
  double s = 0;
  driveWithMarkers(e, 1.0, t, seq, s);
  e.flush();
  // One state per filter per odometry input.
  EXPECT_EQ(rec.log[0], "state:ukf_calib");
  EXPECT_EQ(rec.log[1], "state:dead_reckoning(shadow)");
  EXPECT_EQ(rec.log[2], "state:ukf(shadow)");
  ASSERT_TRUE(e.push(controlIn(t + 1, ++seq, SetPose{Pose(5, 6, 0.3), Vec3(0.1, 0.2, 0.05)})));
  e.flush();
  EXPECT_EQ(rec.count("ack"), 1);
  FilterState st = e.activeState();
  EXPECT_EQ(Eigen::VectorXd(st.x.head(3)), Eigen::Vector3d(5, 6, 0.3));
  EXPECT_NEAR(st.P(0, 0), 0.01, 1e-15);
  EXPECT_NEAR(st.P(1, 1), 0.04, 1e-15);
  EXPECT_NEAR(st.P(2, 2), 0.0025, 1e-15);
  EXPECT_EQ(st.P(0, 1), 0.0);
  EXPECT_EQ(st.P(0, 3), 0.0);
  rec.log.clear();
  ASSERT_TRUE(e.push(odoIn(t + 2, ++seq, 0.0)));
  e.flush();
  ASSERT_EQ(rec.log.size(), 3u);  // the shadows were set too
  for (const auto& name : {"dead_reckoning", "ukf"}) {
    EXPECT_EQ(Eigen::VectorXd(rec.last_state[name].x.head(3)), Eigen::Vector3d(5, 6, 0.3)) << name;
    EXPECT_NEAR(rec.last_state[name].P(1, 1), 0.04, 1e-15) << name;
  }
  ASSERT_TRUE(e.push(controlIn(t + 3, ++seq, SetPose{Pose(0, 0, 0), Vec3(0, 1, 1)})));
  e.flush();
  EXPECT_EQ(rec.count("refused"), 1);  // zero stddev
  ASSERT_TRUE(e.push(controlIn(t + 4, ++seq, ResetFilter{})));
  e.flush();
  st = e.activeState();
  EXPECT_EQ(Eigen::VectorXd(st.x.head(3)), cfg.filter.initial_pose);
  EXPECT_EQ(st.x[3], 0.0);
  EXPECT_EQ(e.activeFilter(), "ukf_calib");
}

TEST(Engine, SetPoseWithAbsurdNumbersIsRefusedAndNoFilterMoves) {
  // Each of these used to be acknowledged: the first made every later state infinite, the next
  // two were not applied (the variance squared to infinity or to 0) yet answered "ack".
  Recorder rec;
  EngineConfig cfg = engineConfig("ukf_gated");
  cfg.shadow = {"dead_reckoning"};
  cfg.reorder_window_us = 0;
  FusionEngine e(cfg, straightMap(10), rec.outputs());
  int64_t t = 1000000, seq = 0;
  double s = 0;
  driveWithMarkers(e, 1.0, t, seq, s);
  e.flush();
  const Eigen::VectorXd before = e.activeState().x;
  const std::vector<std::pair<SetPose, std::string>> cases{
      {SetPose{Pose(1e308, -1e308, 0.0), Vec3(1, 1, 1)}, "position (1e+308, -1e+308) m is beyond"},
      {SetPose{Pose(1, 2, 0.1), Vec3(1e200, 1e200, 1e200)}, "not finite"},
      {SetPose{Pose(1, 2, 0.1), Vec3(1e-200, 1e-200, 1e-200)}, "variance of x is not > 0"},
      {SetPose{Pose(1, 2, 0.1), Vec3(-0.1, 0.1, 0.1)}, "stddev must be > 0"},
      {SetPose{Pose(1, 2, 0.1), Vec3(2e7, 1, 1)}, "a variance (4e+14) is beyond"},
  };
  for (const auto& [cmd, why] : cases) {
    rec.events.clear();
    ASSERT_TRUE(e.push(controlIn(++t, ++seq, cmd)));
    e.flush();
    ASSERT_EQ(rec.count("refused"), 1) << why;
    EXPECT_EQ(rec.count("ack"), 0) << why;
    EXPECT_NE(rec.events.back().detail.find(why), std::string::npos) << rec.events.back().detail;
    EXPECT_EQ(e.activeState().x, before) << why;
  }
  rec.events.clear();
  ASSERT_TRUE(e.push(controlIn(++t, ++seq, SetPose{Pose(1, 2, 0.1), Vec3(0.1, 0.1, 0.1)})));
  e.flush();
  EXPECT_EQ(rec.count("ack"), 1);
  EXPECT_EQ(Eigen::VectorXd(e.activeState().x.head(3)), Eigen::Vector3d(1, 2, 0.1));
}

TEST(Engine, AFilterWhoseStateRunsAwayStartsOverInsteadOfPublishingIt) {
  Recorder rec;
  EngineConfig cfg = engineConfig("dead_reckoning");
  cfg.reorder_window_us = 0;
  FusionEngine e(cfg, straightMap(10), rec.outputs());
  int64_t t = 1000000, seq = 0;
  // Finite (so taken), but its square through the heading's variance is not.
  ASSERT_TRUE(e.push(odoIn(t, ++seq, 0.02)));
  ASSERT_TRUE(e.push(odoIn(t += 10000, ++seq, 1e300)));
  e.flush();
  EXPECT_EQ(rec.count("restarted"), 1);
  EXPECT_NE(rec.events.back().detail.find("dead_reckoning: its state became non-finite"), std::string::npos)
      << rec.events.back().detail;
  const FilterState& out = rec.last_state.at("dead_reckoning");
  EXPECT_TRUE(out.x.allFinite());
  EXPECT_TRUE(out.P.allFinite());
  EXPECT_EQ(Eigen::VectorXd(out.x.head(3)), cfg.filter.initial_pose);
}

TEST(UnusableState, PositionsAndVariancesBeyondAnyLocalFrameAreRefused) {
  FilterState s;
  s.x = Eigen::Vector3d(kMaxAbsPosition, -kMaxAbsPosition, 0.0);
  s.P = Eigen::Matrix3d::Identity() * kMaxVariance;
  EXPECT_EQ(unusableState(s), "");
  s.x(1) = -1.0001 * kMaxAbsPosition;
  EXPECT_NE(unusableState(s).find("is beyond"), std::string::npos);
  s.x(1) = 0.0;
  s.P(2, 2) = 1.0001 * kMaxVariance;
  EXPECT_NE(unusableState(s).find("a variance"), std::string::npos);
}

TEST(Engine, NonFiniteInputsAreRejectedWithoutCorruptingTheState) {
  Recorder rec;
  EngineConfig cfg = engineConfig("ukf_gated");
  cfg.reorder_window_us = 0;
  FusionEngine e(cfg, straightMap(10), rec.outputs());
  int64_t t = 1000000, seq = 0;
  double s = 0;
  driveWithMarkers(e, 2.0, t, seq, s);
  e.flush();
  const FilterState before = e.activeState();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  ASSERT_TRUE(e.push(odoIn(t + 1, ++seq, nan)));
  ASSERT_TRUE(e.push(rulerIn(t + 2, ++seq, std::numeric_limits<double>::infinity())));
  e.flush();
  EXPECT_EQ(rec.count("bad_input"), 1);
  EXPECT_EQ(rec.decisions.back().reason, "bad_input");
  EXPECT_FALSE(rec.decisions.back().accepted);
  EXPECT_EQ(e.activeState().x, before.x);
  EXPECT_EQ(e.activeState().P, before.P);
  // And it keeps going.
  t += 10;
  driveWithMarkers(e, 2.0, t, seq, s);
  e.flush();
  EXPECT_TRUE(rec.decisions.back().accepted);
  EXPECT_NEAR(e.activeState().x[1], 4.0, 0.02);
}

TEST(Engine, LockoutAndRecoveryEvents) {
  Recorder rec;
  EngineConfig cfg = engineConfig("ukf_gated");
  cfg.reorder_window_us = 0;
  FusionEngine e(cfg, straightMap(10), rec.outputs());
  int64_t t = 1000000, seq = 0;
  double s = 0;
  driveWithMarkers(e, 6.0, t, seq, s);  // three good markers
  for (int i = 0; i < cfg.filter.lockout_rejections; ++i)
    ASSERT_TRUE(e.push(rulerIn(t += 10, ++seq, 0.45)));
  e.flush();
  EXPECT_EQ(rec.count("lockout"), 1);
  EXPECT_EQ(e.activeState().status, FilterStatus::Lockout);
  driveWithMarkers(e, 2.0, t, seq, s);
  e.flush();
  EXPECT_EQ(rec.count("recovered"), 1);
  EXPECT_EQ(e.activeState().status, FilterStatus::Ok);
  const auto c = e.counters();
  EXPECT_EQ(c.rejected, cfg.filter.lockout_rejections);
  EXPECT_EQ(c.accepted, 4);
}

TEST(OdometryBatch, ComposedIncrementMovesAPoseAsTheStepsOneByOne) {
  const Pose start(3.0, -2.0, 3.1);  // near +pi: the heading wraps on the way
  Pose seq = start;
  OdometryBatch b;
  for (int k = 0; k < 50; ++k) {
    const double ds = 0.02 + 0.001 * (k % 7), dth = 0.01 * std::sin(0.3 * k);
    seq = propagatePose(seq, ds, dth);
    b.add(ds, dth, 1000 * k, Vec3::Zero());
  }
  const Pose composed = b.apply(start);
  EXPECT_NEAR(composed.x(), seq.x(), 1e-12);
  EXPECT_NEAR(composed.y(), seq.y(), 1e-12);
  EXPECT_NEAR(wrapAngle(composed.z() - seq.z()), 0.0, 1e-12);
  EXPECT_EQ(b.steps, 50);
  EXPECT_EQ(b.utime, 49000);
  for (double a = -0.26; a <= 0.26; a += 0.0007) {  // the polynomial range and both sides of it
    double s, c;
    sinCosSmall(a, s, c);
    EXPECT_NEAR(s, std::sin(a), 1.2e-16) << a;
    EXPECT_NEAR(c, std::cos(a), 2.3e-16) << a;
  }
  // Near a heading by angle addition: within rounding of libm, exactly libm's at the heading.
  for (double theta : {-3.1, -1.0, 0.0, 0.5, 3.1}) {
    const SinCosNear h(theta);
    for (double d = -0.3; d <= 0.3; d += 0.0011) {
      double s, c;
      h.sinCos(theta + d, s, c);
      EXPECT_NEAR(s, std::sin(theta + d), 5e-16) << theta << " " << d;
      EXPECT_NEAR(c, std::cos(theta + d), 5e-16) << theta << " " << d;
    }
    double s, c;
    h.sinCos(theta, s, c);
    EXPECT_EQ(s, std::sin(theta));
    EXPECT_EQ(c, std::cos(theta));
  }
}

TEST(Engine, OutputEveryPublishesEveryNthOdometryAndBeforeMeasurementsAppliesTheBatch) {
  auto run = [](int output_every, Recorder& rec) {
    EngineConfig c = engineConfig("ukf_gated");
    c.shadow = {"dead_reckoning"};
    c.output_every = output_every;
    c.reorder_window_us = 0;
    FusionEngine e(c, straightMap(3), rec.outputs());
    int64_t seq = 0;
    for (int k = 1; k <= 25; ++k) {
      OdometryInput o;
      o.utime = 10000 * k;
      o.delta_s = 0.1;
      o.has_steering = true;
      o.steering = 0.002;
      ASSERT_TRUE(e.push(EngineInput{"ODOMETRY", ++seq, o.utime, o}));
      if (k == 13) {
        ASSERT_TRUE(e.push(rulerIn(o.utime, ++seq, 0.0)));
      }
    }
    e.flush();
  };
  Recorder per, batched, again;
  run(1, per);
  run(10, batched);
  run(10, again);
  ASSERT_EQ(per.decisions.size(), 1u);
  // States: after odometry 10, after the measurement at 13, after odometry 20, and the final
  // state at flush (odometry 25) for each filter, in the per-message order (active first).
  const std::vector<std::string> expected = {
      "state:ukf_gated", "state:dead_reckoning(shadow)",  // odometry 10
      "decision:ukf_gated:" + per.decisions[0].reason, "state:ukf_gated",
      "decision:dead_reckoning:dead_reckoning", "state:dead_reckoning(shadow)",  // measurement at 13
      "state:ukf_gated", "state:dead_reckoning(shadow)",  // odometry 20
      "state:ukf_gated", "state:dead_reckoning(shadow)"}; // flush: odometry 25
  EXPECT_EQ(batched.log, expected);
  EXPECT_EQ(batched.log, again.log);
  ASSERT_EQ(batched.decisions.size(), 1u);
  EXPECT_EQ(batched.decisions[0].reason, per.decisions[0].reason);
  EXPECT_EQ(batched.decisions[0].utime, 130000);
  if (per.decisions[0].innovation.size() == 2) {  // the batch was applied up to the measurement
    ASSERT_EQ(batched.decisions[0].innovation.size(), 2);
    // (within what one sigma-point draw per batch instead of per step changes at this 0.1 m,
    // 0.1 rad prior uncertainty: measured 1.0e-3)
    EXPECT_LT((per.decisions[0].innovation - batched.decisions[0].innovation).cwiseAbs().maxCoeff(), 3e-3);
  }
  for (const char* f : {"ukf_gated", "dead_reckoning"}) {
    const FilterState& a = per.last_state.at(f);
    const FilterState& b = batched.last_state.at(f);
    EXPECT_EQ(a.utime, 250000) << f;
    EXPECT_EQ(b.utime, 250000) << f;
    // Dead reckoning: exact up to rounding (mean and linear covariance propagation). UKF: measured
    // 1.7e-3 (state), 7e-5 (covariance).
    const bool dr = f == std::string("dead_reckoning");
    EXPECT_NEAR((a.x - b.x).cwiseAbs().maxCoeff(), 0.0, dr ? 1e-12 : 5e-3) << f;
    EXPECT_NEAR((a.P - b.P).cwiseAbs().maxCoeff(), 0.0, dr ? 1e-12 : 3e-4) << f;
    EXPECT_EQ(b.x, again.last_state.at(f).x) << f;
    EXPECT_EQ(b.P, again.last_state.at(f).P) << f;
  }
}

TEST(Engine, OutputEveryPublishesTheLastStateAtFlushAfterAnInputNoFilterUses) {
  // An IMU sample that neither ukf_gated nor its shadow uses comes after odometry whose state was
  // not published yet: the flush must still publish the state after the last odometry.
  Recorder rec;
  EngineConfig c = engineConfig("ukf_gated");
  c.output_every = 10;
  c.reorder_window_us = 0;
  FusionEngine e(c, straightMap(3), rec.outputs());
  int64_t seq = 0;
  for (int k = 1; k <= 15; ++k) {
    OdometryInput o;
    o.utime = 10000 * k;
    o.delta_s = 0.1;
    ASSERT_TRUE(e.push(EngineInput{"ODOMETRY", ++seq, o.utime, o}));
  }
  ImuInput imu;
  imu.utime = 155000;
  ASSERT_TRUE(e.push(EngineInput{"IMU", ++seq, imu.utime, imu}));
  e.flush();
  const std::vector<std::string> expected = {"state:ukf_gated", "state:ukf_gated"};  // 10, flush
  EXPECT_EQ(rec.log, expected);
  EXPECT_EQ(rec.last_state.at("ukf_gated").utime, 150000);
}

namespace {

/// 100 Hz odometry (1 cm each) from utime t0; `corrupt` replaces input k's utime.
std::vector<EngineInput> odometryRun(int n, int64_t t0, std::map<int, int64_t> corrupt = {}) {
  std::vector<EngineInput> v;
  for (int k = 0; k < n; ++k) {
    auto in = odoIn(t0 + 10000 * k, k, 0.01);
    if (corrupt.count(k)) in.utime = std::get<OdometryInput>(in.payload).utime = corrupt[k];
    v.push_back(in);
  }
  return v;
}

}  // namespace

TEST(Engine, AnInputFarInTheFutureIsDroppedInsteadOfMakingEveryLaterInputTooOld) {
  const int64_t t0 = 1000000, bad = int64_t{1} << 60;  // a corrupt utime (flipped high bit)
  Recorder clean, guarded, unguarded;
  {
    FusionEngine e(engineConfig("dead_reckoning"), {}, clean.outputs());
    for (auto& in : odometryRun(200, t0)) e.push(std::move(in));
    e.flush();
  }
  // Two corrupt inputs (the second releases the first from the reorder window).
  const std::map<int, int64_t> corrupt{{100, bad}, {101, bad + 1000000}};
  FusionEngine g(engineConfig("dead_reckoning"), {}, guarded.outputs());
  for (auto& in : odometryRun(200, t0, corrupt)) g.push(std::move(in));
  g.flush();
  EXPECT_EQ(g.counters().too_new, 2);
  EXPECT_EQ(g.counters().too_old, 0);
  EXPECT_EQ(g.counters().processed, 198);
  ASSERT_EQ(guarded.count("too_new"), 2);
  EXPECT_NE(guarded.events[0].detail.find("ODOMETRY seq 100 utime " + std::to_string(bad)), std::string::npos)
      << guarded.events[0].detail;
  // Two increments of 1 cm less than the clean run, and nothing else lost.
  const auto& a = clean.last_state.at("dead_reckoning");
  const auto& b = guarded.last_state.at("dead_reckoning");
  EXPECT_EQ(b.utime, a.utime);
  EXPECT_NEAR(std::hypot(a.x[0] - b.x[0], a.x[1] - b.x[1]), 0.02, 1e-9);

  EngineConfig off = engineConfig("dead_reckoning");
  off.max_time_jump_us = 0;  // without the guard every later input is too old
  FusionEngine u(off, {}, unguarded.outputs());
  for (auto& in : odometryRun(200, t0, corrupt)) u.push(std::move(in));
  EXPECT_EQ(u.counters().too_old, 98);
}

TEST(Engine, ANewTimeBaseIsTakenAfterInputsSpanningTheConfirmSpanWithNothingLost) {
  const int64_t t0 = 1000000, later = t0 + 3600 * int64_t{1000000};  // e.g. a restarted source
  Recorder r;
  EngineConfig ec = engineConfig("dead_reckoning");
  ec.odometry_gap.max_gap_us = 0;  // (the time base only: the restarted source's gap is not bridged)
  FusionEngine e(ec, {}, r.outputs());
  for (auto& in : odometryRun(50, t0)) e.push(std::move(in));
  // The inputs of the new base are held until they span kTimeJumpConfirmSpanUs (0.2 s: the
  // 21st at 100 Hz), then taken with the rest.
  auto after = odometryRun(50, later);
  const std::size_t confirming = kTimeJumpConfirmSpanUs / 10000;
  for (std::size_t k = 0; k < confirming; ++k) e.push(std::move(after[k]));
  EXPECT_EQ(r.count("time_jump"), 0);
  EXPECT_LE(e.counters().processed, 50);  // none of the new base yet
  e.push(std::move(after[confirming]));
  EXPECT_EQ(r.count("time_jump"), 1);
  EXPECT_NE(r.events.back().detail.find("confirmed by the inputs of 200 ms in a row"), std::string::npos)
      << r.events.back().detail;
  for (std::size_t k = confirming + 1; k < after.size(); ++k) e.push(std::move(after[k]));
  e.flush();
  EXPECT_EQ(e.counters().processed, 100);
  EXPECT_EQ(e.counters().too_new + e.counters().too_old, 0);
  EXPECT_EQ(r.last_state.at("dead_reckoning").utime, later + 49 * 10000);
  const auto& x = r.last_state.at("dead_reckoning").x;
  EXPECT_NEAR(std::hypot(x[0], x[1]), 1.0, 1e-9);  // 100 increments of 1 cm from the origin
  // Suspects that stay alone are dropped at the end too.
  Recorder r2;
  FusionEngine e2(engineConfig("dead_reckoning"), {}, r2.outputs());
  for (auto& in : odometryRun(10, t0)) e2.push(std::move(in));
  e2.push(odoIn(later, 10, 0.01));
  e2.flush();
  EXPECT_EQ(e2.counters().too_new, 1);
  EXPECT_EQ(e2.counters().processed, 10);
}

TEST(Engine, AFastChannelWithAFaultyClockDoesNotTakeTheTimeBaseOver) {
  // A channel four times as fast as odometry, its clock an hour ahead for a second: three of its
  // inputs in a row came before the next odometry and took the time base over; the good odometry
  // was then refused, and the filters restarted when the clock came back.
  const int64_t t0 = 1000000, ahead = 3600 * int64_t{1000000};
  Recorder r;
  FusionEngine e(engineConfig("dead_reckoning"), {}, r.outputs());
  int64_t seq = 0;
  for (int k = 0; k < 300; ++k) {
    const int64_t t = t0 + 10000 * k;
    e.push(odoIn(t, k, 0.01));
    for (int j = 0; j < 4; ++j) {
      const bool faulty = k >= 100 && k < 200;
      e.push(rulerIn(t + 2500 * j + (faulty ? ahead : 0), seq++, 0.0));
    }
  }
  e.flush();
  EXPECT_EQ(r.count("time_jump"), 0);
  EXPECT_EQ(e.counters().too_new, 400);  // the faulty readings, dropped as outliers
  EXPECT_EQ(e.counters().too_old, 0);
  const auto& x = r.last_state.at("dead_reckoning").x;
  EXPECT_NEAR(std::hypot(x[0], x[1]), 3.0, 1e-9);  // every odometry increment taken
}

namespace {

/// Odometry at 100 Hz (1 cm each, slight steering) and a ruler reading every 0.5 s, from t0.
std::vector<EngineInput> drive(int64_t t0, int n) {
  std::vector<EngineInput> v;
  for (int k = 0; k < n; ++k) {
    auto in = odoIn(t0 + 10000 * k, k, 0.01);
    std::get<OdometryInput>(in.payload).steering = 0.02;
    v.push_back(in);
    if (k % 50 == 25) v.push_back(rulerIn(t0 + 10000 * k + 5000, k / 50, 0.01 * (k % 7)));
  }
  return v;
}

/// Every active state the engine published, in order.
struct StateTrace {
  std::vector<FilterState> states;
  std::vector<std::string> events;
  EngineOutputs outputs() {
    EngineOutputs o;
    o.on_state = [this](const std::string&, bool active, const FilterState& s) {
      if (active) states.push_back(s);
    };
    o.on_event = [this](const EngineEvent& e) {
      events.push_back(eventName(e.kind) + std::string(": ") + eventText(e));
    };
    return o;
  }
};

}  // namespace

TEST(Engine, ATimeBaseInThePastRestartsTheFiltersSoARunPlayedAgainGivesTheSameStates) {
  // A log played again into a running daemon (or a restarted simulator): without the restart
  // every input of the second run would be refused as too old.
  for (int every : {1, 10}) {
    for (const char* type : {"ukf_gated", "tvekf"}) {
      EngineConfig c = engineConfig(type);
      c.output_every = every;
      c.shadow = {"dead_reckoning"};
      const auto run = drive(5000000, 400);
      StateTrace once, twice;
      {
        FusionEngine e(c, straightMap(3), once.outputs());
        for (auto in : run) e.push(std::move(in));
        e.flush();
      }
      FusionEngine e(c, straightMap(3), twice.outputs());
      for (auto in : run) e.push(std::move(in));
      for (auto in : run) e.push(std::move(in));
      e.flush();
      SCOPED_TRACE(std::string(type) + " output_every " + std::to_string(every));
      EXPECT_EQ(e.counters().processed, 2 * static_cast<int64_t>(run.size()));
      EXPECT_EQ(e.counters().too_old + e.counters().too_new, 0);
      // The same events in both runs (gate lock-outs and recoveries), the restart between them.
      ASSERT_EQ(twice.events.size(), 2 * once.events.size() + 1);
      const std::string& restart = twice.events[once.events.size()];
      EXPECT_NE(restart.find("time_jump: ODOMETRY seq 0: time went back 3 s"), std::string::npos) << restart;
      for (std::size_t k = 0; k < once.events.size(); ++k) {
        EXPECT_EQ(twice.events[k], once.events[k]);
        EXPECT_EQ(twice.events[once.events.size() + 1 + k], once.events[k]);
      }
      ASSERT_GE(once.states.size(), 40u);
      ASSERT_EQ(twice.states.size(), 2 * once.states.size());
      for (std::size_t k = 0; k < once.states.size(); ++k) {
        const FilterState& a = once.states[k];
        const FilterState& b = twice.states[once.states.size() + k];
        ASSERT_EQ(a.utime, b.utime) << k;
        ASSERT_EQ(a.x, b.x) << k;
        ASSERT_EQ(a.P, b.P) << k;
      }
      // The first run ended away from its start: the second really started afresh.
      EXPECT_GT(std::hypot(twice.states[once.states.size() - 1].x[0] - twice.states[once.states.size()].x[0],
                           twice.states[once.states.size() - 1].x[1] - twice.states[once.states.size()].x[1]),
                3.0);
    }
  }
}

TEST(Engine, InputsFarInThePastAreDroppedAsTooOldUnlessThreeInARowStartANewTimeBase) {
  const int64_t t0 = 100 * int64_t{1000000};
  StateTrace clean;
  {
    FusionEngine e(engineConfig("dead_reckoning"), {}, clean.outputs());
    for (auto& in : odometryRun(100, t0)) e.push(std::move(in));
    e.flush();
  }
  // Two stragglers 60 s in the past amid the run: dropped as too old, the rest as the clean run.
  const std::map<int, int64_t> past{{50, t0 - 60000000}, {51, t0 - 59990000}};
  Recorder r;
  FusionEngine e(engineConfig("dead_reckoning"), {}, r.outputs());
  for (auto& in : odometryRun(100, t0, past)) e.push(std::move(in));
  e.flush();
  EXPECT_EQ(e.counters().too_old, 2);
  EXPECT_EQ(e.counters().processed, 98);
  EXPECT_EQ(r.count("time_jump"), 0);
  ASSERT_EQ(r.count("too_old"), 2);
  EXPECT_NE(r.events[0].detail.find("ODOMETRY seq 50 utime 40000000: 60 s behind the newest input"),
            std::string::npos)
      << r.events[0].detail;
  // A first input with a corrupt utime far in the future: the run that follows restarts the
  // filters after the confirm span and then gives the clean run's states.
  StateTrace after;
  FusionEngine f(engineConfig("dead_reckoning"), {}, after.outputs());
  f.push(odoIn(int64_t{1} << 60, 99, 0.5));
  for (auto& in : odometryRun(100, t0)) f.push(std::move(in));
  f.flush();
  EXPECT_EQ(f.counters().too_old, 0);
  ASSERT_EQ(after.events.size(), 1u);
  EXPECT_NE(after.events[0].find("time went back"), std::string::npos) << after.events[0];
  ASSERT_EQ(after.states.size(), clean.states.size() + 1);  // + the corrupt input's
  EXPECT_EQ(after.states.back().x, clean.states.back().x);
  EXPECT_EQ(after.states.back().P, clean.states.back().P);
}

// A stream on a channel no filter uses (GPS fixes to the magnetic filter), its times 25 ms ahead
// of the odometry: its inputs are ordered and processed in turn, but they do not move the
// horizon; the canonical states come out one per odometry input, on the odometry's time. (A
// second publisher's stream there, its times jittered around the live time, released them in
// bursts with silences of up to 30 ms between.) A shadow that uses GPS makes the fixes the
// sensors' time again: the states then come out on the fixes.
TEST(FusionEngine, AMeasurementNoFilterUsesDoesNotMoveTheHorizon) {
  // GPS fixes (used by a GPS shadow only) and bearings (used only when there are landmarks to make
  // a fix from), each 25 ms ahead of the odometry.
  enum class Case { Gps, GpsShadow, BearingsNoMap, BearingsMap };
  for (const Case c : {Case::Gps, Case::GpsShadow, Case::BearingsNoMap, Case::BearingsMap}) {
    EngineConfig cfg = engineConfig();
    if (c == Case::GpsShadow) cfg.shadow = {"ukf_gps"};
    if (c == Case::BearingsMap) cfg.landmarks = {{1, Vec2(100, 0)}, {2, Vec2(0, 100)}, {3, Vec2(-100, -100)}};
    const bool used = c == Case::GpsShadow || c == Case::BearingsMap;
    Recorder rec;
    FusionEngine e(cfg, straightMap(50), rec.outputs());
    auto activeStates = [&] {
      return std::count(rec.log.begin(), rec.log.end(), std::string("state:ukf_gated"));
    };
    int64_t on_odometry = 0, on_fixes = 0, most_at_once = 0;
    for (int k = 1; k <= 300; ++k) {
      const int64_t t = 1'000'000 + k * 10'000;
      auto before = activeStates();
      ASSERT_TRUE(e.push(odoIn(t, k, 0.02)));
      on_odometry += activeStates() - before;
      most_at_once = std::max<int64_t>(most_at_once, activeStates() - before);
      before = activeStates();
      if (c == Case::Gps || c == Case::GpsShadow) {
        GpsInput g;
        g.utime = t + 25'000;
        ASSERT_TRUE(e.push(EngineInput{"GPS", k, g.utime, g}));
      } else {
        BearingsInput b;
        b.utime = t + 25'000;
        b.seq = k;
        b.ids = {1, 2, 3};
        b.bearings = {0.1, 1.6, -2.4};
        ASSERT_TRUE(e.push(EngineInput{"VISION", k, b.utime, b}));
      }
      on_fixes += activeStates() - before;
    }
    const auto before_flush = e.counters().processed;
    e.flush();
    const int label = static_cast<int>(c);
    EXPECT_EQ(e.counters().processed, 600u) << label;  // every input processed all the same
    EXPECT_GT(before_flush, 500u) << label;
    if (used) {
      EXPECT_GT(on_fixes, 250) << label << " " << on_odometry;
    } else {
      EXPECT_EQ(on_fixes, 0) << label;
      EXPECT_EQ(most_at_once, 1) << label;
      EXPECT_EQ(on_odometry, 300 - 6) << label;  // all but the six within the last 50 ms window
    }
  }
}
