// Process tests: the real executables over udpm on loopback (a unique multicast port per test).
#include <gtest/gtest.h>

#include <cmath>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <set>

#include <lcm/lcm-cpp.hpp>

#include "process_fixture.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/fusion_control_t.hpp"
#include "lcmloc/fusion_status_t.hpp"
#include "lcmloc/ground_truth_t.hpp"
#include "lcmloc/heartbeat_t.hpp"
#include "lcmloc/odometry_t.hpp"
#include "lcmloc/pose_t.hpp"

using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {

const std::map<std::string, std::string> kExecutables{
    {"lcmloc-sim", LCMLOC_SIM}, {"lcmloc-odometry", LCMLOC_ODOMETRY}, {"lcmloc-magruler", LCMLOC_MAGRULER},
    {"lcmloc-fault-injector", LCMLOC_FAULT_INJECTOR}, {"lcmloc-fusion", LCMLOC_FUSION},
    {"lcmloc-logger", LCMLOC_LOGGER}, {"lcmloc-launcher", LCMLOC_LAUNCHER},
    // need no settings, but a bad --config is an error for them too (they ignored it)
    {"lcmloc-burst", LCMLOC_BURST}, {"lcmloc-magnet-grid", LCMLOC_MAGNET_GRID}};

/// A port no other test (in this run or a parallel one) uses.
class ProcessTest : public ProcessFixture {
 protected:
};

/// Handles bus messages until pred() or the timeout; returns pred().
bool waitFor(lcmloc::bus::Bus& bus, const std::function<bool()>& pred, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!pred() && std::chrono::steady_clock::now() < deadline) bus.handle(50);
  return pred();
}


int64_t seqOf(const std::vector<uint8_t>& d) {
  uint64_t v = 0;
  for (int i = 16; i < 24; ++i) v = (v << 8) | d[i];
  return static_cast<int64_t>(v);
}


}  // namespace

// ---------------------------------------------------------------------------------------------

TEST_F(ProcessTest, LauncherRunsTheSystemAndTheLogHasEveryChannelWithoutGaps) {
  const std::string log = path("run.lcmlog");
  // At ten times real time the default 50 ms reorder window is 5 ms of wall time: a process
  // that waits that long for a core (ctest -j2 on two cores) would deliver a message too late.
  // The window is widened to 50 ms of wall time; what is checked does not depend on it.
  const std::string scenario = writeFile(
      "scenario.yaml", "scenario: {realtime_factor: 10}\nfusion: {reorder_window: 0.5}\nlogger: {output: " + log + "}\n");
  Child launcher(LCMLOC_LAUNCHER, {"--system", LCMLOC_SYSTEM_YAML, "--config", scenario, "--lcm-url", url_},
                 path("launcher.out"));
  const auto rc = launcher.wait(90s);
  ASSERT_TRUE(rc.has_value()) << "launcher did not finish within 90 s\n" << launcher.output();
  ASSERT_EQ(*rc, 0) << launcher.output();

  const auto events = readLog(log);
  std::map<std::string, int64_t> count;
  std::map<std::string, std::vector<int64_t>> seqs;  // HEARTBEAT keyed per process
  std::vector<lcmloc::fusion_status_t> status;
  for (const auto& ev : events) {
    ++count[ev.channel];
    if (ev.channel == "LCM_SELF_TEST") continue;
    std::string key = ev.channel;
    if (ev.channel == "HEARTBEAT") key += "[" + decode<lcmloc::heartbeat_t>(ev).process + "]";
    if (ev.channel == "FUSION_STATUS") status.push_back(decode<lcmloc::fusion_status_t>(ev));
    seqs[key].push_back(seqOf(ev.data));
  }
  for (const char* ch : {"GROUND_TRUTH", "ODOMETRY", "MAGRULER", "MAGRULER_FAULT", "FAULT_EVENTS", "POSE", "GATE",
                         "FUSION_STATUS", "HEARTBEAT"})
    EXPECT_GT(count[ch], 0) << ch << " missing from the log";
  for (const auto& [key, s] : seqs) {
    for (std::size_t i = 1; i < s.size(); ++i)
      ASSERT_EQ(s[i], s[i - 1] + 1) << key << ": sequence gap or reorder at index " << i;
  }
  // Every process reported a heartbeat.
  for (const char* p : {"lcmloc-sim", "lcmloc-odometry", "lcmloc-magruler", "lcmloc-fault-injector",
                        "lcmloc-fusion", "lcmloc-logger"})
    EXPECT_TRUE(seqs.count(std::string("HEARTBEAT[") + p + "]")) << p;

  // The whole run, end to end: ground truth from its first sample, all 20 markers detected,
  // both faults injected and gated out, one pose per processed measurement, one gate decision
  // per ruler measurement, and the fusion's final status recorded (the logger stops last).
  EXPECT_EQ(seqs["GROUND_TRUTH"].front(), 0);
  EXPECT_GT(count["GROUND_TRUTH"], 2500);
  EXPECT_EQ(count["MAGRULER"], 20);
  EXPECT_EQ(count["MAGRULER_FAULT"], 2);
  EXPECT_EQ(count["FAULT_EVENTS"], 2);
  EXPECT_EQ(count["POSE"], count["ODOMETRY"] + count["MAGRULER"] + count["MAGRULER_FAULT"]);
  EXPECT_EQ(count["GATE"], count["MAGRULER"] + count["MAGRULER_FAULT"]);
  ASSERT_FALSE(status.empty());
  EXPECT_EQ(status.front().event, "started");
  EXPECT_EQ(status.back().event, "stopped");
  EXPECT_EQ(status.back().sequence_gaps, 0);
  EXPECT_EQ(status.back().messages_rejected, 0);
  EXPECT_EQ(status.back().messages_used, count["POSE"]);
}

