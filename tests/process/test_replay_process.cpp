// Replay and hot swap over real processes (udpm on loopback, a unique port per test):
// live == offline replay byte for byte (with control commands sent by lcmloc-ctl during the run
// and a shadow filter), lcm-logplayer into a daemon == offline replay and drops reported,
// process-level hand-over from the bus and from a checkpoint; GPS fixes delivered 200 ms late,
// fused within the horizon live as in the replay.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <map>
#include <thread>

#include <lcm/lcm-cpp.hpp>

#include "process_fixture.hpp"
#include "lcmloc/drivers/scenario_map.hpp"
#include "lcmloc/app/config.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/fusion_control_t.hpp"
#include "lcmloc/fusion_status_t.hpp"
#include "lcmloc/gate_decision_t.hpp"
#include "lcmloc/gps_fix_t.hpp"
#include "lcmloc/heartbeat_t.hpp"
#include "lcmloc/imu_t.hpp"
#include "lcmloc/odometry_t.hpp"
#include "lcmloc/pose_t.hpp"
#include "lcmloc/replay/replay.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

using namespace std::chrono_literals;
namespace fs = std::filesystem;
using lcmloc::bus::Bus;

namespace {

using Event = LogEvent;

/// Payloads per channel, in order.
std::map<std::string, std::vector<std::vector<uint8_t>>> byChannel(const std::vector<Event>& events) {
  std::map<std::string, std::vector<std::vector<uint8_t>>> out;
  for (const auto& e : events) out[e.channel].push_back(e.data);
  return out;
}

template <typename T>
T decode(const std::vector<uint8_t>& d) {
  T m;
  EXPECT_GE(m.decode(d.data(), 0, static_cast<int>(d.size())), 0);
  return m;
}

bool waitFor(Bus& bus, const std::function<bool()>& pred, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!pred() && std::chrono::steady_clock::now() < deadline) bus.handle(20);
  return pred();
}

/// First index where two payload sequences differ (or the shorter length), -1 if identical.
long firstDifference(const std::vector<std::vector<uint8_t>>& a, const std::vector<std::vector<uint8_t>>& b) {
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i)
    if (a[i] != b[i]) return static_cast<long>(i);
  return a.size() == b.size() ? -1 : static_cast<long>(std::min(a.size(), b.size()));
}

/// A test-side daemon watcher: heartbeats, POSE/GATE payloads and FUSION_STATUS messages.
struct Watch {
  explicit Watch(Bus& bus) {
    bus.subscribe<lcmloc::heartbeat_t>("HEARTBEAT", [this](const std::string&, const lcmloc::heartbeat_t& m, int64_t) {
      if (m.process == "lcmloc-fusion") alive[m.pid] = m.state;
    });
    bus.subscribe<lcmloc::fusion_status_t>(
        "FUSION_STATUS", [this](const std::string&, const lcmloc::fusion_status_t& m, int64_t) { status.push_back(m); });
    bus.subscribeRaw("(POSE|GATE)", [this](const std::string& ch, const uint8_t* d, std::size_t n, int64_t) {
      payloads[ch].emplace_back(d, d + n);
      if (ch == "POSE") poses.push_back(decode<lcmloc::pose_t>(payloads[ch].back()));
    });
  }
  bool has(const std::string& event, const std::string& what) const {
    for (const auto& s : status)
      if (s.event == event && s.detail.find(what) != std::string::npos) return true;
    return false;
  }
  std::map<int, std::string> alive;
  std::vector<lcmloc::fusion_status_t> status;
  std::map<std::string, std::vector<std::vector<uint8_t>>> payloads;
  std::vector<lcmloc::pose_t> poses;
};

