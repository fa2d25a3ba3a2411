// The fusion daemon's behaviour over the MemoryBus (no sockets): a filter switch by command, a
// shadow filter, an odometry gap, undecodable and NaN inputs, sequence gaps; and its process
// (DaemonRunner): the hand-over from a running daemon, its own POSE echo, the stop.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include <unistd.h>

#include "daemon/checkpoint.hpp"
#include "daemon/daemon.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/bus/memory_bus.hpp"
#include "lcmloc/fusion_status_t.hpp"
#include "lcmloc/heartbeat_t.hpp"
#include "daemon/runner.hpp"

using namespace lcmloc;
namespace fs = std::filesystem;

namespace {

constexpr int64_t kT0 = 1000000;   // [us] first input
constexpr int64_t kStep = 10000;   // [us] 100 Hz odometry

lcmloc::odometry_t odometry(int64_t seq, int64_t utime) {
  lcmloc::odometry_t m{};
  m.utime = utime;
  m.seq = seq;
  m.delta_s = 0.1;  // 10 m/s
  m.has_steering = true;
  m.steering = 0.01;
  m.delta_theta = 0.1 * std::tan(0.01) / 2.5;
  return m;
}

class DaemonTest : public ::testing::Test {
 protected:
  app::SystemConfig cfg_ = app::loadSystemConfig(LCMLOC_PAPER_YAML);
  bus::MemoryBus bus_;

  /// Odometry seq from..to (inclusive) at 100 Hz on the seq's time (kT0 + seq * kStep), each
  /// delivered at once.
  void odo(int64_t from, int64_t to) {
    for (int64_t k = from; k <= to; ++k) send(cfg_.channels.odometry, odometry(k, kT0 + k * kStep));
  }
  template <typename T>
  void send(const std::string& channel, const T& m) {
    bus_.inject(channel, m);
    bus_.deliverAll();
  }
  std::vector<lcmloc::fusion_status_t> status() const {
    return bus_.decoded<lcmloc::fusion_status_t>(cfg_.channels.status);
  }
  std::vector<lcmloc::fusion_status_t> events(const std::string& event) const {
    std::vector<lcmloc::fusion_status_t> out;
    for (const auto& s : status())
      if (s.event == event) out.push_back(s);
    return out;
  }
  std::vector<lcmloc::pose_t> poses(const std::string& channel) const { return bus_.decoded<lcmloc::pose_t>(channel); }
  static bool finite(const lcmloc::pose_t& p) {
    for (double v : p.state)
      if (!std::isfinite(v)) return false;
    for (const auto& row : p.covariance)
      for (double v : row)
        if (!std::isfinite(v)) return false;
    return p.dim >= 3;
  }
};

}  // namespace

TEST_F(DaemonTest, ASwitchCommandIsAnsweredAndThePoseComesFromTheNewFilterFromThenOn) {
  ASSERT_EQ(cfg_.fusion.filter.type, "ukf_gated");
  fusion::FusionDaemon daemon(cfg_, bus_);
  odo(0, 49);
  lcmloc::fusion_control_t c{};
  c.utime = kT0 + 50 * kStep;
  c.seq = 77;
  c.command = lcmloc::fusion_control_t::CMD_SWITCH_FILTER;
  c.filter = "dead_reckoning";
  send(cfg_.channels.control, c);
  odo(50, 99);
  daemon.shutdown();

  // In the order published: POSE from ukf_gated, the ack on FUSION_STATUS, POSE from dead_reckoning.
  int before = 0, after = 0;
  bool acked = false;
  for (const auto& m : bus_.published()) {
    if (m.channel == cfg_.channels.status) {
      lcmloc::fusion_status_t s;
      ASSERT_GE(s.decode(m.data.data(), 0, static_cast<int>(m.data.size())), 0);
      if (s.event != "ack") continue;
      EXPECT_FALSE(acked) << "one answer per command";
      acked = true;
      EXPECT_NE(s.detail.find("FUSION_CONTROL seq 77: switched ukf_gated -> dead_reckoning"), std::string::npos)
          << s.detail;
      EXPECT_EQ(s.filter, "dead_reckoning");
    } else if (m.channel == cfg_.channels.pose) {
      lcmloc::pose_t p;
      ASSERT_GE(p.decode(m.data.data(), 0, static_cast<int>(m.data.size())), 0);
      EXPECT_EQ(p.filter, acked ? "dead_reckoning" : "ukf_gated") << "POSE at utime " << p.utime;
      ++(acked ? after : before);
    }
  }
  EXPECT_TRUE(acked);
  EXPECT_GE(before, 40);
  EXPECT_GE(after, 40);
  EXPECT_EQ(daemon.activeFilter(), "dead_reckoning");
  EXPECT_EQ(status().back().event, "stopped");
  EXPECT_EQ(status().back().filter, "dead_reckoning");
}