// The simulator restarted while the drivers, the fault injector and the daemon keep running: the
// drivers' models start over with it (truth time went back), the daemon restarts its filter,
// and the second run's estimates and gate decisions equal the first run's.
TEST_F(ProcessTest, ARestartedSimulatorGivesTheSameEstimatesAgainWithoutRestartingTheRest) {
  const std::string scenario =
      writeFile("scenario.yaml", "scenario: {realtime_factor: 10}\nfusion: {reorder_window: 0.5}\n");
  lcmloc::bus::Bus bus(url_);
  std::map<std::string, std::set<int>> alive;  // process -> pids seen
  std::vector<lcmloc::pose_t> poses;
  std::vector<lcmloc::fusion_status_t> status;
  bus.subscribe<lcmloc::heartbeat_t>("HEARTBEAT", [&](const std::string&, const lcmloc::heartbeat_t& m, int64_t) {
    alive[m.process].insert(m.pid);
  });
  bus.subscribe<lcmloc::pose_t>("POSE", [&](const std::string&, const lcmloc::pose_t& m, int64_t) { poses.push_back(m); });
  bus.subscribe<lcmloc::fusion_status_t>(
      "FUSION_STATUS", [&](const std::string&, const lcmloc::fusion_status_t& m, int64_t) { status.push_back(m); });
  std::vector<std::unique_ptr<Child>> rest;
  for (const char* exe : {LCMLOC_FUSION, LCMLOC_ODOMETRY, LCMLOC_MAGRULER, LCMLOC_FAULT_INJECTOR})
    rest.push_back(std::make_unique<Child>(exe, std::vector<std::string>{"--lcm-url", url_, "--config", scenario},
                                           path(fs::path(exe).filename().string() + ".out")));
  ASSERT_TRUE(waitFor(bus, [&] { return alive.size() == 4; }, 10s));
  for (int run = 0; run < 2; ++run) {
    Child sim(LCMLOC_SIM, {"--lcm-url", url_, "--config", scenario}, path("sim.out"));
    std::optional<int> rc;
    const auto deadline = std::chrono::steady_clock::now() + 60s;
    while (!(rc = sim.wait(0ms)) && std::chrono::steady_clock::now() < deadline) bus.handle(20);
    ASSERT_EQ(rc.value_or(-1), 0) << sim.output();
  }
  for (auto& c : rest) c->signal(SIGTERM);
  ASSERT_TRUE(waitFor(bus, [&] { return !status.empty() && status.back().event == "stopped"; }, 10s))
      << rest[0]->output();
  for (auto& c : rest) EXPECT_EQ(c->wait(10s).value_or(-1), 0) << c->output();
  for (std::size_t i = 1; i < rest.size(); ++i)
    EXPECT_NE(rest[i]->output().find("the simulator started over; so does the sensor model"), std::string::npos)
        << rest[i]->output();
  int restarts = 0;
  for (const auto& st : status) restarts += st.event == "time_jump" && st.detail.find("time went back") != std::string::npos;
  EXPECT_EQ(restarts, 1);
  EXPECT_EQ(status.back().messages_rejected, 0);
  EXPECT_EQ(status.back().sequence_gaps, 0);
  EXPECT_EQ(status.back().messages_used, static_cast<int64_t>(poses.size()));
  ASSERT_GT(poses.size(), 5000u);
  ASSERT_EQ(poses.size() % 2, 0u);
  const std::size_t n = poses.size() / 2;
  for (std::size_t k = 0; k < n; ++k) {  // the same estimates (the output seq goes on)
    const auto& a = poses[k];
    const auto& b = poses[n + k];
    ASSERT_EQ(a.utime, b.utime) << k;
    ASSERT_EQ(a.status, b.status) << k;
    for (int i = 0; i < a.dim; ++i) ASSERT_EQ(a.state[i], b.state[i]) << k;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) ASSERT_EQ(a.covariance[i][j], b.covariance[i][j]) << k;
  }
}

