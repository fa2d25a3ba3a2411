// The delay-aware fusion horizon (fusion.sensors.<key>.delay, docs/horizon.md) over the GPS
// golden's recorded inputs (tests/data/golden/gps.lcmlog: ODOMETRY and IMU at 100 Hz, GPS at
// 1 Hz): a fix delivered 200 ms after its time is fused within a 0.25 s horizon, the live daemon
// giving the offline replay's output byte for byte; within a 0.1 s horizon it is refused and
// counted with its lateness; and inputs arriving in any order within the horizon give the
// canonical output of the in-order run.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "daemon/daemon.hpp"
#include "daemon/inputs.hpp"
#include "lcmloc/app/config.hpp"
#include "lcmloc/bus/memory_bus.hpp"
#include "lcmloc/core/engine.hpp"
#include "lcmloc/fusion_status_t.hpp"
#include "lcmloc/gate_decision_t.hpp"
#include "lcmloc/gps_fix_t.hpp"
#include "lcmloc/imu_t.hpp"
#include "lcmloc/odometry_t.hpp"
#include "lcmloc/pose_t.hpp"
#include "lcmloc/replay/replay.hpp"
#include "process_fixture.hpp"

using namespace lcmloc;
namespace fs = std::filesystem;

namespace {

const std::string kGolden = LCMLOC_GOLDEN_DIR;

/// An input event of the log with its message time.
struct Timed {
  LogEvent event;
  int64_t utime = 0;
};

template <typename T>
bool decodeInto(const LogEvent& e, T& m) {
  return m.decode(e.data.data(), 0, static_cast<int>(e.data.size())) >= 0;
}

/// The golden's input events, in the log's order, each with its message time.
std::vector<Timed> goldenInputs() {
  std::vector<Timed> out;
  for (auto& e : readLog(kGolden + "/gps.lcmlog")) {
    int64_t utime = 0;
    if (lcmloc::odometry_t o; e.channel == "ODOMETRY" && decodeInto(e, o)) utime = o.utime;
    else if (lcmloc::imu_t i; e.channel == "IMU" && decodeInto(e, i)) utime = i.utime;
    else if (lcmloc::gps_fix_t g; e.channel == "GPS" && decodeInto(e, g)) utime = g.utime;
    else continue;
    out.push_back({std::move(e), utime});
  }
  return out;
}

/// The events as they arrive when each GPS fix is delivered delay_us after its time: after the
/// last other input of message time at most its time + delay_us.
/// The live daemon over bus: the events delivered one by one in the order given, then shut down;
/// its inputs later than the horizon per channel.
std::map<std::string, core::LateInputs> runDaemon(const app::SystemConfig& cfg, const std::vector<Timed>& events,
                                                  bus::MemoryBus& bus) {
  fusion::FusionDaemon d(cfg, bus);
  for (const Timed& t : events) {
    bus.inject(t.event.channel, t.event.data);
    bus.deliverAll();
  }
  d.shutdown();
  return d.lateInputs();
}

std::vector<Timed> gpsDelayed(const std::vector<Timed>& in, int64_t delay_us) {
  std::vector<Timed> out, waiting;
  for (const Timed& t : in) {
    if (t.event.channel == "GPS") {
      waiting.push_back(t);
      continue;
    }
    while (!waiting.empty() && waiting.front().utime + delay_us < t.utime) {
      out.push_back(waiting.front());
      waiting.erase(waiting.begin());
    }
    out.push_back(t);
  }
  out.insert(out.end(), waiting.begin(), waiting.end());
  return out;
}

void writeLog(const std::string& path, const std::vector<Timed>& events) {
  lcm::LogFile log(path, "w");
  ASSERT_TRUE(log.good());
  int64_t arrival = 0;
  for (const Timed& t : events) {
    arrival = std::max(arrival, t.utime);
    lcm::LogEvent ev;
    ev.eventnum = 0;
    ev.timestamp = arrival;
    ev.channel = t.event.channel;
    ev.datalen = static_cast<int32_t>(t.event.data.size());
    ev.data = const_cast<uint8_t*>(t.event.data.data());
    ASSERT_EQ(log.writeEvent(&ev), 0);
  }
}

std::string slurp(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

/// Payloads of channel in the log, in order.
std::vector<std::vector<uint8_t>> payloads(const std::string& log, const std::string& channel) {
  std::vector<std::vector<uint8_t>> out;
  for (const auto& e : readLog(log))
    if (e.channel == channel) out.push_back(e.data);
  return out;
}

class HorizonTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("lcmloc_horizon_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    cfg_ = app::loadSystemConfig(kGolden + "/gps.yaml");
    inputs_ = goldenInputs();
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  app::SystemConfig withGpsDelay(double delay) const {
    app::SystemConfig c = cfg_;
    c.fusion.sensors["gps"].delay = delay;
    return c;
  }
  replay::ReplayResult replayInto(const app::SystemConfig& cfg, const std::string& in, const std::string& out) {
    replay::ReplayOptions o;
    o.input = in;
    o.output = out;
    o.progress_period_s = 0;
    return replay::replayLog(cfg, o);
  }
  /// The live daemon over the MemoryBus, the events delivered in the order given.
  struct Live {
    std::vector<std::vector<uint8_t>> pose, gate;
    std::map<std::string, core::LateInputs> late;
  };
  Live live(const app::SystemConfig& cfg, const std::vector<Timed>& events) {
    bus::MemoryBus bus;
    Live l;
    l.late = runDaemon(cfg, events, bus);
    for (const auto& m : bus.published(cfg.channels.pose)) l.pose.push_back(m.data);
    for (const auto& m : bus.published(cfg.channels.gate)) l.gate.push_back(m.data);
    return l;
  }

  fs::path dir_;
  app::SystemConfig cfg_;
  std::vector<Timed> inputs_;
};

int gpsAccepted(const std::string& log) {
  int n = 0;
  for (const auto& d : payloads(log, "GATE")) {
    lcmloc::gate_decision_t g;
    EXPECT_GE(g.decode(d.data(), 0, static_cast<int>(d.size())), 0);
    if (g.sensor == "GPS" && g.accepted && g.filter == "tvekf") ++n;
  }
  return n;
}

lcmloc::pose_t lastPose(const std::string& log) {
  lcmloc::pose_t p;
  const auto all = payloads(log, "POSE");
  EXPECT_FALSE(all.empty());
  if (!all.empty()) {
    EXPECT_GE(p.decode(all.back().data(), 0, static_cast<int>(all.back().size())), 0);
  }
  return p;
}

}  // namespace

TEST_F(HorizonTest, AFixDelivered200msLateIsFusedWithinA250msHorizonLiveAsInReplay) {
  const std::vector<Timed> late = gpsDelayed(inputs_, 200000);
  int fixes = 0, moved = 0;
  for (std::size_t i = 0; i < late.size(); ++i) {
    fixes += late[i].event.channel == "GPS";
    moved += late[i].event.channel == "GPS" && late[i].utime != inputs_[i].utime;
  }
  ASSERT_GE(fixes, 10);
  ASSERT_GE(moved, fixes - 1) << "each fix arrives after the inputs of the 200 ms after it";
  writeLog(path("in_order.lcmlog"), inputs_);
  writeLog(path("late.lcmlog"), late);

  const app::SystemConfig cfg = withGpsDelay(0.25);
  ASSERT_EQ(core::FusionEngine(app::engineConfig(cfg), {}, {}).horizonUs(), 250000);
  const auto in_order = replayInto(cfg, path("in_order.lcmlog"), path("in_order_out.lcmlog"));
  const auto delayed = replayInto(cfg, path("late.lcmlog"), path("late_out.lcmlog"));
  EXPECT_EQ(delayed.rejected, 0);
  EXPECT_EQ(delayed.used, in_order.used);
  // Fused: the very output of the run where each fix came on time, its fixes accepted.
  EXPECT_TRUE(slurp(path("late_out.lcmlog")) == slurp(path("in_order_out.lcmlog")));
  EXPECT_GE(gpsAccepted(path("late_out.lcmlog")), fixes - 2);

  // The live daemon over the MemoryBus, the messages in the same order: the replay's bytes.
  const Live l = live(cfg, late);
  EXPECT_TRUE(l.late.empty());
  EXPECT_TRUE(l.pose == payloads(path("late_out.lcmlog"), "POSE"));
  EXPECT_TRUE(l.gate == payloads(path("late_out.lcmlog"), "GATE"));
  ASSERT_GT(l.pose.size(), 1000u);

  // Within a 0.1 s horizon the same fixes are refused, each counted with its lateness, and the
  // estimate is another: the fixes changed it.
  const app::SystemConfig narrow = withGpsDelay(0.1);
  const auto refused = replayInto(narrow, path("late.lcmlog"), path("narrow_out.lcmlog"));
  EXPECT_EQ(refused.rejected, fixes);
  EXPECT_EQ(gpsAccepted(path("narrow_out.lcmlog")), 0);
  const lcmloc::pose_t fused = lastPose(path("late_out.lcmlog")), dropped = lastPose(path("narrow_out.lcmlog"));
  EXPECT_GT(std::hypot(fused.state[0] - dropped.state[0], fused.state[1] - dropped.state[1]), 1.0);
  const Live n = live(narrow, late);
  ASSERT_EQ(n.late.count("GPS"), 1u);
  EXPECT_EQ(n.late.at("GPS").count, fixes);
  EXPECT_GT(n.late.at("GPS").max_lateness_us, 190000);
  EXPECT_LE(n.late.at("GPS").max_lateness_us, 200000);
  int said = 0;
  for (const auto& e : readLog(path("narrow_out.lcmlog"))) {
    if (e.channel != "FUSION_STATUS") continue;
    lcmloc::fusion_status_t s;
    ASSERT_GE(s.decode(e.data.data(), 0, static_cast<int>(e.data.size())), 0);
    if (s.event == "rejected_input" && s.detail.find("GPS seq") != std::string::npos &&
        s.detail.find("s after its time") != std::string::npos && s.detail.find("the horizon is 0.100 s") != std::string::npos)
      ++said;
  }
  EXPECT_GE(said, 5) << "the first ones of a status period each say their lateness";
  const auto status = payloads(path("narrow_out.lcmlog"), "FUSION_STATUS");
  lcmloc::fusion_status_t stopped;
  ASSERT_GE(stopped.decode(status.back().data(), 0, static_cast<int>(status.back().size())), 0);
  EXPECT_EQ(stopped.event, "stopped");
  EXPECT_NE(stopped.detail.find(", GPS later than the 0.100 s horizon " + std::to_string(fixes) + " (by up to 0.200 s)"),
            std::string::npos) << stopped.detail;
}

// The golden's inputs, each arriving up to the horizon after its time in many random orders:
// the canonical output (every state, decision and event, bit for bit) is that of the in-order run.
TEST_F(HorizonTest, InputsShuffledWithinTheHorizonGiveTheInOrderCanonicalOutput) {
  const app::SystemConfig cfg = withGpsDelay(0.25);
  const core::EngineConfig ec = app::engineConfig(cfg);
  const int64_t horizon = ec.horizonUs();
  fusion::DaemonIntake intake(cfg);
  std::vector<core::EngineInput> all;
  fusion::IntakeItem item;
  for (const Timed& t : inputs_) {
    if (lcmloc::odometry_t o; t.event.channel == "ODOMETRY" && decodeInto(t.event, o)) intake.take(t.event.channel, o, item);
    else if (lcmloc::imu_t i; t.event.channel == "IMU" && decodeInto(t.event, i)) intake.take(t.event.channel, i, item);
    else if (lcmloc::gps_fix_t g; decodeInto(t.event, g)) intake.take(t.event.channel, g, item);
    if (item.kind == fusion::IntakeItem::Kind::Input) all.push_back(item.input);
  }
  ASSERT_GT(all.size(), 2000u);
  std::stable_sort(all.begin(), all.end(), [](const auto& a, const auto& b) { return a.utime < b.utime; });

  auto run = [&](const std::vector<core::EngineInput>& order, core::EngineCounters* counters) {
    std::string bytes;
    auto add = [&bytes](const void* p, std::size_t n) { bytes.append(static_cast<const char*>(p), n); };
    core::EngineOutputs out;
    out.on_state = [&](const std::string& f, bool active, const core::FilterState& s) {
      bytes += f + (active ? "+" : "-");
      add(&s.utime, sizeof s.utime);
      add(s.x.data(), sizeof(double) * static_cast<std::size_t>(s.x.size()));
      add(s.P.data(), sizeof(double) * static_cast<std::size_t>(s.P.size()));
    };
    out.on_decision = [&](const std::string& f, bool, const core::GateDecision& d) {
      bytes += f + d.sensor + d.reason + (d.accepted ? "A" : "R");
      add(&d.mahalanobis, sizeof d.mahalanobis);
    };
    out.on_event = [&](const core::EngineEvent& e) { bytes += std::string(core::eventName(e.kind)) + core::eventText(e); };
    core::FusionEngine engine(ec, {}, out);
    for (const auto& in : order) engine.push(in);
    engine.flush();
    *counters = engine.counters();
    return bytes;
  };
  core::EngineCounters c0;
  const std::string expected = run(all, &c0);
  ASSERT_GT(expected.size(), 100000u);
  ASSERT_EQ(c0.too_old, 0);

  std::mt19937_64 rng(36);
  for (int trial = 0; trial < 25; ++trial) {
    std::uniform_int_distribution<int64_t> delay(0, horizon);
    std::vector<std::pair<int64_t, std::size_t>> arrival;
    for (std::size_t i = 0; i < all.size(); ++i) arrival.push_back({all[i].utime + delay(rng), i});
    std::sort(arrival.begin(), arrival.end());
    std::vector<core::EngineInput> shuffled;
    std::size_t out_of_order = 0;
    int64_t newest = INT64_MIN;
    for (const auto& [at, i] : arrival) {
      out_of_order += all[i].utime < newest;
      newest = std::max(newest, all[i].utime);
      shuffled.push_back(all[i]);
    }
    ASSERT_GT(out_of_order, all.size() / 4) << "trial " << trial;
    core::EngineCounters c;
    const std::string got = run(shuffled, &c);
    EXPECT_EQ(c.too_old, 0) << "trial " << trial;
    EXPECT_EQ(c.processed, c0.processed) << "trial " << trial;
    ASSERT_TRUE(got == expected) << "trial " << trial << ": the canonical output differs from the in-order run";
  }
}

// A GPS receiver silent for 7 s (fusion.sensors.gps.period 1 s: said after 5 s of message time
// of the other inputs): one sensor_stopped and one sensor_resumed on FUSION_STATUS, the pose at
// the odometry's rate throughout; unwatched (the default), nothing is said.
TEST_F(HorizonTest, ASensorThatStopsIsSaidOnceAndThePoseGoesOn) {
  std::vector<Timed> silent;
  for (const Timed& t : inputs_)
    if (!(t.event.channel == "GPS" && t.utime >= 3000000 && t.utime < 10000000)) silent.push_back(t);
  ASSERT_LT(silent.size(), inputs_.size() - 5);
  auto run = [&](const app::SystemConfig& cfg, std::vector<lcmloc::fusion_status_t>& status) {
    bus::MemoryBus bus;
    runDaemon(cfg, silent, bus);
    status = bus.decoded<lcmloc::fusion_status_t>(cfg.channels.status);
    return bus.decoded<lcmloc::pose_t>(cfg.channels.pose);
  };
  app::SystemConfig watched = cfg_;
  watched.fusion.sensors["gps"].period = 1.0;
  std::vector<lcmloc::fusion_status_t> st, st_default;
  const auto poses = run(watched, st);
  std::vector<std::string> said;
  for (const auto& s : st)
    if (s.event == "sensor_stopped" || s.event == "sensor_resumed") said.push_back(s.event + " " + s.detail);
  ASSERT_EQ(said.size(), 2u);
  EXPECT_EQ(said[0].rfind("sensor_stopped GPS: no input since utime 2000000, 5.0", 0), 0u) << said[0];
  EXPECT_EQ(said[1], "sensor_resumed GPS: input again at utime 10000000 after none since utime 2000000");
  ASSERT_GT(poses.size(), 1000u);
  int64_t worst = 0;
  for (std::size_t i = 1; i < poses.size(); ++i) worst = std::max(worst, poses[i].utime - poses[i - 1].utime);
  EXPECT_LE(worst, 10000) << "a pose after every odometry message";
  EXPECT_GT(poses.back().utime, 11000000);
  const auto poses_default = run(cfg_, st_default);
  for (const auto& s : st_default) EXPECT_EQ(s.event.rfind("sensor_", 0), std::string::npos) << s.event;
  EXPECT_EQ(poses_default.size(), poses.size());
}

// fusion.sensors takes the channels key of every sensor input the daemon takes, and only those.
TEST(HorizonConfig, TheSensorKeysAreTheDaemonsInputKinds) {
  std::vector<std::string> kinds;
  fusion::forEachSensorInput([&](const auto& kind) { kinds.push_back(kind.name); });
  std::vector<std::string> keys = app::sensorKeys();
  std::sort(kinds.begin(), kinds.end());
  std::sort(keys.begin(), keys.end());
  EXPECT_EQ(kinds, keys);
}