class ReplayProcessTest : public ProcessFixture {
 protected:
  /// Runs lcmloc-replay and returns its output log's events.
  std::vector<Event> replay(const std::string& log, const std::string& config, const std::string& name) {
    Child r(LCMLOC_REPLAY, {log, "-o", path(name), "--overwrite", "--config", config}, path(name + ".out"));
    const auto rc = r.wait(60s);
    EXPECT_TRUE(rc.has_value());
    EXPECT_EQ(rc.value_or(-1), 0) << r.output();
    return readLog(path(name));
  }
  /// The scenario of a live launcher run at four times real time, recording into log.
  std::string liveScenario(const std::string& log, const std::string& fusion) {
    return writeFile("scenario.yaml",
                     "scenario: {realtime_factor: 4}\nlogger: {output: " + log + "}\nfusion: " + fusion + "\n");
  }
  /// Runs lcmloc-ctl with args against the daemon, keeping bus drained meanwhile; (exit code, output).
  std::pair<int, std::string> ctl(Bus& bus, const std::string& scenario, std::vector<std::string> args,
                                  const std::string& name) {
    std::vector<std::string> all{"--lcm-url", url_, "--config", scenario, "--timeout", "5"};
    all.insert(all.end(), args.begin(), args.end());
    Child c(LCMLOC_CTL, all, path(name));
    // Keep our own subscriptions drained while the ctl runs (its answer is on the bus too).
    const auto deadline = std::chrono::steady_clock::now() + 15s;
    std::optional<int> rc;
    while (!(rc = c.wait(0ms)) && std::chrono::steady_clock::now() < deadline) bus.handle(20);
    return {rc.value_or(-1), c.output()};
  }
  /// A config with the oval track's marker map, and a synthetic log of `seconds` on it (full.lcmlog).
  std::pair<std::string, std::string> ovalConfigAndLog(double seconds) {
    auto cfg = lcmloc::simconfig::loadSimSystemConfig(LCMLOC_PAPER_YAML);
    cfg.scenario = lcmloc::replay::ovalScenario(cfg.scenario, lcmloc::replay::OvalTrack{}, seconds);
    // The daemon and the replay need the oval's marker map: a config file with that path.
    std::string segs;
    for (const auto& s : cfg.scenario.path.segments)
      segs += (segs.empty() ? "" : ", ") + ("{length: " + std::to_string(s.length) + ", curvature: " +
                                            std::to_string(s.curvature) + "}");
    const std::string config = writeFile(
        "oval.yaml", "path: {segments: [" + segs + "]}\nmarkers: {count: " + std::to_string(cfg.scenario.markers.count) +
                         ", spacing: 2.0, first_at: 2.0}\nfusion: {shadow: [], map_file: oval_map.csv}\n");
    const auto loaded = lcmloc::simconfig::loadSimSystemConfig(config);
    lcmloc::drivers::writeScenarioMap(loaded, loaded.fusion.map_file);  // the daemon's map: the oval's markers
    const std::string log = path("full.lcmlog");
    lcmloc::replay::writeSyntheticLog(loaded.scenario, seconds, log, loaded.channels);
    return {config, log};
  }
  /// Writes events to a log file (in order; the timestamps as given).
  static void writeLog(const std::string& file, const std::vector<Event>& events) {
    lcm::LogFile out(file, "w");
    for (const auto& e : events) {
      lcm::LogEvent ev{0, e.timestamp, e.channel, static_cast<int32_t>(e.data.size()), const_cast<uint8_t*>(e.data.data())};
      out.writeEvent(&ev);
    }
  }
  /// Starts lcmloc-fusion with config, plays each log into it with lcm-logplayer -s 5 (one
  /// after the other), stops it with SIGTERM; w sees what it published.
  void playIntoDaemon(Bus& bus, const Watch& w, const std::string& config, const std::vector<std::string>& logs) {
    Child daemon(LCMLOC_FUSION, {"--lcm-url", url_, "--config", config}, path("fusion.out"));
    ASSERT_TRUE(waitFor(bus, [&] { return w.alive.count(daemon.pid()) > 0; }, 10s)) << daemon.output();
    for (const auto& log : logs) {
      Child player("/usr/bin/lcm-logplayer", {"--lcm-url=" + url_, "-s", "5", log}, path("player.out"));
      std::optional<int> prc;
      const auto deadline = std::chrono::steady_clock::now() + 30s;
      while (!(prc = player.wait(0ms)) && std::chrono::steady_clock::now() < deadline) bus.handle(20);
      ASSERT_EQ(prc.value_or(-1), 0) << player.output();
      // The player has sent everything, but its last datagrams may still be on their way through
      // the loopback device (delivered by a softirq: late on a loaded host), and a daemon stopped
      // (or a log played again) before they arrive never sees them; a loss at the end of a log
      // leaves no seq gap to tell. Wait until the daemon has published nothing for 300 ms (a pose
      // per input): it has taken in what was sent.
      std::size_t seen = w.poses.size();
      auto quiet_since = std::chrono::steady_clock::now();
      const auto settle_deadline = quiet_since + 10s;
      while (std::chrono::steady_clock::now() - quiet_since < 300ms &&
             std::chrono::steady_clock::now() < settle_deadline) {
        bus.handle(20);
        if (w.poses.size() != seen) {
          seen = w.poses.size();
          quiet_since = std::chrono::steady_clock::now();
        }
      }
    }
    daemon.signal(SIGTERM);
    ASSERT_TRUE(waitFor(bus, [&] { return !w.status.empty() && w.status.back().event == "stopped"; }, 10s))
        << daemon.output();
    EXPECT_EQ(daemon.wait(10s).value_or(-1), 0) << daemon.output();
    daemon_output_ = daemon.output();
  }
  std::string daemon_output_;  ///< of the last playIntoDaemon
  /// The daemon's outputs recorded live equal those of the offline replay of the same log.
  void expectLiveEqualsReplay(std::map<std::string, std::vector<std::vector<uint8_t>>>& live,
                              std::map<std::string, std::vector<std::vector<uint8_t>>>& offline) {
    for (const char* ch : {"POSE", "POSE_DEAD_RECKONING", "GATE", "FUSION_STATUS"}) {
      ASSERT_FALSE(live[ch].empty()) << ch;
      EXPECT_EQ(firstDifference(live[ch], offline[ch]), -1)
          << ch << ": live " << live[ch].size() << " vs replay " << offline[ch].size() << " messages";
    }
  }
};

lcmloc::odometry_t odo(int64_t seq, int64_t utime) {
  lcmloc::odometry_t m{};
  m.utime = utime;
  m.seq = seq;
  m.delta_s = 0.015;
  m.ticks = 15;
  m.steering = 0.01;
  m.has_steering = true;
  m.delta_theta = 0.015 * std::tan(0.01) / 2.5;
  return m;
}

}  // namespace

// The live system (launcher) with a shadow filter; lcmloc-ctl refuses an unknown filter and bad
// parameters and switches the filter during the run. Offline replay of the recorded log with the
// same config reproduces every POSE, POSE_DEAD_RECKONING, GATE and FUSION_STATUS byte for byte,
// including the switch at the same point.
TEST_F(ReplayProcessTest, LiveRunEqualsOfflineReplayByteForByteWithSwitchAndShadow) {
  const std::string log = path("run.lcmlog");
  const std::string scenario = liveScenario(log, "{shadow: [dead_reckoning]}");
  Bus bus(url_);
  Watch w(bus);
  Child launcher(LCMLOC_LAUNCHER, {"--system", LCMLOC_SYSTEM_YAML, "--config", scenario, "--lcm-url", url_},
                 path("launcher.out"));
  ASSERT_TRUE(waitFor(bus, [&] { return w.poses.size() > 300; }, 30s)) << launcher.output();

  const auto [rc_unknown, out_unknown] = ctl(bus, scenario, {"switch", "no_such_filter"}, "ctl1.out");
  EXPECT_EQ(rc_unknown, 5) << out_unknown;  // refused
  EXPECT_NE(out_unknown.find("refused: switch to 'no_such_filter'"), std::string::npos) << out_unknown;
  EXPECT_NE(out_unknown.find("unknown filter type"), std::string::npos) << out_unknown;
  const auto [rc_bad, out_bad] = ctl(bus, scenario, {"switch", "ukf", "--param", "pv_diag=[-1, 1]"}, "ctl2.out");
  EXPECT_EQ(rc_bad, 5) << out_bad;
  EXPECT_NE(out_bad.find("refused"), std::string::npos) << out_bad;
  EXPECT_EQ(w.poses.back().filter, "ukf_gated") << "the running filter continues after a refusal";
  const auto [rc_ok, out_ok] = ctl(bus, scenario, {"switch", "ukf_calib", "--param", "scale_std0=0.03"}, "ctl3.out");
  EXPECT_EQ(rc_ok, 0) << out_ok;
  EXPECT_NE(out_ok.find("ack: switched ukf_gated -> ukf_calib"), std::string::npos) << out_ok;

  const auto rc = launcher.wait(90s);
  ASSERT_TRUE(rc.has_value()) << launcher.output();
  ASSERT_EQ(*rc, 0) << launcher.output();
  auto live = byChannel(readLog(log));
  ASSERT_FALSE(live["POSE"].empty());
  EXPECT_EQ(decode<lcmloc::pose_t>(live["POSE"].back()).filter, "ukf_calib");
  ASSERT_EQ(live["FUSION_CONTROL"].size(), 3u) << "the logger records the commands";
  auto offline = byChannel(replay(log, scenario, "replay.lcmlog"));
  expectLiveEqualsReplay(live, offline);
  const auto last = decode<lcmloc::fusion_status_t>(live["FUSION_STATUS"].back());
  EXPECT_EQ(last.event, "stopped");
  EXPECT_EQ(last.sequence_gaps, 0);
  EXPECT_EQ(last.filter, "ukf_calib");
}