TEST_F(ProcessTest, DaemonSurvivesBadInputAndReportsEachOnStatus) {
  Child daemon(LCMLOC_FUSION, {"--lcm-url", url_, "--config", LCMLOC_PAPER_YAML}, path("fusion.out"));
  lcmloc::bus::Bus bus(url_);
  bool ready = false;
  std::vector<lcmloc::fusion_status_t> status;
  int64_t last_pose_utime = -1;
  bus.subscribe<lcmloc::heartbeat_t>("HEARTBEAT", [&](const std::string&, const lcmloc::heartbeat_t& m, int64_t) {
    ready |= m.process == "lcmloc-fusion" && m.pid == daemon.pid();
  });
  bus.subscribe<lcmloc::fusion_status_t>(
      "FUSION_STATUS", [&](const std::string&, const lcmloc::fusion_status_t& m, int64_t) { status.push_back(m); });
  std::string last_pose_filter;
  bus.subscribe<lcmloc::pose_t>("POSE", [&](const std::string&, const lcmloc::pose_t& m, int64_t) {
    last_pose_utime = m.utime;
    last_pose_filter = m.filter;
  });
  ASSERT_TRUE(waitFor(bus, [&] { return ready; }, 10s)) << daemon.output();

  auto odo = [](int64_t seq, int64_t utime) {
    lcmloc::odometry_t m{};
    m.utime = utime;
    m.seq = seq;
    m.delta_s = 0.015;
    m.ticks = 15;
    m.steering = 0.0;
    m.has_steering = true;
    return m;
  };
  const int64_t t0 = 1000000, dt = 10000;
  int64_t seq = 0;
  for (; seq < 20; ++seq) bus.publish("ODOMETRY", odo(seq, t0 + seq * dt));
  ASSERT_TRUE(waitFor(bus, [&] { return last_pose_utime >= t0 + 10 * dt; }, 10s)) << daemon.output();

  const char garbage[] = "\x01\x02 not an odometry_t";
  bus.publishRaw("ODOMETRY", garbage, sizeof garbage);
  auto nan = odo(seq, t0 + seq * dt);
  nan.delta_s = std::nan("");
  bus.publish("ODOMETRY", nan);
  ++seq;
  bus.publish("ODOMETRY", odo(seq++, t0));  // older than the reorder window
  const int64_t resume = seq;
  // Control: a bad parameter is refused with the key named; a valid switch is acknowledged.
  lcmloc::fusion_control_t ctl{};
  ctl.utime = t0 + resume * dt;
  ctl.seq = 0;
  ctl.command = lcmloc::fusion_control_t::CMD_SWITCH_FILTER;
  ctl.filter = "ukf";
  ctl.parameters = "{bogus: 1}";
  bus.publish("FUSION_CONTROL", ctl);
  ctl.seq = 1;
  ctl.filter = "dead_reckoning";
  ctl.parameters = "";
  bus.publish("FUSION_CONTROL", ctl);
  for (; seq < resume + 20; ++seq) bus.publish("ODOMETRY", odo(seq, t0 + seq * dt));

  auto rejected = [&](const std::string& what) {
    for (const auto& s : status)
      if (s.event == "rejected_input" && s.detail.find(what) != std::string::npos) return true;
    return false;
  };
  EXPECT_TRUE(waitFor(bus, [&] { return last_pose_utime >= t0 + (resume + 10) * dt; }, 10s))
      << "the daemon stopped publishing after bad input\n" << daemon.output();
  EXPECT_TRUE(waitFor(bus, [&] { return rejected("cannot decode"); }, 5s)) << daemon.output();
  EXPECT_TRUE(rejected("delta_s is NaN")) << daemon.output();
  EXPECT_TRUE(rejected("too old")) << daemon.output();
  auto event = [&](const std::string& ev, const std::string& what) {
    for (const auto& st : status)
      if (st.event == ev && st.detail.find(what) != std::string::npos) return true;
    return false;
  };
  EXPECT_TRUE(event("refused", "FUSION_CONTROL: parameters.bogus: unknown key")) << daemon.output();
  EXPECT_TRUE(event("ack", "dead_reckoning")) << daemon.output();
  EXPECT_EQ(last_pose_filter, "dead_reckoning");
  // Everything older than the 50 ms reorder window is processed; the rest waits for the flush.
  const int64_t last_input = t0 + (seq - 1) * dt;
  ASSERT_TRUE(waitFor(bus, [&] { return last_pose_utime >= last_input - 60000; }, 10s)) << daemon.output();
  EXPECT_LT(last_pose_utime, last_input);

  daemon.signal(SIGTERM);
  const auto rc = daemon.wait(10s);
  ASSERT_TRUE(rc.has_value()) << "the daemon did not stop on SIGTERM";
  EXPECT_EQ(*rc, 0) << daemon.output();
  ASSERT_TRUE(waitFor(bus, [&] { return !status.empty() && status.back().event == "stopped"; }, 5s));
  EXPECT_EQ(status.back().messages_rejected, 3);
  EXPECT_EQ(status.back().sequence_gaps, 0);
  EXPECT_EQ(last_pose_utime, last_input);  // flushed on shutdown: the last input processed
  const std::string out = daemon.output();
  EXPECT_NE(out.find("rejected input: ODOMETRY: cannot decode"), std::string::npos) << out;
  EXPECT_NE(out.find("rejected input: ODOMETRY seq 20: delta_s is NaN"), std::string::npos) << out;
}