TEST_F(DaemonTest, AnUnknownFilterIsRefusedAndTheActiveOneKeepsRunning) {
  fusion::FusionDaemon daemon(cfg_, bus_);
  odo(0, 9);
  lcmloc::fusion_control_t c{};
  c.utime = kT0 + 10 * kStep;
  c.seq = 5;
  c.command = lcmloc::fusion_control_t::CMD_SWITCH_FILTER;
  c.filter = "no_such_filter";
  send(cfg_.channels.control, c);
  odo(10, 19);
  daemon.shutdown();
  ASSERT_EQ(events("refused").size(), 1u);
  EXPECT_NE(events("refused")[0].detail.find("no_such_filter"), std::string::npos) << events("refused")[0].detail;
  EXPECT_TRUE(events("ack").empty());
  EXPECT_EQ(poses(cfg_.channels.pose).back().filter, "ukf_gated");
}

TEST_F(DaemonTest, AShadowFilterPublishesOnItsOwnChannelBesideTheActiveOne) {
  cfg_.fusion.shadow = {"dead_reckoning"};
  fusion::FusionDaemon daemon(cfg_, bus_);
  odo(0, 49);
  daemon.shutdown();
  const auto active = poses(cfg_.channels.pose);
  const auto shadow = poses(cfg_.channels.pose + "_DEAD_RECKONING");
  ASSERT_GE(active.size(), 40u);
  ASSERT_EQ(shadow.size(), active.size()) << "a shadow POSE for every POSE";
  for (std::size_t i = 0; i < active.size(); ++i) {
    EXPECT_EQ(active[i].filter, "ukf_gated");
    EXPECT_EQ(shadow[i].filter, "dead_reckoning");
    EXPECT_EQ(shadow[i].utime, active[i].utime);
    EXPECT_EQ(shadow[i].seq, static_cast<int64_t>(i)) << "a seq of its own per channel";
  }
  // Both integrated the same odometry: 50 increments of 0.1 m, nearly straight ahead (+y) (the
  // UKF's mean a little shorter: its heading is uncertain).
  EXPECT_NEAR(shadow.back().state[1], 5.0, 0.01);
  EXPECT_NEAR(active.back().state[1], shadow.back().state[1], 0.1);
  // Steering 0.01 rad to the left: 0.02 rad turned over 5 m, about 0.05 m towards -x.
  EXPECT_NEAR(shadow.back().state[0], -0.05, 0.005);
}