// fusion.output_every: 10 in the live daemon: the batched time update and the decimated poses are
// the engine's, so the live system and the offline replay of its log still agree byte for byte,
// a switch in the middle of a batch included (the batch is applied before the command).
TEST_F(ReplayProcessTest, LiveRunWithOutputEveryEqualsOfflineReplayByteForByte) {
  const std::string log = path("run.lcmlog");
  const std::string scenario = liveScenario(log, "{shadow: [dead_reckoning], output_every: 10}");
  Bus bus(url_);
  Watch w(bus);
  Child launcher(LCMLOC_LAUNCHER, {"--system", LCMLOC_SYSTEM_YAML, "--config", scenario, "--lcm-url", url_},
                 path("launcher.out"));
  ASSERT_TRUE(waitFor(bus, [&] { return w.poses.size() > 60; }, 30s)) << launcher.output();
  const auto [ctl_rc, ctl_out] = ctl(bus, scenario, {"switch", "ukf"}, "ctl.out");
  EXPECT_EQ(ctl_rc, 0) << ctl_out;

  const auto rc = launcher.wait(90s);
  ASSERT_TRUE(rc.has_value()) << launcher.output();
  ASSERT_EQ(*rc, 0) << launcher.output();
  auto live = byChannel(readLog(log));
  const std::size_t odometry = live["ODOMETRY"].size(), detections = live["MAGRULER"].size() + live["MAGRULER_FAULT"].size();
  ASSERT_GT(odometry, 1000u);
  // About one pose per ten odometry messages, plus one per detection and the final one.
  EXPECT_LE(live["POSE"].size(), odometry / 10 + detections + 2);
  EXPECT_GE(live["POSE"].size(), odometry / 10 + detections - 2);
  EXPECT_EQ(decode<lcmloc::pose_t>(live["POSE"].back()).filter, "ukf");
  auto offline = byChannel(replay(log, scenario, "replay.lcmlog"));
  expectLiveEqualsReplay(live, offline);
  EXPECT_EQ(decode<lcmloc::fusion_status_t>(live["FUSION_STATUS"].back()).sequence_gaps, 0);
}

// lcm-logplayer into a running daemon gives the offline replay's estimates byte for byte when
// nothing is lost; with events removed from the log, the daemon reports the gap on FUSION_STATUS
// (and still equals the offline replay of the same damaged input).
TEST_F(ReplayProcessTest, LogplayerIntoDaemonEqualsOfflineReplayAndDropsAreReported) {
  const auto [config, full] = ovalConfigAndLog(15.0);
  // The same log with ODOMETRY seq 500..504 removed.
  const std::string gapped = path("gapped.lcmlog");
  std::vector<Event> kept;
  for (auto& e : readLog(full))
    if (e.channel != "ODOMETRY" || decode<lcmloc::odometry_t>(e.data).seq < 500 ||
        decode<lcmloc::odometry_t>(e.data).seq >= 505)
      kept.push_back(std::move(e));
  writeLog(gapped, kept);

  for (const std::string& log : {full, gapped}) {
    SCOPED_TRACE(log);
    Bus bus(url_);
    Watch w(bus);
    playIntoDaemon(bus, w, config, {log});
    if (HasFatalFailure()) return;

    auto offline = byChannel(replay(log, config, "offline.lcmlog"));
    for (const char* ch : {"POSE", "GATE"}) {
      ASSERT_FALSE(offline[ch].empty());
      EXPECT_EQ(firstDifference(w.payloads[ch], offline[ch]), -1)
          << ch << ": live " << w.payloads[ch].size() << " vs replay " << offline[ch].size();
    }
    const auto offline_last = decode<lcmloc::fusion_status_t>(offline["FUSION_STATUS"].back());
    if (log == full) {
      EXPECT_EQ(w.status.back().sequence_gaps, 0);
      EXPECT_FALSE(w.has("drop", ""));
    } else {
      EXPECT_EQ(w.status.back().sequence_gaps, 5);
      EXPECT_TRUE(w.has("drop", "ODOMETRY: 5 message(s) missing before seq 505")) << daemon_output_;
      EXPECT_NE(daemon_output_.find("ODOMETRY: 5 message(s) missing before seq 505"), std::string::npos);
    }
    EXPECT_EQ(offline_last.sequence_gaps, w.status.back().sequence_gaps);
  }
}

// GPS fixes delivered 200 ms after their time (a receiver's latency), over real LCM: the golden
// GPS run's log with each fix moved after the odometry and IMU of the 200 ms that follow it,
// played by lcm-logplayer into a daemon whose horizon covers the delay
// (fusion.sensors.gps.delay 0.25 s). Every fix is fused, none is refused as late, and the live
// POSE and GATE are the offline replay's of the same log, byte for byte.
TEST_F(ReplayProcessTest, GpsFixesDelivered200msLateAreFusedLiveAsInTheReplay) {
  const std::string golden = LCMLOC_GOLDEN_DIR;
  std::vector<std::pair<Event, int64_t>> in;  // (event, its message time)
  for (auto& e : readLog(golden + "/gps.lcmlog")) {
    int64_t t = 0;
    if (e.channel == "ODOMETRY") t = decode<lcmloc::odometry_t>(e.data).utime;
    else if (e.channel == "IMU") t = decode<lcmloc::imu_t>(e.data).utime;
    else if (e.channel == "GPS") t = decode<lcmloc::gps_fix_t>(e.data).utime;
    else continue;
    in.emplace_back(std::move(e), t);
  }
  std::vector<Event> late;
  std::vector<std::pair<Event, int64_t>> waiting;
  int64_t arrival = 0;
  int fixes = 0;
  auto add = [&](Event e, int64_t t) {
    arrival = std::max(arrival, t);
    e.timestamp = arrival;  // lcm-logplayer paces by these: the fix goes out when it arrived
    late.push_back(std::move(e));
  };
  for (auto& [e, t] : in) {
    if (e.channel == "GPS") {
      ++fixes;
      waiting.emplace_back(std::move(e), t);
      continue;
    }
    while (!waiting.empty() && waiting.front().second + 200000 < t) {
      add(std::move(waiting.front().first), t);
      waiting.erase(waiting.begin());
    }
    add(std::move(e), t);
  }
  for (auto& [e, t] : waiting) add(std::move(e), arrival);
  ASSERT_GE(fixes, 10);
  const std::string log = path("late.lcmlog");
  writeLog(log, late);
  // The golden's config with the GPS delay.
  std::ifstream g(golden + "/gps.yaml");
  std::string text((std::istreambuf_iterator<char>(g)), std::istreambuf_iterator<char>());
  const auto at = text.find("\nfusion:\n");
  ASSERT_NE(at, std::string::npos);
  text.insert(at + 9, "  sensors: {gps: {delay: 0.25}}\n");
  const std::string config = writeFile("gps_late.yaml", text);

  Bus bus(url_);
  Watch w(bus);
  playIntoDaemon(bus, w, config, {log});
  if (HasFatalFailure()) return;
  auto offline = byChannel(replay(log, config, "offline.lcmlog"));
  for (const char* ch : {"POSE", "GATE"}) {
    ASSERT_GT(offline[ch].size(), static_cast<std::size_t>(fixes)) << ch;
    EXPECT_EQ(firstDifference(w.payloads[ch], offline[ch]), -1)
        << ch << ": live " << w.payloads[ch].size() << " vs replay " << offline[ch].size();
  }
  ASSERT_FALSE(w.status.empty());
  EXPECT_EQ(w.status.back().event, "stopped");
  EXPECT_EQ(w.status.back().detail.find("later than"), std::string::npos) << w.status.back().detail;
  int gps_decisions = 0;
  for (const auto& d : offline["GATE"]) gps_decisions += decode<lcmloc::gate_decision_t>(d).sensor == "GPS";
  EXPECT_GE(gps_decisions, fixes) << "each fix fused (decided by the filter and its shadow)";
}