TEST_F(ProcessTest, LoggerFlushesOnSigtermAndReportsGaps) {
  const std::string log = path("gaps.lcmlog");
  Child logger(LCMLOC_LOGGER, {"--lcm-url", url_, "--config", LCMLOC_PAPER_YAML, "--output", log, "--channel",
                               "TEST_.*"},
               path("logger.out"));
  lcmloc::bus::Bus bus(url_);
  int64_t logger_received = -1;
  bus.subscribe<lcmloc::heartbeat_t>("HEARTBEAT", [&](const std::string&, const lcmloc::heartbeat_t& m, int64_t) {
    if (m.pid != logger.pid()) return;
    for (int i = 0; i < m.num_counters; ++i)
      if (m.counter_names[i] == "received") logger_received = m.counters[i];
  });
  ASSERT_TRUE(waitFor(bus, [&] { return logger_received >= 0; }, 10s)) << logger.output();
  for (int64_t seq : {0, 1, 2, 5}) {
    lcmloc::odometry_t m{};
    m.utime = 1000 + seq;
    m.seq = seq;
    bus.publish("TEST_ODOMETRY", m);
  }
  bus.publish("NOT_RECORDED", lcmloc::odometry_t{});
  ASSERT_TRUE(waitFor(bus, [&] { return logger_received >= 4; }, 10s)) << logger.output();

  logger.signal(SIGTERM);
  const auto rc = logger.wait(10s);
  ASSERT_TRUE(rc.has_value()) << "the logger did not stop on SIGTERM";
  EXPECT_EQ(*rc, 0) << logger.output();
  const auto events = readLog(log);
  ASSERT_EQ(events.size(), 4u) << logger.output();
  std::vector<int64_t> seqs;
  for (const auto& e : events) {
    EXPECT_EQ(e.channel, "TEST_ODOMETRY");
    seqs.push_back(seqOf(e.data));
  }
  EXPECT_EQ(seqs, (std::vector<int64_t>{0, 1, 2, 5}));
  const std::string out = logger.output();
  EXPECT_NE(out.find("TEST_ODOMETRY: 2 message(s) missing before seq 5"), std::string::npos) << out;
  EXPECT_NE(out.find("recorded 4 of 4 messages on 1 channels"), std::string::npos) << out;
  EXPECT_NE(out.find("2 sequence gaps"), std::string::npos) << out;
}

// A sensor driver (every one shares drivers::TruthDriver) counts every GROUND_TRUTH message
// missing, warns about the first five gaps only, and numbers its own output without gaps.
TEST_F(ProcessTest, DriverCountsEveryTruthGapWarnsAboutTheFirstFiveAndNumbersItsOutput) {
  Child driver(LCMLOC_ODOMETRY, {"--lcm-url", url_, "--config", LCMLOC_PAPER_YAML}, path("odometry.out"));
  lcmloc::bus::Bus bus(url_);
  std::map<std::string, int64_t> counters;
  std::string state;
  bus.subscribe<lcmloc::heartbeat_t>("HEARTBEAT", [&](const std::string&, const lcmloc::heartbeat_t& m, int64_t) {
    if (m.pid != driver.pid()) return;
    state = m.state;
    for (int i = 0; i < m.num_counters; ++i) counters[m.counter_names[i]] = m.counters[i];
  });
  std::vector<int64_t> out_seqs;
  bus.subscribe<lcmloc::odometry_t>("ODOMETRY", [&](const std::string&, const lcmloc::odometry_t& m, int64_t) {
    out_seqs.push_back(m.seq);
  });
  ASSERT_TRUE(waitFor(bus, [&] { return !state.empty(); }, 10s)) << driver.output();
  // 100 Hz truth along x at 1 m/s, every other message missing (seq 0, 2, 4, ...): 49 gaps of 1.
  for (int k = 0; k < 50; ++k) {
    lcmloc::ground_truth_t t{};
    t.seq = 2 * k;
    t.utime = 1000000 + 20000 * k;
    t.x = t.distance = 0.02 * k;
    t.speed = 1.0;
    bus.publish("GROUND_TRUTH", t);
    bus.handle(2);
  }
  ASSERT_TRUE(waitFor(bus, [&] { return counters["received"] == 50 && !out_seqs.empty(); }, 10s))
      << driver.output();
  driver.signal(SIGTERM);
  ASSERT_TRUE(waitFor(bus, [&] { return state == "stopping"; }, 10s)) << driver.output();
  EXPECT_EQ(driver.wait(10s).value_or(-1), 0) << driver.output();
  EXPECT_EQ(counters["gaps"], 49);
  EXPECT_EQ(counters["published"], static_cast<int64_t>(out_seqs.size()));
  for (std::size_t i = 0; i < out_seqs.size(); ++i) ASSERT_EQ(out_seqs[i], static_cast<int64_t>(i));
  const std::string out = driver.output();
  int warnings = 0;
  for (auto at = out.find("message(s) missing before seq"); at != std::string::npos;
       at = out.find("message(s) missing before seq", at + 1))
    ++warnings;
  EXPECT_EQ(warnings, 5) << out;
  EXPECT_NE(out.find("GROUND_TRUTH: 1 message(s) missing before seq 2"), std::string::npos) << out;
  EXPECT_NE(out.find("stopping: 50 ground-truth samples in, " + std::to_string(out_seqs.size()) +
                     " odometry out, 49 gaps"),
            std::string::npos)
      << out;
}