TEST_F(DaemonTest, AnOdometryGapIsBridgedAndReported) {
  fusion::FusionDaemon daemon(cfg_, bus_);
  odo(0, 49);
  odo(80, 99);  // 30 messages lost: 0.31 s without odometry (max_odometry_gap 0.1 s)
  daemon.shutdown();
  const auto gaps = events("odometry_gap");
  ASSERT_EQ(gaps.size(), 1u);
  EXPECT_NE(gaps[0].detail.find("ODOMETRY seq 80 after seq 49"), std::string::npos) << gaps[0].detail;
  EXPECT_NE(gaps[0].detail.find("messages lost"), std::string::npos) << gaps[0].detail;
  EXPECT_EQ(daemon.gaps(), 30);
  // Bridged at the last speed (10 m/s): the position goes on across the gap, with a larger
  // covariance than before it.
  // The same drive without the gap, for comparison.
  bus::MemoryBus whole_bus;
  fusion::FusionDaemon whole(cfg_, whole_bus);
  for (int64_t k = 0; k <= 99; ++k) whole_bus.inject(cfg_.channels.odometry, odometry(k, kT0 + k * kStep));
  whole_bus.deliverAll();
  whole.shutdown();
  auto at = [&](const bus::MemoryBus& bus, int64_t seq) {
    for (const auto& pose : bus.decoded<lcmloc::pose_t>(cfg_.channels.pose))
      if (pose.utime == kT0 + seq * kStep) return pose;
    ADD_FAILURE() << "no POSE at seq " << seq;
    return lcmloc::pose_t{};
  };
  const auto after = at(bus_, 80), without = at(whole_bus, 80), before = at(bus_, 49);
  ASSERT_EQ(after.dim, 3);
  ASSERT_EQ(without.dim, 3);
  ASSERT_EQ(before.dim, 3);
  EXPECT_NEAR(after.state[1], without.state[1], 0.05) << "bridged at the speed before the gap";
  EXPECT_GT(after.state[1], before.state[1] + 3.0);
  EXPECT_GT(after.covariance[1][1], without.covariance[1][1]) << "less certain along the track (+y) than without the gap";
  for (const auto& st : whole_bus.decoded<lcmloc::fusion_status_t>(cfg_.channels.status))
    EXPECT_NE(st.event, "odometry_gap") << "without the gap: " << st.detail;
}

TEST_F(DaemonTest, AnUndecodableMessageIsRejectedAndCountedAndTheDaemonGoesOn) {
  fusion::FusionDaemon daemon(cfg_, bus_);
  odo(0, 9);
  bus_.inject(cfg_.channels.odometry, std::vector<uint8_t>{0xde, 0xad, 0xbe, 0xef});
  bus_.deliverAll();
  odo(10, 19);
  daemon.shutdown();
  EXPECT_EQ(daemon.rejected(), 1);
  EXPECT_EQ(bus_.decodeErrors(cfg_.channels.odometry), 1);
  const auto rejected = events("rejected_input");
  ASSERT_EQ(rejected.size(), 1u);
  EXPECT_NE(rejected[0].detail.find("ODOMETRY: cannot decode odometry_t"), std::string::npos)
      << rejected[0].detail;
  EXPECT_EQ(rejected[0].messages_rejected, 1);
  EXPECT_EQ(status().back().messages_rejected, 1);
  EXPECT_EQ(daemon.processed(), 20);
  const auto p = poses(cfg_.channels.pose);
  ASSERT_FALSE(p.empty());
  EXPECT_EQ(p.back().utime, kT0 + 19 * kStep);
  for (const auto& pose : p) EXPECT_TRUE(finite(pose)) << "POSE at " << pose.utime;
}