// The same log played twice into one running daemon (as a restarted simulator would be): the
// second playing starts a time base in the past, the daemon restarts its filter and gives the
// first playing's estimates again instead of refusing every input as too old; offline replay of
// the two runs in one log gives the live outputs byte for byte.
TEST_F(ReplayProcessTest, ALogPlayedTwiceIntoARunningDaemonGivesTheSameEstimatesTwice) {
  const auto [config, full] = ovalConfigAndLog(10.0);
  const std::string twice = path("twice.lcmlog");
  std::vector<Event> events = readLog(full);
  const std::size_t n_events = events.size();
  for (std::size_t k = 0; k < n_events; ++k) {
    Event e = events[k];
    e.timestamp += 20000000;
    events.push_back(std::move(e));
  }
  writeLog(twice, events);
  Bus bus(url_);
  Watch w(bus);
  playIntoDaemon(bus, w, config, {full, full});
  if (HasFatalFailure()) return;

  EXPECT_TRUE(w.has("time_jump", "time went back")) << daemon_output_;
  EXPECT_TRUE(w.has("source_restart", "ODOMETRY: seq went back from")) << daemon_output_;
  int periodic[2] = {0, 0}, half = 0;  // periodic status reports before and after the restart
  for (const auto& st : w.status) {
    half += st.event == "time_jump";
    if (st.event == "periodic") ++periodic[std::min(half, 1)];
  }
  EXPECT_GT(periodic[0], 0);
  EXPECT_EQ(periodic[1], periodic[0]);
  EXPECT_FALSE(w.has("rejected_input", "")) << daemon_output_;
  EXPECT_EQ(w.status.back().messages_rejected, 0);
  // Every input of both playings reached the daemon (a datagram lost on the way would make the
  // halves differ for a reason that is not the daemon's).
  ASSERT_EQ(w.status.back().messages_in, static_cast<int64_t>(2 * n_events)) << daemon_output_;
  ASSERT_GT(w.poses.size(), 100u);
  ASSERT_EQ(w.poses.size() % 2, 0u);
  const std::size_t n = w.poses.size() / 2;
  for (std::size_t k = 0; k < n; ++k) {  // the same estimates (the output seq goes on)
    auto a = w.poses[k], b = w.poses[n + k];
    ASSERT_EQ(b.seq, a.seq + static_cast<int64_t>(n));
    a.seq = b.seq = 0;
    std::vector<uint8_t> ea(a.getEncodedSize()), eb(b.getEncodedSize());
    a.encode(ea.data(), 0, static_cast<int>(ea.size()));
    b.encode(eb.data(), 0, static_cast<int>(eb.size()));
    ASSERT_EQ(ea, eb) << "pose " << k << " of " << n;
  }
  auto offline = byChannel(replay(twice, config, "offline.lcmlog"));
  for (const char* ch : {"POSE", "GATE"}) {
    ASSERT_FALSE(offline[ch].empty());
    EXPECT_EQ(firstDifference(w.payloads[ch], offline[ch]), -1)
        << ch << ": live " << w.payloads[ch].size() << " vs replay " << offline[ch].size();
  }
}