// A second recording into the same name (a logger run again, or started again by the launcher
// after a crash) keeps the first: it writes NAME-001 and says so; --overwrite replaces it.
TEST_F(ProcessTest, LoggerKeepsAnEarlierRecordingUnlessToldToOverwrite) {
  const std::string log = path("keep.lcmlog");
  lcmloc::bus::Bus bus(url_);
  auto record = [&](const std::vector<std::string>& extra, int64_t seq, const std::string& name) {
    std::vector<std::string> args{"--lcm-url", url_, "--config", LCMLOC_PAPER_YAML, "--output", log, "--channel", "TEST_.*"};
    args.insert(args.end(), extra.begin(), extra.end());
    Child logger(LCMLOC_LOGGER, args, path(name));
    int64_t received = -1;
    lcmloc::bus::Bus watch(url_);
    watch.subscribe<lcmloc::heartbeat_t>("HEARTBEAT", [&](const std::string&, const lcmloc::heartbeat_t& m, int64_t) {
      if (m.pid != logger.pid()) return;
      for (int i = 0; i < m.num_counters; ++i)
        if (m.counter_names[i] == "received") received = m.counters[i];
    });
    EXPECT_TRUE(waitFor(watch, [&] { return received >= 0; }, 10s)) << logger.output();
    lcmloc::odometry_t m{};
    m.seq = seq;
    bus.publish("TEST_ODOMETRY", m);
    EXPECT_TRUE(waitFor(watch, [&] { return received >= 1; }, 10s)) << logger.output();
    logger.signal(SIGTERM);
    EXPECT_EQ(logger.wait(10s).value_or(-1), 0) << logger.output();
    return logger.output();
  };
  record({}, 1, "first.out");
  const std::string second = record({}, 2, "second.out");
  const std::string kept = path("keep-001.lcmlog");
  EXPECT_NE(second.find(log + " exists (an earlier recording): writing " + kept + " instead"), std::string::npos)
      << second;
  ASSERT_EQ(readLog(log).size(), 1u);
  EXPECT_EQ(seqOf(readLog(log)[0].data), 1) << "the first recording is kept";
  ASSERT_EQ(readLog(kept).size(), 1u);
  EXPECT_EQ(seqOf(readLog(kept)[0].data), 2);
  record({"--overwrite"}, 3, "third.out");
  ASSERT_EQ(readLog(log).size(), 1u);
  EXPECT_EQ(seqOf(readLog(log)[0].data), 3) << "--overwrite replaces it";
}

TEST_F(ProcessTest, BadConfigExitsNonZeroNamingFileAndKey) {
  // name run with --config file exits 2 with a line that has what.
  const auto expectConfigError = [&](const std::string& name, const std::string& file, const std::string& what,
                                     const std::string& out) {
    Child c(kExecutables.at(name), {"--config", file, "--lcm-url", url_}, path(name + out));
    const auto rc = c.wait(10s);
    ASSERT_TRUE(rc.has_value()) << name;
    EXPECT_EQ(*rc, 2) << name << "\n" << c.output();
    EXPECT_NE(c.output().find(what), std::string::npos) << name << "\n" << c.output();
  };
  const std::string bad = writeFile("bad.yaml", "fusion:\n  filter:\n    bogus_key: 1\n");
  const std::string missing = path("does_not_exist.yaml");
  for (const auto& [name, exe] : kExecutables) {
    expectConfigError(name, bad, bad + ": fusion.filter.bogus_key: unknown key", ".bad.out");
    expectConfigError(name, missing, missing + ": cannot open config file", ".missing.out");
  }
  // The simulation's sections: refused by every program here that reads them (the daemon and the
  // logger take them unread, Config.TheProcessesReaderAcceptsTheSimulationSectionsUnread).
  const std::string bad_sim = writeFile("bad_sim.yaml", "vehicle:\n  wheelbas: 2.0\n");
  for (const char* name : {"lcmloc-sim", "lcmloc-odometry", "lcmloc-magruler", "lcmloc-fault-injector", "lcmloc-launcher"})
    expectConfigError(name, bad_sim, bad_sim + ": vehicle.wheelbas: unknown key", ".bad_sim.out");
  Child filter(LCMLOC_FUSION, {"--config", LCMLOC_PAPER_YAML, "--lcm-url", url_, "--filter", "kalman"},
               path("filter.out"));
  ASSERT_EQ(filter.wait(10s), std::optional<int>(2)) << filter.output();
  EXPECT_NE(filter.output().find("unknown filter type 'kalman'"), std::string::npos) << filter.output();
}