TEST_F(DaemonTest, ANonFiniteMessageIsRejectedAndCountedAndThePoseStaysFinite) {
  fusion::FusionDaemon daemon(cfg_, bus_);
  odo(0, 9);
  auto bad = odometry(10, kT0 + 10 * kStep);
  bad.delta_s = std::nan("");
  send(cfg_.channels.odometry, bad);
  auto inf = odometry(11, kT0 + 11 * kStep);
  inf.delta_theta = INFINITY;
  send(cfg_.channels.odometry, inf);
  odo(12, 29);
  daemon.shutdown();
  EXPECT_EQ(daemon.rejected(), 2);
  EXPECT_EQ(daemon.gaps(), 0) << "a rejected message still continues its channel's seq";
  const auto rejected = events("rejected_input");
  ASSERT_EQ(rejected.size(), 2u);
  EXPECT_NE(rejected[0].detail.find("ODOMETRY seq 10"), std::string::npos) << rejected[0].detail;
  EXPECT_NE(rejected[0].detail.find("delta_s"), std::string::npos) << rejected[0].detail;
  EXPECT_NE(rejected[1].detail.find("delta_theta"), std::string::npos) << rejected[1].detail;
  EXPECT_EQ(daemon.processed(), 28);
  const auto p = poses(cfg_.channels.pose);
  ASSERT_FALSE(p.empty());
  for (const auto& pose : p) EXPECT_TRUE(finite(pose)) << "POSE at " << pose.utime;
  EXPECT_NEAR(p.back().state[1], 2.8, 0.05) << "the rejected increments are not integrated";
}

TEST_F(DaemonTest, SequenceGapsAreCountedPerChannelAndReported) {
  fusion::FusionDaemon daemon(cfg_, bus_);
  odo(0, 9);
  odo(13, 19);  // 10, 11, 12 lost (0.04 s: no odometry gap)
  odo(25, 30);  // 5 more
  daemon.shutdown();
  EXPECT_EQ(daemon.gaps(), 8);
  const auto drops = events("drop");
  ASSERT_EQ(drops.size(), 2u);
  EXPECT_NE(drops[0].detail.find("ODOMETRY"), std::string::npos) << drops[0].detail;
  EXPECT_EQ(drops[0].sequence_gaps, 3);
  EXPECT_EQ(drops[1].sequence_gaps, 8);
  EXPECT_EQ(status().back().sequence_gaps, 8);
  EXPECT_TRUE(events("odometry_gap").empty()) << "0.06 s apart is within max_odometry_gap";
  EXPECT_EQ(daemon.processed(), 10 + 7 + 6);
}

// A second publisher on ODOMETRY (a driver started twice, lcm-logplayer on the live network):
// its stream (seq from 0, -1 m every 10 ms, time near the live one) is held apart or refused by
// the physical limits, and reported once on the status: the pose is the one without it.
TEST_F(DaemonTest, ASecondPublisherIsHeldApartReportedAndChangesNoPose) {
  std::vector<lcmloc::pose_t> clean;
  for (const bool hostile : {false, true}) {
    bus::MemoryBus bus;
    fusion::FusionDaemon daemon(cfg_, bus);
    for (int64_t k = 0; k < 300; ++k) {
      bus.inject(cfg_.channels.odometry, odometry(5000 + k, kT0 + k * kStep));
      bus.deliverAll();
      if (!hostile || k < 100) continue;
      auto m = odometry(k - 100, kT0 + k * kStep + 3000);
      m.delta_s = -1.0;
      m.steering = -1.0;
      m.has_steering = false;  // (a yaw-rate source: -1 m and 0 rad, within the yaw-rate bound)
      m.delta_theta = 0.0;
      bus.inject(cfg_.channels.odometry, m);
      bus.deliverAll();
    }
    daemon.shutdown();
    auto p = bus.decoded<lcmloc::pose_t>(cfg_.channels.pose);
    for (auto& x : p) x.seq = 0;
    if (!hostile) {
      clean = p;
      EXPECT_EQ(daemon.rejected(), 0);
      continue;
    }
    ASSERT_EQ(p.size(), clean.size());
    for (std::size_t i = 0; i < p.size(); ++i) {
      ASSERT_EQ(p[i].utime, clean[i].utime) << i;
      ASSERT_EQ(p[i].state, clean[i].state) << i;
    }
    const auto st = bus.decoded<lcmloc::fusion_status_t>(cfg_.channels.status);
    int second = 0, limit = 0;
    for (const auto& s : st) {
      if (s.event == "second_publisher") {
        ++second;
        EXPECT_NE(s.detail.find("ODOMETRY: a second publisher (first seq 0 at utime 2003000)"), std::string::npos)
            << s.detail;
      }
      if (s.event == "rejected_input" && s.detail.find("max_speed") != std::string::npos) ++limit;
    }
    EXPECT_EQ(second, 1);
    EXPECT_EQ(limit, 1);  // its first message, a lone seq so far, refused by the speed bound
    EXPECT_EQ(daemon.rejected(), 200);
    EXPECT_EQ(daemon.gaps(), 0);
  }
}