// Process-level swap: a second daemon with another filter and --init-from-bus waits while the
// first runs, takes its last POSE when it stops and continues without a gap or jump; then a
// third daemon starts from the checkpoint the second wrote at exit.
TEST_F(ReplayProcessTest, HandOverFromTheBusAndFromACheckpoint) {
  Bus bus(url_);
  Watch w(bus);
  fs::create_directories(path("ck"));
  const std::string ck = path("ck/fusion.ck");
  Child a(LCMLOC_FUSION, {"--lcm-url", url_, "--config", LCMLOC_PAPER_YAML, "--filter", "ukf_gated"}, path("a.out"));
  ASSERT_TRUE(waitFor(bus, [&] { return w.alive.count(a.pid()) > 0; }, 10s)) << a.output();
  const int64_t t0 = 1000000, dt = 10000;
  int64_t seq = 0;
  auto publish = [&](int n) {
    for (int i = 0; i < n; ++i, ++seq) bus.publish("ODOMETRY", odo(seq, t0 + seq * dt));
  };
  publish(100);
  ASSERT_TRUE(waitFor(bus, [&] { return !w.poses.empty() && w.poses.back().utime >= t0 + 80 * dt; }, 10s));

  Child b(LCMLOC_FUSION, {"--lcm-url", url_, "--config", LCMLOC_PAPER_YAML, "--filter", "ukf", "--init-from-bus",
                          "20", "--checkpoint", ck},
          path("b.out"));
  ASSERT_TRUE(waitFor(bus, [&] { return w.alive.count(b.pid()) > 0; }, 10s)) << b.output();
  publish(50);  // both receive these; only A publishes
  ASSERT_TRUE(waitFor(bus, [&] { return w.poses.back().utime >= t0 + 140 * dt; }, 10s));
  a.signal(SIGTERM);
  ASSERT_EQ(a.wait(10s).value_or(-1), 0) << a.output();
  ASSERT_TRUE(waitFor(bus, [&] { return w.has("started", "initialized from the last POSE"); }, 10s)) << b.output();
  EXPECT_TRUE(w.has("started", "(filter ukf_gated)")) << b.output();
  ASSERT_EQ(w.poses.back().filter, "ukf_gated");
  const auto a_last = w.poses.back();
  EXPECT_EQ(a_last.utime, t0 + 149 * dt) << "A flushed everything on SIGTERM";
  const std::size_t a_count = w.poses.size();
  publish(50);
  ASSERT_TRUE(waitFor(bus, [&] { return w.poses.back().utime >= t0 + 190 * dt; }, 10s)) << b.output();
  const auto& b_first = w.poses[a_count];
  EXPECT_EQ(b_first.filter, "ukf");
  EXPECT_EQ(b_first.utime, t0 + 150 * dt) << "no gap: B's first pose is the first input after A's last";
  const double jump = std::hypot(b_first.state[0] - a_last.state[0], b_first.state[1] - a_last.state[1]);
  EXPECT_LT(jump, 0.02) << "one 15 mm odometry step, no jump";
  EXPECT_NEAR(b_first.covariance[0][0], a_last.covariance[0][0], 0.1 * a_last.covariance[0][0] + 1e-6);

  // B stops and writes its checkpoint; C (dead reckoning) starts from it.
  b.signal(SIGTERM);
  ASSERT_EQ(b.wait(10s).value_or(-1), 0) << b.output();
  ASSERT_TRUE(fs::exists(ck));
  ASSERT_TRUE(waitFor(bus, [&] { return w.status.back().event == "stopped"; }, 5s));
  const auto b_last = w.poses.back();
  EXPECT_EQ(b_last.utime, t0 + 199 * dt);
  Child c(LCMLOC_FUSION, {"--lcm-url", url_, "--config", LCMLOC_PAPER_YAML, "--filter", "dead_reckoning",
                          "--checkpoint", ck},
          path("c.out"));
  ASSERT_TRUE(waitFor(bus, [&] { return w.has("started", "initialized from checkpoint"); }, 10s)) << c.output();
  ASSERT_TRUE(waitFor(bus, [&] { return w.alive.count(c.pid()) > 0; }, 10s)) << c.output();
  const std::size_t b_count = w.poses.size();
  publish(20);
  ASSERT_TRUE(waitFor(bus, [&] { return w.poses.size() > b_count && w.poses.back().utime >= t0 + 210 * dt; }, 10s))
      << c.output();
  const auto& c_first = w.poses[b_count];
  EXPECT_EQ(c_first.filter, "dead_reckoning");
  EXPECT_EQ(c_first.utime, t0 + 200 * dt);
  EXPECT_LT(std::hypot(c_first.state[0] - b_last.state[0], c_first.state[1] - b_last.state[1]), 0.02);
  // The checkpoint's directory goes away: the failure is reported once, and the exit says so.
  fs::remove_all(path("ck"));
  std::this_thread::sleep_for(2500ms);  // two periodic writes fail
  c.signal(SIGTERM);
  EXPECT_EQ(c.wait(10s).value_or(-1), 1) << c.output();
  const std::string out = c.output();
  const auto first = out.find("checkpoint: cannot write");
  ASSERT_NE(first, std::string::npos) << out;
  EXPECT_EQ(out.find("checkpoint: cannot write", first + 1), std::string::npos) << "reported once\n" << out;
  EXPECT_NE(out.find("could not be written at exit"), std::string::npos) << out;

  // A checkpoint that cannot be written is refused at start-up (exit 2), not found out later.
  Child d(LCMLOC_FUSION, {"--lcm-url", url_, "--config", LCMLOC_PAPER_YAML, "--checkpoint", path("no/dir/ck")},
          path("d.out"));
  EXPECT_EQ(d.wait(10s).value_or(-1), 2) << d.output();
  EXPECT_NE(d.output().find("--checkpoint: cannot create"), std::string::npos) << d.output();

  // The hand-overs above went on with the next message: no resume gap was reported, and the
  // daemon handed over from was never taken for a second one on the bus.
  for (const auto& st : w.status) {
    EXPECT_NE(st.event, "resume_gap") << st.detail;
    EXPECT_NE(st.event, "foreign_output") << st.detail;
  }

  // A checkpoint of another time base (written at utime ~4.2 s; the source then started over at
  // 1 s): the new inputs are taken, not counted as already in the checkpoint.
  const std::string ck2 = path("ck2");
  {
    Child e(LCMLOC_FUSION, {"--lcm-url", url_, "--config", LCMLOC_PAPER_YAML, "--checkpoint", ck2}, path("e.out"));
    ASSERT_TRUE(waitFor(bus, [&] { return w.alive.count(e.pid()) > 0; }, 10s)) << e.output();
    seq = 300;
    publish(20);
    ASSERT_TRUE(waitFor(bus, [&] { return w.poses.back().utime >= t0 + 310 * dt; }, 10s)) << e.output();
    e.signal(SIGTERM);
    ASSERT_EQ(e.wait(10s).value_or(-1), 0) << e.output();
  }
  Child f(LCMLOC_FUSION, {"--lcm-url", url_, "--config", LCMLOC_PAPER_YAML, "--checkpoint", ck2}, path("f.out"));
  ASSERT_TRUE(waitFor(bus, [&] { return w.alive.count(f.pid()) > 0; }, 10s)) << f.output();
  const std::size_t e_count = w.poses.size();
  seq = 0;
  publish(20);  // utime 1.0 .. 1.19 s
  ASSERT_TRUE(waitFor(bus, [&] { return w.poses.size() > e_count && w.poses.back().utime >= t0 + 10 * dt; }, 10s))
      << f.output();
  EXPECT_EQ(w.poses[e_count].utime, t0);
  f.signal(SIGTERM);
  ASSERT_EQ(f.wait(10s).value_or(-1), 0) << f.output();

  // A hand-over that finds no POSE (a daemon started again after a crash, without --checkpoint)
  // starts from the configured initial state: a warning and a status event, not an info line.
  Child g(LCMLOC_FUSION, {"--lcm-url", url_, "--config", LCMLOC_PAPER_YAML, "--init-from-bus", "0.3"}, path("g.out"));
  ASSERT_TRUE(waitFor(bus, [&] { return w.has("no_handover", "no POSE on the bus within 0.3 s"); }, 10s))
      << g.output();
  EXPECT_TRUE(w.has("no_handover", "lcmloc-ctl set-pose")) << g.output();
  g.signal(SIGTERM);
  ASSERT_EQ(g.wait(10s).value_or(-1), 0) << g.output();
  EXPECT_NE(g.output().find("warning: no POSE on the bus within 0.3 s"), std::string::npos) << g.output();
}