TEST_F(ProcessTest, EveryExecutableHasHelp) {
  for (const auto& [name, exe] : kExecutables) {
    Child c(exe, {"--help"}, path(name + ".help"));
    const auto rc = c.wait(10s);
    ASSERT_TRUE(rc.has_value()) << name;
    EXPECT_EQ(*rc, 0) << name;
    const std::string out = c.output();
    EXPECT_NE(out.find(name), std::string::npos) << out;
    for (const char* opt : {"--config", "--lcm-url", "--log-level"})
      EXPECT_NE(out.find(opt), std::string::npos) << name << " lacks " << opt;
    // A bad command line is a configuration error: exit 2 with CLI11's message.
    Child bad(exe, {"--no-such-option"}, path(name + ".bad-option"));
    EXPECT_EQ(bad.wait(10s), std::optional<int>(2)) << name << "\n" << bad.output();
    EXPECT_NE(bad.output().find("--no-such-option"), std::string::npos) << name << "\n" << bad.output();
  }
}

TEST_F(ProcessTest, NumericFlagsRefuseNaNInfOverflowAndValuesOutOfRange) {
  // NaN passes CLI11's range checks (every comparison with it is false) and was then taken as
  // "not given" or used; an integer beyond its type was clamped; a tiny --max-file-mb meant "no
  // size limit". Each is now a bad command line (exit 2) naming the option, in a short message.
  const std::vector<std::tuple<std::string, std::vector<std::string>, std::string>> cases{
      {LCMLOC_SIM, {"--realtime-factor", "nan"}, "--realtime-factor: nan is not a finite number"},
      {LCMLOC_SIM, {"--realtime-factor", "2e6"}, "--realtime-factor"},
      {LCMLOC_FUSION, {"--checkpoint-period", "inf"}, "--checkpoint-period: inf is not"},
      {LCMLOC_FUSION, {"--checkpoint-period", "0"}, "--checkpoint-period: 0 is not > 0"},
      {LCMLOC_FUSION, {"--init-from-bus", "-1"}, "--init-from-bus: -1 is not in [0, 86400]"},
      {LCMLOC_LOGGER, {"--max-file-mb", "1e-7"}, "--max-file-mb"},
      {LCMLOC_LOGGER, {"--flush-period", "nan"}, "--flush-period: nan is not a finite number"},
      {LCMLOC_LOGGER, {"--flush-period", "-inf"}, "--flush-period"},
      // A wall-clock wait beyond a day: 1e300 s overflowed the deadline's clock arithmetic.
      {LCMLOC_FUSION, {"--init-from-bus", "1e7"}, "--init-from-bus: 1e7 is not in [0, 86400]"},
  };
  for (const auto& [exe, args, expected] : cases) {
    std::vector<std::string> argv = args;
    argv.insert(argv.end(), {"--lcm-url", url_});
    Child c(exe, argv, path("flags.out"));
    ASSERT_EQ(c.wait(10s), std::optional<int>(2)) << exe << " " << args[0] << " " << args[1] << "\n" << c.output();
    EXPECT_NE(c.output().find(expected), std::string::npos) << c.output();
    EXPECT_LT(c.output().size(), 300u) << c.output();  // not the 300 digits of a double's range
  }
}

namespace {
/// Has process pid ended (gone, or a zombie waiting for its new parent)?
bool ended(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  if (!std::getline(stat, line)) return true;
  const auto close = line.rfind(')');
  return close != std::string::npos && close + 2 < line.size() && line[close + 2] == 'Z';
}
}  // namespace