// A flood of bad messages (100 undecodable and 100 NaN odometry messages within one status
// period) costs a few status events per channel and reason, then one summary in the periodic
// status: counts per channel and reason; every one is counted as rejected.
TEST_F(DaemonTest, AFloodOfBadMessagesIsCountedPerChannelAndReasonNotReportedOneByOne) {
  fusion::FusionDaemon daemon(cfg_, bus_);
  odo(0, 9);
  for (int k = 0; k < 100; ++k) {
    bus_.inject(cfg_.channels.odometry, std::vector<uint8_t>{1, 2, 3});
    auto bad = odometry(10, kT0 + 10 * kStep);
    bad.delta_s = std::nan("");
    bus_.inject(cfg_.channels.odometry, bad);
  }
  bus_.deliverAll();
  odo(10, 250);  // 2.4 s more: periodic status reports
  daemon.shutdown();
  EXPECT_EQ(daemon.rejected(), 200);
  EXPECT_EQ(events("rejected_input").size(), 2 * fusion::RejectBook::kEventsPerPeriod);
  bool summary = false;
  for (const auto& s : events("periodic"))
    summary |= s.detail.find("rejected since the last periodic status: ODOMETRY invalid 100 (95 not reported each), "
                             "ODOMETRY undecodable 100 (95 not reported each)") != std::string::npos;
  EXPECT_TRUE(summary);
  const auto stopped = events("stopped");
  ASSERT_EQ(stopped.size(), 1u);
  EXPECT_NE(stopped[0].detail.find("rejected by channel and reason: ODOMETRY invalid 100, ODOMETRY undecodable 100"),
            std::string::npos)
      << stopped[0].detail;
  for (const auto& pose : poses(cfg_.channels.pose)) EXPECT_TRUE(finite(pose));
}

// Odometry that decodes but describes no vehicle's motion is refused with the bound it broke
// (fusion.limits), and the pose goes on from the rest.
TEST_F(DaemonTest, OdometryBeyondThePhysicalLimitsIsRefusedNamingTheLimit) {
  fusion::FusionDaemon daemon(cfg_, bus_);
  odo(0, 9);
  auto fast = odometry(10, kT0 + 10 * kStep);
  fast.delta_s = 2.0;  // 200 m/s
  send(cfg_.channels.odometry, fast);
  auto steer = odometry(11, kT0 + 11 * kStep);
  steer.steering = -1.0;
  send(cfg_.channels.odometry, steer);
  odo(12, 29);
  daemon.shutdown();
  EXPECT_EQ(daemon.rejected(), 2);
  const auto rejected = events("rejected_input");
  ASSERT_EQ(rejected.size(), 2u);
  EXPECT_NE(rejected[0].detail.find("ODOMETRY seq 10: increment 2 m over 0.01 s is 200 m/s, beyond fusion.limits.max_speed 70"),
            std::string::npos)
      << rejected[0].detail;
  EXPECT_NE(rejected[1].detail.find("max_steering"), std::string::npos) << rejected[1].detail;
  const auto p = poses(cfg_.channels.pose);
  ASSERT_FALSE(p.empty());
  EXPECT_NEAR(p.back().state[1], 2.8, 0.05) << "the refused increments are not integrated";
}

// ---------------------------------------------------------------------------------------------
// The process around the daemon (lcmloc-fusion's main), over the MemoryBus