// Several lcmloc-ctl at once: each is answered for its own command, and the sensors' time stays
// the daemon's time. All used to send seq 0 (duplicates of each other at one utime), to time their
// commands after each other's answers, climbing ahead of the odometry, which the daemon then
// rejected as too old while it restarted the filters.
TEST_F(ReplayProcessTest, SeveralCtlAtOnceAreEachAnsweredAndTheOdometryGoesOn) {
  Bus bus(url_);
  Watch w(bus);
  Child daemon(LCMLOC_FUSION, {"--lcm-url", url_, "--config", LCMLOC_PAPER_YAML}, path("fusion.out"));
  ASSERT_TRUE(waitFor(bus, [&] { return w.alive.count(daemon.pid()) > 0; }, 10s)) << daemon.output();
  const int64_t t0 = 1000000, dt = 10000;
  int64_t seq = 0;
  auto tick = [&] {  // 100 Hz of message time in real time
    bus.publish("ODOMETRY", odo(seq, t0 + seq * dt));
    ++seq;
    std::this_thread::sleep_for(10ms);
    bus.drain();
  };
  for (int i = 0; i < 50; ++i) tick();
  std::vector<std::unique_ptr<Child>> ctls;
  for (int i = 0; i < 6; ++i)
    ctls.push_back(std::make_unique<Child>(
        LCMLOC_CTL,
        std::vector<std::string>{"--lcm-url", url_, "--config", LCMLOC_PAPER_YAML, "--timeout", "5", "switch",
                                 i % 2 ? "ukf_gated" : "ukf"},
        path("ctl" + std::to_string(i) + ".out")));
  std::vector<std::optional<int>> rc(ctls.size());
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  auto running = [&] {
    bool any = false;
    for (std::size_t i = 0; i < ctls.size(); ++i)
      if (!rc[i] && !(rc[i] = ctls[i]->wait(0ms))) any = true;
    return any;
  };
  while (running() && std::chrono::steady_clock::now() < deadline) tick();
  for (int i = 0; i < 50; ++i) tick();
  for (std::size_t i = 0; i < ctls.size(); ++i) {
    EXPECT_EQ(rc[i].value_or(-1), 0) << ctls[i]->output();
    EXPECT_NE(ctls[i]->output().find("ack: switched "), std::string::npos) << ctls[i]->output();
  }
  daemon.signal(SIGTERM);
  ASSERT_EQ(daemon.wait(10s).value_or(-1), 0) << daemon.output();
  waitFor(bus, [&] { return !w.status.empty() && w.status.back().event == "stopped"; }, 5s);
  int acks = 0;
  for (const auto& st : w.status) {
    acks += st.event == "ack";
    EXPECT_NE(st.event, "rejected_input") << st.detail;
    EXPECT_NE(st.event, "time_jump") << st.detail;
    EXPECT_NE(st.event, "foreign_output") << st.detail;  // its own POSE coming back is not another's
  }
  EXPECT_EQ(acks, 6);
  ASSERT_FALSE(w.poses.empty());
  EXPECT_EQ(w.poses.back().utime, t0 + (seq - 1) * dt) << "every odometry message was used, the last one too";
  for (std::size_t i = 1; i < w.poses.size(); ++i) ASSERT_GE(w.poses[i].utime, w.poses[i - 1].utime);
}

// Two daemons on one bus: their POSE interleave (jumps of hundreds of metres on a vehicle), and
// nothing said so. Each now sees the other's POSE among its own and reports it.
TEST_F(ReplayProcessTest, TwoDaemonsOnOneBusEachReportTheOther) {
  // B with another filter (other states), then B a twin of A (the very same poses: each seq
  // comes twice).
  for (const std::string b_filter : {"dead_reckoning", "ukf_gated"}) {
    SCOPED_TRACE(b_filter);
    Bus bus(url_);
    Watch w(bus);
    Child a(LCMLOC_FUSION, {"--lcm-url", url_, "--config", LCMLOC_PAPER_YAML, "--filter", "ukf_gated"},
            path("a.out"));
    Child b(LCMLOC_FUSION, {"--lcm-url", url_, "--config", LCMLOC_PAPER_YAML, "--filter", b_filter}, path("b.out"));
    ASSERT_TRUE(waitFor(bus, [&] { return w.alive.count(a.pid()) > 0 && w.alive.count(b.pid()) > 0; }, 10s));
    const int64_t t0 = 1000000, dt = 10000;
    for (int64_t seq = 0; seq < 50; ++seq) {
      bus.publish("ODOMETRY", odo(seq, t0 + seq * dt));
      std::this_thread::sleep_for(5ms);
      bus.drain();
    }
    ASSERT_TRUE(waitFor(bus, [&] { return w.has("foreign_output", "another process publishes on POSE"); }, 10s));
    a.signal(SIGTERM);
    b.signal(SIGTERM);
    ASSERT_EQ(a.wait(10s).value_or(-1), 0) << a.output();
    ASSERT_EQ(b.wait(10s).value_or(-1), 0) << b.output();
    for (Child* c : {&a, &b})
      EXPECT_NE(c->output().find("warning: another process publishes on POSE"), std::string::npos) << c->output();
    EXPECT_NE(a.output().find("filter " + b_filter), std::string::npos) << "A names B's filter\n" << a.output();
  }
}