TEST_F(ProcessTest, LauncherStopsAChildsWholeProcessGroupAndLeaksItNoDescriptors) {
  // A child (here a script that starts a background job) is stopped with its process group: the
  // launcher used to signal the child alone and leave its own children running. The child got the
  // launcher's LCM sockets and pipes. A child ended by the stop's SIGTERM (one that does not
  // handle it, or not yet) is stopped, not failed.
  const std::string script = writeFile("child.sh", "#!/bin/sh\nsleep 300 &\necho $! > " + path("sleep.pid") +
                                                       "\nfor f in /proc/$$/fd/*; do echo \"${f##*/} $(readlink $f)\"; "
                                                       "done > " + path("fds.txt") + ".tmp\nmv " + path("fds.txt") +
                                                       ".tmp " + path("fds.txt") + "\nwait\n");
  fs::permissions(script, fs::perms::owner_all);
  const std::string system =
      writeFile("system.yaml", "scenario: " + std::string(LCMLOC_PAPER_YAML) +
                                   "\nready_timeout: 0.1\nprocesses:\n  - {name: script, executable: " + script + "}\n");
  Child launcher(LCMLOC_LAUNCHER, {"--system", system, "--lcm-url", url_}, path("launcher.out"));
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (!fs::exists(path("fds.txt")) && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(20ms);
  ASSERT_TRUE(fs::exists(path("fds.txt"))) << launcher.output();
  pid_t sleeper = 0;
  std::ifstream(path("sleep.pid")) >> sleeper;
  ASSERT_GT(sleeper, 0);
  launcher.signal(SIGINT);
  EXPECT_EQ(launcher.wait(10s), std::optional<int>(0)) << launcher.output();
  EXPECT_NE(launcher.output().find("stopped by SIGTERM  ok"), std::string::npos) << launcher.output();
  const auto gone_by = std::chrono::steady_clock::now() + 5s;
  while (!ended(sleeper) && std::chrono::steady_clock::now() < gone_by) std::this_thread::sleep_for(20ms);
  EXPECT_TRUE(ended(sleeper)) << "the child's own child still runs";
  if (!ended(sleeper)) ::kill(sleeper, SIGKILL);
  std::ifstream fds(path("fds.txt"));
  for (std::string line; std::getline(fds, line);)
    EXPECT_EQ(line.find("socket:"), std::string::npos) << "inherited: " << line;
}

// The launcher kept every pid seen in any `running` heartbeat as ready, for good: a heartbeat of
// some other process (another host's pids are any numbers, or a forged one) with the pid a child
// was to get made that child "ready" the moment it started, and the map grew with every pid seen.
TEST_F(ProcessTest, LauncherTakesOnlyItsOwnChildrensHeartbeatsAsReady) {
  auto script = [&](const std::string& name) {
    const std::string f = writeFile(name + ".sh", "#!/bin/sh\necho $$ > " + path(name + ".tmp") + "\nmv " +
                                                      path(name + ".tmp") + " " + path(name + ".pid") +
                                                      "\nexec sleep 300\n");
    fs::permissions(f, fs::perms::owner_all);
    return f;
  };
  const std::string system = writeFile(
      "system.yaml", "scenario: " + std::string(LCMLOC_PAPER_YAML) + "\nready_timeout: 4\nprocesses:\n" +
                         "  - {name: one, executable: " + script("one") + "}\n" +
                         "  - {name: two, executable: " + script("two") + "}\n" +
                         "  - {name: three, executable: " + script("three") + "}\n");
  Child launcher(LCMLOC_LAUNCHER, {"--system", system, "--lcm-url", url_}, path("launcher.out"));
  auto waitFile = [&](const std::string& f, std::chrono::milliseconds t) {
    const auto deadline = std::chrono::steady_clock::now() + t;
    while (!fs::exists(f) && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(10ms);
    return fs::exists(f);
  };
  ASSERT_TRUE(waitFile(path("one.pid"), 10s)) << launcher.output();
  int one = 0, pid_max = 32768;
  std::ifstream(path("one.pid")) >> one;
  std::ifstream("/proc/sys/kernel/pid_max") >> pid_max;
  // While `one` (no heartbeat) is waited for: "running" heartbeats of other processes with the
  // next 30,000 pids (on this machine's pid_max of 32768: every pid), `two`'s among them.
  lcmloc::bus::Bus bus(url_);
  lcmloc::heartbeat_t hb{};
  hb.process = "lcmloc-elsewhere";
  hb.state = "running";
  for (int k = 1; k <= std::min(30000, pid_max - 2); ++k) {
    int pid = one + k;
    if (pid >= pid_max) pid -= pid_max - 300;  // (pids wrap around to 300)
    hb.pid = pid;
    ASSERT_TRUE(bus.publish("HEARTBEAT", hb));
    if (k % 500 == 0) std::this_thread::sleep_for(5ms);
  }
  ASSERT_FALSE(fs::exists(path("two.pid"))) << "published too late: two started already\n" << launcher.output();
  ASSERT_TRUE(waitFile(path("three.pid"), 20s)) << launcher.output();
  launcher.signal(SIGINT);
  EXPECT_EQ(launcher.wait(10s), std::optional<int>(0)) << launcher.output();
  const std::string out = launcher.output();
  EXPECT_NE(out.find("one: no heartbeat within 4.0 s"), std::string::npos) << out;
  EXPECT_NE(out.find("two: no heartbeat within 4.0 s"), std::string::npos) << out;
}

TEST_F(ProcessTest, LauncherRefusesTwoProcessesOfTheSameName) {
  // Unnamed processes are named after their executable: two magnetic rulers need names.
  const std::string system = writeFile("system.yaml", std::string("processes:\n") +
                                                          "  - {executable: " + LCMLOC_MAGRULER + "}\n" +
                                                          "  - {executable: " + LCMLOC_MAGRULER + "}\n");
  Child launcher(LCMLOC_LAUNCHER, {"--system", system, "--lcm-url", url_}, path("launcher.out"));
  EXPECT_EQ(launcher.wait(10s), std::optional<int>(2)) << launcher.output();
  EXPECT_NE(launcher.output().find("processes[1].name: '" + std::string(LCMLOC_MAGRULER) +
                                   "' is also the name of processes[0]"),
            std::string::npos)
      << launcher.output();
}

// A process with `restart` is started again when it crashes, while the others keep running: the
// fusion daemon, killed mid-run, comes back from its checkpoint and the run ends well.
TEST_F(ProcessTest, LauncherStartsACrashedProcessAgainAndTheDaemonGoesOnFromItsCheckpoint) {
  const std::string ck = path("fusion.ck");
  const std::string scenario =
      writeFile("scenario.yaml", "scenario: {realtime_factor: 5}\nfusion: {reorder_window: 0.5}\n");
  const std::string system = writeFile(
      "system.yaml", std::string("scenario: scenario.yaml\nrestart_delay: 0.2\nprocesses:\n") +
                         "  - {name: fusion, executable: " + LCMLOC_FUSION + ", args: [--checkpoint, " + ck +
                         ", --checkpoint-period, 0.1], restart: 1}\n" +
                         "  - {name: odometry, executable: " + LCMLOC_ODOMETRY + "}\n" +
                         "  - {name: sim, executable: " + LCMLOC_SIM + ", until_exit: true}\n");
  lcmloc::bus::Bus bus(url_);
  std::set<int> fusion_pids;
  std::vector<lcmloc::pose_t> poses;
  std::vector<lcmloc::fusion_status_t> status;
  bus.subscribe<lcmloc::heartbeat_t>("HEARTBEAT", [&](const std::string&, const lcmloc::heartbeat_t& m, int64_t) {
    if (m.process == "lcmloc-fusion" && m.state == "running") fusion_pids.insert(m.pid);
  });
  bus.subscribe<lcmloc::pose_t>("POSE", [&](const std::string&, const lcmloc::pose_t& m, int64_t) { poses.push_back(m); });
  bus.subscribe<lcmloc::fusion_status_t>(
      "FUSION_STATUS", [&](const std::string&, const lcmloc::fusion_status_t& m, int64_t) { status.push_back(m); });
  Child launcher(LCMLOC_LAUNCHER, {"--system", system, "--lcm-url", url_}, path("launcher.out"));
  // Once the first daemon has published for a while (and written its checkpoint), kill it.
  ASSERT_TRUE(waitFor(bus, [&] { return fusion_pids.size() == 1 && poses.size() > 1500 && fs::exists(ck); }, 30s))
      << launcher.output();
  const int first = *fusion_pids.begin();
  ASSERT_EQ(::kill(first, SIGKILL), 0);
  const std::size_t before = poses.size();
  const lcmloc::pose_t last = poses.back();
  ASSERT_TRUE(waitFor(bus, [&] { return fusion_pids.size() == 2 && poses.size() > before + 100; }, 30s))
      << launcher.output();
  std::optional<int> rc;
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  while (!(rc = launcher.wait(0ms)) && std::chrono::steady_clock::now() < deadline) bus.handle(20);
  ASSERT_EQ(rc.value_or(-1), 0) << launcher.output();
  const std::string out = launcher.output();
  EXPECT_NE(out.find("fusion ended unexpectedly (killed by Killed); starting it again in 0.2 s (1 of 1)"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("started fusion again"), std::string::npos) << out;
  EXPECT_NE(out.find("(started again 1 time(s))"), std::string::npos) << out;
  bool from_checkpoint = false;
  for (const auto& st : status)
    from_checkpoint |= st.event == "started" && st.detail.find("initialized from checkpoint") != std::string::npos;
  EXPECT_TRUE(from_checkpoint);
  bool gap_reported = false;  // the motion the daemon missed while down is reported as lost
  for (const auto& st : status)
    gap_reported |= st.event == "resume_gap" && st.detail.find("the motion in between was not seen") !=
                                                   std::string::npos;
  EXPECT_TRUE(gap_reported);
  // ... and bridged at the speed of its first odometry (1.5 m/s; one increment, 1 mm ticks: within
  // 0.1 m/s of it), not left behind.
  std::string bridge;
  for (const auto& st : status)
    if (st.event == "odometry_gap" && st.detail.find("since the state the filters started from") != std::string::npos)
      bridge = st.detail;
  const auto at = bridge.find("bridged at ");
  ASSERT_NE(at, std::string::npos) << bridge;
  EXPECT_NEAR(std::stod(bridge.substr(at + 11)), 1.5, 0.12) << bridge;
  // The second daemon went on from where the first was (its down time bridged, above:
  // at five times real time and 1.5 m/s, well under 10 m), not from the start of the path.
  const lcmloc::pose_t& resumed = poses[before];
  EXPECT_GT(resumed.utime, last.utime);
  EXPECT_LT(std::hypot(resumed.state[0] - last.state[0], resumed.state[1] - last.state[1]), 10.0);
  EXPECT_GT(std::hypot(resumed.state[0] - poses.front().state[0], resumed.state[1] - poses.front().state[1]), 10.0);
}

TEST_F(ProcessTest, LauncherFailsWhenAChildFailsAndStopsTheOthers) {
  const std::string log = path("fail.lcmlog");
  const std::string scenario = writeFile("scenario.yaml", "logger: {output: " + log + "}\n");
  const std::string system = writeFile("system.yaml", std::string("scenario: scenario.yaml\nprocesses:\n") +
                                                          "  - {name: logger, executable: " + LCMLOC_LOGGER + "}\n" +
                                                          "  - {name: broken, executable: /bin/false}\n");
  Child launcher(LCMLOC_LAUNCHER, {"--system", system, "--lcm-url", url_}, path("launcher.out"));
  const auto rc = launcher.wait(30s);
  ASSERT_TRUE(rc.has_value()) << launcher.output();
  EXPECT_EQ(*rc, 1) << launcher.output();
  const std::string out = launcher.output();
  EXPECT_NE(out.find("broken ended during start-up (exit 1)"), std::string::npos) << out;
  EXPECT_NE(out.find("exit 0  ok"), std::string::npos) << out;     // the logger, stopped cleanly
  EXPECT_NE(out.find("exit 1  FAILED"), std::string::npos) << out;  // the broken child
  EXPECT_TRUE(fs::exists(log));
}