TEST_F(DaemonTest, AHandOverStartsFromTheRunningDaemonsLastPose) {
  fusion::RunnerOptions ro;
  ro.init_from_bus = 30.0;  // (a bound: the old daemon's "stopped" ends the wait)
  fusion::DaemonRunner runner(cfg_, ro);
  lcmloc::pose_t old{};
  old.utime = kT0;
  old.seq = 41;
  old.filter = "ukf";
  old.dim = 3;
  old.state = {50.0, 2.0, 0.3};
  old.state_names = {"x", "y", "theta"};
  old.covariance = {{1e-4, 0, 0}, {0, 1e-4, 0}, {0, 0, 1e-4}};
  bus_.inject(cfg_.channels.pose, old);
  lcmloc::fusion_status_t stopped{};
  stopped.event = "stopped";
  bus_.inject(cfg_.channels.status, stopped);
  runner.start(bus_);
  const auto started = events("started");
  ASSERT_EQ(started.size(), 1u);
  EXPECT_NE(started[0].detail.find("initialized from the last POSE on the bus (filter ukf)"), std::string::npos)
      << started[0].detail;
  bus_.inject(cfg_.channels.odometry, odometry(1, kT0 + kStep));
  while (bus_.queued() > 0) runner.step(0);
  EXPECT_EQ(runner.finish(), app::kExitOk);
  const auto p = poses(cfg_.channels.pose);
  ASSERT_EQ(p.size(), 1u);
  EXPECT_NEAR(p[0].state[0], 50.0 + 0.1 * std::cos(0.3), 1e-3);
  EXPECT_NEAR(p[0].state[1], 2.0 + 0.1 * std::sin(0.3), 1e-3);
  EXPECT_EQ(runner.daemon().foreignOutputs(), 0) << "its own POSE came back: not another daemon's";
}

TEST_F(DaemonTest, APoseThisDaemonDidNotPublishIsReportedAsAnotherDaemons) {
  fusion::DaemonRunner runner(cfg_, fusion::RunnerOptions{});
  runner.start(bus_);
  for (int64_t k = 0; k < 20; ++k) bus_.inject(cfg_.channels.odometry, odometry(k, kT0 + k * kStep));
  while (bus_.queued() > 0) runner.step(0);  // the inputs, and its own POSE coming back
  ASSERT_GE(poses(cfg_.channels.pose).size(), 10u);
  EXPECT_EQ(runner.daemon().foreignOutputs(), 0);
  EXPECT_TRUE(events("foreign_output").empty());
  lcmloc::pose_t other = poses(cfg_.channels.pose).front();
  other.state[0] += 1.0;  // seq 0 again, another state
  bus_.inject(cfg_.channels.pose, other);
  while (bus_.queued() > 0) runner.step(0);
  EXPECT_EQ(runner.daemon().foreignOutputs(), 1);
  ASSERT_EQ(events("foreign_output").size(), 1u);
  EXPECT_EQ(runner.finish(), app::kExitOk);
  EXPECT_EQ(status().back().event, "stopped");
  const auto hb = bus_.decoded<lcmloc::heartbeat_t>(cfg_.channels.heartbeat);
  ASSERT_FALSE(hb.empty());
  EXPECT_EQ(hb.back().state, "stopping");
  EXPECT_EQ(hb.back().process, "lcmloc-fusion");
}