TEST_F(ReplayProcessTest, HelpAndCtlWithoutDaemonOrWithBadArguments) {
  for (const char* exe : {LCMLOC_REPLAY, LCMLOC_CTL}) {
    Child c(exe, {"--help"}, path("help.out"));
    EXPECT_EQ(c.wait(10s).value_or(-1), 0) << exe << c.output();
    EXPECT_NE(c.output().find("--config"), std::string::npos) << c.output();
  }
  Child none(LCMLOC_CTL, {"--lcm-url", url_, "--config", LCMLOC_PAPER_YAML, "--timeout", "0.5", "reset"},
             path("none.out"));
  EXPECT_EQ(none.wait(10s).value_or(-1), 1) << none.output();
  EXPECT_NE(none.output().find("is lcmloc-fusion running"), std::string::npos) << none.output();
  // The common options after the subcommand and its positionals, too (CLI11 took --timeout for a
  // fourth number of the pose: exit 2).
  Child after(LCMLOC_CTL, {"--lcm-url", url_, "set-pose", "1", "2", "0.5", "--timeout", "0.5", "--config",
                           LCMLOC_PAPER_YAML}, path("after.out"));
  EXPECT_EQ(after.wait(10s).value_or(-1), 1) << after.output();
  EXPECT_NE(after.output().find("within 0.5 s: is lcmloc-fusion running"), std::string::npos) << after.output();
  // A wall-clock wait beyond a day is refused (1e300 s overflowed the deadline's clock arithmetic).
  for (const auto& [exe, args, why] : std::vector<std::tuple<std::string, std::vector<std::string>, std::string>>{
           {LCMLOC_CTL, {"--timeout", "1e300", "reset"}, "--timeout: 1e300 is not in [0, 86400]"},
           {LCMLOC_REPLAY, {"--progress", "1e300", "x.lcmlog"}, "--progress: 1e300 is not in [0, 86400]"}}) {
    Child c(exe, args, path("day.out"));
    EXPECT_EQ(c.wait(10s).value_or(-1), 2) << c.output();
    EXPECT_NE(c.output().find(why), std::string::npos) << c.output();
  }
  Child bad(LCMLOC_CTL, {"--lcm-url", url_, "switch", "ukf", "--param", "novalue"}, path("bad.out"));
  EXPECT_EQ(bad.wait(10s).value_or(0), 2) << bad.output();  // bad arguments (it was 1)
  EXPECT_NE(bad.output().find("KEY=VALUE"), std::string::npos) << bad.output();
  for (const char* utime : {"99999999999999999999", "-5"}) {  // was clamped / taken as not given
    Child u(LCMLOC_CTL, {"--lcm-url", url_, "--utime", utime, "reset"}, path("utime.out"));
    EXPECT_EQ(u.wait(10s).value_or(0), 2) << u.output();
    EXPECT_NE(u.output().find("--utime"), std::string::npos) << u.output();
  }
  Child noout(LCMLOC_REPLAY, {"in.lcmlog", "--config", LCMLOC_PAPER_YAML}, path("noout.out"));
  EXPECT_EQ(noout.wait(10s).value_or(-1), 2) << noout.output();
  // A map file that cannot be read is a configuration error naming the key (it was exit 1 without).
  const std::string no_map = writeFile("no_map.yaml", "fusion: {map_file: /nonexistent/map.csv}\n");
  const std::string one_second = ovalConfigAndLog(1.0).second;
  Child map(LCMLOC_REPLAY, {one_second, "-o", path("o.lcmlog"), "--config", no_map}, path("map.out"));
  EXPECT_EQ(map.wait(10s).value_or(-1), 2) << map.output();
  EXPECT_NE(map.output().find("fusion.map_file: '/nonexistent/map.csv': cannot open"), std::string::npos)
      << map.output();
  // Two shadows of one type would both publish on POSE_UKF; --no-shadow beside --shadow was ignored.
  const std::pair<std::vector<std::string>, std::string> shadows[] = {
      {{"--shadow", "ukf,dead_reckoning,ukf"}, "--shadow: shadow[2]: 'ukf' is listed twice"},
      {{"--shadow", "ukf,bogus"}, "shadow[1]: unknown filter type 'bogus'"},
      {{"--shadow", "ukf", "--no-shadow"}, "excludes"}};
  for (const auto& [args, why] : shadows) {
    std::vector<std::string> all{"in.lcmlog", "-o", path("o.lcmlog"), "--config", LCMLOC_PAPER_YAML};
    all.insert(all.end(), args.begin(), args.end());
    Child c(LCMLOC_REPLAY, all, path("shadow.out"));
    EXPECT_EQ(c.wait(10s).value_or(-1), 2) << c.output();
    EXPECT_NE(c.output().find(why), std::string::npos) << c.output();
  }
}

TEST_F(ReplayProcessTest, CtlTakesOnlyTheAnswerToItsOwnCommandAndNoTimeBeyondInt64) {
  Bus bus(url_);
  // Runs lcmloc-ctl while publishing msg on channel every 20 ms; (exit code, output).
  auto ctlWhile = [&](const std::vector<std::string>& args, const std::string& channel, const auto& msg,
                      const std::string& name) {
    std::vector<std::string> all{"--lcm-url", url_, "--config", LCMLOC_PAPER_YAML, "--timeout", "1"};
    all.insert(all.end(), args.begin(), args.end());
    Child c(LCMLOC_CTL, all, path(name));
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    std::optional<int> rc;
    while (!(rc = c.wait(20ms)) && std::chrono::steady_clock::now() < deadline) bus.publish(channel, msg);
    return std::make_pair(rc.value_or(-1), c.output());
  };
  // A fake daemon: answers each command on FUSION_CONTROL with `answer` (its event and detail,
  // "{seq}" replaced by the command's seq), at the command's utime.
  lcmloc::fusion_status_t answer{};
  std::vector<lcmloc::fusion_control_t> commands;
  bus.subscribe<lcmloc::fusion_control_t>(
      "FUSION_CONTROL", [&](const std::string&, const lcmloc::fusion_control_t& m, int64_t) {
        commands.push_back(m);
        if (answer.event.empty()) return;
        lcmloc::fusion_status_t a = answer;
        a.utime = m.utime;
        const auto at = a.detail.find("{seq}");
        if (at != std::string::npos) a.detail.replace(at, 5, std::to_string(m.seq));
        bus.publish("FUSION_STATUS", a);
      });
  auto ctlAnswered = [&](const std::string& event, const std::string& detail, const std::string& name) {
    answer.event = event;
    answer.detail = detail;
    std::vector<std::string> all{"--lcm-url", url_, "--config", LCMLOC_PAPER_YAML, "--timeout", "1", "--utime",
                                 "5000000", "reset"};
    Child c(LCMLOC_CTL, all, path(name));
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    std::optional<int> rc;
    while (!(rc = c.wait(0ms)) && std::chrono::steady_clock::now() < deadline) bus.handle(20);
    return std::make_pair(rc.value_or(-1), c.output());
  };
  // An ack of another command, even at this command's time, is no answer to this one: it used to
  // exit 0 (several lcmloc-ctl at once all took the first ack).
  auto [rc, out] = ctlAnswered("ack", "FUSION_CONTROL seq 7: reset ukf_gated", "foreign_ack.out");
  EXPECT_EQ(rc, 4) << out;
  EXPECT_NE(out.find("no answer"), std::string::npos) << out;
  // Nor is the rejection of another FUSION_CONTROL input (it used to be taken: exit 3 with several
  // ctl at once, though this command was applied).
  std::tie(rc, out) = ctlAnswered("rejected_input", "too old: FUSION_CONTROL seq 0 utime 5000000: duplicate",
                                  "foreign_reject.out");
  EXPECT_EQ(rc, 4) << out;
  std::tie(rc, out) = ctlAnswered("rejected_input", "too old: FUSION_CONTROL seq {seq} utime 5000000: duplicate",
                                  "own_reject.out");
  EXPECT_EQ(rc, 5) << out;
  EXPECT_NE(out.find("rejected_input"), std::string::npos) << out;
  std::tie(rc, out) = ctlAnswered("ack", "FUSION_CONTROL seq {seq}: reset ukf_gated", "own_ack.out");
  EXPECT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("ack: reset ukf_gated (filter"), std::string::npos) << out;  // its own seq is not repeated
  // Each command has its own seq: two commands at one utime are not duplicates of each other.
  ASSERT_EQ(commands.size(), 4u);
  for (std::size_t i = 1; i < commands.size(); ++i) EXPECT_NE(commands[i].seq, commands[i - 1].seq);
  answer.event = "";  // (no more answers below: the commands there get none)
  // A POSE with a utime at the end of the int64 range: the command's time would overflow into a
  // negative one (it was sent at utime -9223372036854726808).
  lcmloc::pose_t pose{};
  pose.utime = std::numeric_limits<int64_t>::max() - 1000;
  pose.filter = "ukf_gated";
  std::tie(rc, out) = ctlWhile({"reset"}, "POSE", pose, "huge_utime.out");
  EXPECT_EQ(rc, 1) << out;
  EXPECT_NE(out.find("too close to the end of the int64 range"), std::string::npos) << out;
  EXPECT_EQ(out.find("sent to"), std::string::npos) << out;
  // A stray ODOMETRY an hour ahead of the daemon's POSE: the daemon holds it as a possible time
  // jump, so the command is timed after the POSE (5 s + the 50 ms reorder window), not after it.
  pose.utime = 5000000;
  lcmloc::odometry_t stray{};
  stray.utime = pose.utime + 3600000000LL;
  {
    Child c(LCMLOC_CTL, {"--lcm-url", url_, "--config", LCMLOC_PAPER_YAML, "--timeout", "1", "reset"},
            path("stray.out"));
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    std::optional<int> code;
    for (int i = 0; !(code = c.wait(20ms)) && std::chrono::steady_clock::now() < deadline; ++i) {
      bus.publish("ODOMETRY", stray);
      bus.publish("POSE", pose);
    }
    EXPECT_EQ(code.value_or(-1), 4) << c.output();  // no daemon to answer
    EXPECT_NE(c.output().find("sent to FUSION_CONTROL at utime 5050000 (seq "), std::string::npos) << c.output();
    EXPECT_NE(c.output().find("more than fusion.max_time_jump (1.000 s) ahead of the daemon's newest output "
                              "(utime 5000000)"), std::string::npos) << c.output();
  }
}