TEST_F(DaemonTest, TheCheckpointHoldsTheActiveStateAtTheStop) {
  const fs::path dir = fs::temp_directory_path() / ("lcmloc_daemon_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  fusion::RunnerOptions ro;
  ro.checkpoint = (dir / "fusion.ck").string();
  {
    fusion::DaemonRunner runner(cfg_, ro);
    runner.start(bus_);
    // No checkpoint file yet: the start is that of a daemon without --checkpoint (a replay's).
    EXPECT_EQ(events("started").at(0).detail, "filter ukf_gated");
    for (int64_t k = 0; k < 20; ++k) bus_.inject(cfg_.channels.odometry, odometry(k, kT0 + k * kStep));
    while (bus_.queued() > 0) runner.step(0);
    EXPECT_EQ(runner.finish(), app::kExitOk);
  }
  const auto ck = fusion::readCheckpoint(ro.checkpoint);
  ASSERT_TRUE(ck.has_value());
  EXPECT_EQ(ck->filter, "ukf_gated");
  EXPECT_EQ(ck->state.utime, kT0 + 19 * kStep);
  EXPECT_NEAR(ck->state.x(1), poses(cfg_.channels.pose).back().state[1], 1e-9);
  fs::remove_all(dir);
}

// ukf_landmarks' self-calibration states (FilterConfig::Calibration): the periodic status says
// their estimates, the checkpoint holds them, and a daemon started from a checkpoint starts
// from them (values and variances), not from their priors.
TEST_F(DaemonTest, CalibrationStatesAreReportedAndRoundTripThroughTheCheckpoint) {
  const fs::path dir = fs::temp_directory_path() / ("lcmloc_daemon_cal_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  cfg_.fusion.filter.type = "ukf_landmarks";
  cfg_.fusion.filter.calibration.odo_scale = true;
  cfg_.fusion.filter.calibration.odo_scale_std = 0.04;
  cfg_.fusion.filter.calibration.yaw_rate_bias = true;
  fusion::RunnerOptions ro;
  ro.checkpoint = (dir / "fusion.ck").string();
  {
    fusion::DaemonRunner runner(cfg_, ro);
    runner.start(bus_);
    for (int64_t k = 0; k < 250; ++k) bus_.inject(cfg_.channels.odometry, odometry(k, kT0 + k * kStep));
    while (bus_.queued() > 0) runner.step(0);
    EXPECT_EQ(runner.finish(), app::kExitOk);
  }
  const auto periodic = events("periodic");
  ASSERT_FALSE(periodic.empty());
  EXPECT_EQ(periodic.back().detail.rfind("calibration: odo_scale 0 +- 0.04, yaw_rate_bias 0 +- ", 0), 0u)
      << periodic.back().detail;
  auto ck = fusion::readCheckpoint(ro.checkpoint);
  ASSERT_TRUE(ck.has_value());
  EXPECT_EQ(ck->filter, "ukf_landmarks");
  ASSERT_EQ(ck->state.names, (std::vector<std::string>{"x", "y", "theta", "cal_odo_scale", "cal_yaw_rate_bias"}));

  // A checkpoint whose calibration has been learnt: the next daemon starts from it.
  ck->state.x[3] = 0.031;
  ck->state.x[4] = -0.004;
  ck->state.P.bottomRows(2).setZero();
  ck->state.P.rightCols(2).setZero();
  ck->state.P(3, 3) = 1e-6;
  ck->state.P(4, 4) = 4e-8;
  fusion::writeCheckpoint(ro.checkpoint, ck->state, ck->filter);
  const int64_t t1 = ck->state.utime;
  {
    bus::MemoryBus bus;  // (the first runner's subscriptions stay on bus_: a bus of its own)
    fusion::DaemonRunner runner(cfg_, ro);
    runner.start(bus);
    for (int64_t k = 1; k <= 3; ++k) bus.inject(cfg_.channels.odometry, odometry(300 + k, t1 + k * kStep));
    while (bus.queued() > 0) runner.step(0);
    const core::FilterState s = runner.daemon().activeState();
    ASSERT_EQ(s.names, ck->state.names);
    EXPECT_NEAR(s.x[3], 0.031, 1e-12);
    EXPECT_NEAR(s.x[4], -0.004, 1e-12);
    EXPECT_NEAR(s.P(3, 3), 1e-6, 1e-8);  // (3 odometry steps of random walk)
    EXPECT_NEAR(s.P(4, 4), 4e-8, 1e-9);
    EXPECT_EQ(runner.finish(), app::kExitOk);
  }
  fs::remove_all(dir);
}