// --bench on a long log: SIGINT while the synthetic log is generated stops it at once and leaves
// no partial log behind (it went on for minutes, filling the disk); a kept log of another length
// or a damaged one is generated again instead of being measured as the requested one.
TEST_F(ReplayProcessTest, BenchStopsOnSigintAndChecksAKeptLog) {
  const std::string dir = path("bench");
  {
    Child c(LCMLOC_REPLAY, {"--bench", "--bench-duration", "86400", "--bench-dir", dir}, path("bench_int.out"));
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    while (c.output().find("generating 86400 s") == std::string::npos && std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(20ms);
    c.signal(SIGINT);  // generating a day of log takes minutes: the signal comes while it runs
    EXPECT_EQ(c.wait(10s).value_or(-1), 1) << c.output();
    EXPECT_NE(c.output().find("stopped while generating the synthetic log; the partial log is removed"),
              std::string::npos) << c.output();
    EXPECT_FALSE(std::filesystem::exists(dir + "/synthetic.lcmlog"));
  }
  auto bench = [&](const std::string& seconds, const std::string& name) {
    Child c(LCMLOC_REPLAY, {"--bench", "--bench-duration", seconds, "--bench-reps", "1", "--bench-dir", dir,
                            "--bench-keep-log"}, path(name));
    EXPECT_EQ(c.wait(60s).value_or(-1), 0) << c.output();
    return c.output();
  };
  const std::string first = bench("10", "b10.out");
  EXPECT_NE(first.find("generated 1000 odometry"), std::string::npos) << first;
  // The two-thread replay is measured against the one-thread one, and the aim judged on it.
  EXPECT_NE(first.find("ukf_gated, output_every 10, one thread"), std::string::npos) << first;
  EXPECT_NE(first.find("ukf_gated, output_every 10 / read+decode ="), std::string::npos) << first;
  EXPECT_EQ(first.find("one thread / read+decode"), std::string::npos) << first;
  std::string out = bench("10", "b10again.out");
  EXPECT_EQ(out.find("generat"), std::string::npos) << out;  // kept: the same length
  out = bench("20", "b20.out");
  EXPECT_NE(out.find("covers 9.990 s of message time, not the 20.000 s of --bench-duration: generating it again"),
            std::string::npos) << out;
  EXPECT_NE(out.find("generated 2000 odometry"), std::string::npos) << out;
  {
    std::ofstream junk(dir + "/synthetic.lcmlog", std::ios::binary | std::ios::trunc);
    junk << std::string(5000, '\x5a');
  }
  out = bench("20", "bjunk.out");
  EXPECT_NE(out.find("is damaged"), std::string::npos) << out;
  EXPECT_NE(out.find("generated 2000 odometry"), std::string::npos) << out;
  Child big(LCMLOC_REPLAY, {"--bench", "--bench-duration", "1e7", "--bench-dir", dir}, path("big.out"));
  EXPECT_EQ(big.wait(10s).value_or(-1), 2) << big.output();
  EXPECT_NE(big.output().find("1e7 s is more than a day"), std::string::npos) << big.output();
}

// The control pose (POSE_CONTROL) a running daemon publishes as each odometry message arrives is
// reproduced by the offline replay with --control, byte for byte, the log's event order standing
// for the order of arrival (lcm-logplayer sends in it); the canonical POSE is the same as without.
TEST_F(ReplayProcessTest, LiveControlPoseEqualsOfflineReplayWithControl) {
  const auto [config, log] = ovalConfigAndLog(8.0);
  Bus bus(url_);
  Watch w(bus);
  std::vector<std::vector<uint8_t>> live_control;
  bus.subscribeRaw("POSE_CONTROL", [&](const std::string&, const uint8_t* d, std::size_t n, int64_t) {
    live_control.emplace_back(d, d + n);
  });
  playIntoDaemon(bus, w, config, {log});
  if (HasFatalFailure()) return;

  Child r(LCMLOC_REPLAY, {log, "-o", path("control.lcmlog"), "--overwrite", "--config", config, "--control"},
          path("control.out"));
  ASSERT_EQ(r.wait(60s).value_or(-1), 0) << r.output();
  auto offline = byChannel(readLog(path("control.lcmlog")));
  auto plain = byChannel(replay(log, config, "plain.lcmlog"));
  ASSERT_GT(offline["POSE_CONTROL"].size(), 500u);
  EXPECT_EQ(firstDifference(live_control, offline["POSE_CONTROL"]), -1)
      << "live " << live_control.size() << " vs replay " << offline["POSE_CONTROL"].size();
  EXPECT_TRUE(plain["POSE_CONTROL"].empty());
  EXPECT_EQ(firstDifference(plain["POSE"], offline["POSE"]), -1);
  EXPECT_EQ(firstDifference(w.payloads["POSE"], offline["POSE"]), -1);
}
