// lcmloc-launcher over real processes on loopback udpm: a hung child (SIGSTOP: no heartbeat) is
// found and stopped, non-critical children, the receive buffer the children's URL gets, an orderly
// stop on SIGTERM at start-up, configuration errors.
#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>
#include <thread>

#include "process_fixture.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/heartbeat_t.hpp"
#include "lcmloc/odometry_t.hpp"

using namespace std::chrono_literals;
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

class LauncherTest : public ProcessFixture {
 protected:
  void SetUp() override {
    ProcessFixture::SetUp();
    bus_ = std::make_unique<lcmloc::bus::Bus>(url_);
    bus_->subscribe<lcmloc::heartbeat_t>("HEARTBEAT", [this](const std::string&, const lcmloc::heartbeat_t& m, int64_t) {
      if (m.state == "running") pids_[m.process].insert(m.pid);
    });
  }

  /// Handles bus messages until pred() or the timeout; returns pred().
  bool waitFor(const std::function<bool()>& pred, std::chrono::milliseconds timeout) {
    const auto deadline = Clock::now() + timeout;
    while (!pred() && Clock::now() < deadline) bus_->handle(20);
    return pred();
  }

  /// Waits for the launcher to end (handling bus messages meanwhile).
  std::optional<int> waitExit(Child& launcher, std::chrono::milliseconds timeout) {
    std::optional<int> rc;
    const auto deadline = Clock::now() + timeout;
    while (!(rc = launcher.wait(0ms)) && Clock::now() < deadline) bus_->handle(20);
    return rc;
  }

  /// The pid of the first running heartbeat of process (0 when none within the timeout).
  int firstPid(const std::string& process, std::chrono::milliseconds timeout) {
    if (!waitFor([&] { return pids_.count(process) > 0; }, timeout)) return 0;
    return *pids_[process].begin();
  }

  std::string system(const std::string& head, const std::string& processes) {
    return writeFile("system.yaml", "scenario: " + std::string(LCMLOC_PAPER_YAML) + "\n" + head +
                                        "processes:\n" + processes);
  }

  /// A script that writes its arguments to name.args and sleeps (no heartbeat).
  std::string argsScript(const std::string& name) {
    const std::string f = writeFile(name + ".sh", "#!/bin/sh\necho \"$@\" > " + path(name + ".tmp") + "\nmv " +
                                                      path(name + ".tmp") + " " + path(name + ".args") +
                                                      "\nexec sleep 300\n");
    fs::permissions(f, fs::perms::owner_all);
    return f;
  }

  std::string waitRead(const std::string& file, std::chrono::milliseconds timeout) {
    const auto deadline = Clock::now() + timeout;
    while (!fs::exists(file) && Clock::now() < deadline) std::this_thread::sleep_for(10ms);
    std::ifstream in(file);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }

  std::unique_ptr<lcmloc::bus::Bus> bus_;
  std::map<std::string, std::set<int>> pids_;  // running heartbeats: process -> pids
};

}  // namespace

// A child stopped with SIGSTOP kept the launcher content for as long as it was left stopped (27 s
// in the audit): no heartbeat came and nothing was said. Now it is hung after heartbeat_timeout,
// stopped, and, being critical without restarts, ends the run with a failure.
TEST_F(LauncherTest, AHungChildIsFoundStoppedAndFailsTheRun) {
  const std::string sys =
      system("heartbeat_timeout: 2\nstop_timeout: 1\n", "  - {name: odometry, executable: " +
                                                            std::string(LCMLOC_ODOMETRY) + "}\n  - {name: magruler, "
                                                                                           "executable: " +
                                                            LCMLOC_MAGRULER + "}\n");
  Child launcher(LCMLOC_LAUNCHER, {"--system", sys, "--lcm-url", url_}, path("launcher.out"));
  const int pid = firstPid("lcmloc-odometry", 15s);
  ASSERT_GT(pid, 0) << launcher.output();
  ASSERT_GT(firstPid("lcmloc-magruler", 15s), 0) << launcher.output();
  ASSERT_EQ(::kill(pid, SIGSTOP), 0);
  const auto t0 = Clock::now();
  const auto rc = waitExit(launcher, 20s);
  const double took = std::chrono::duration<double>(Clock::now() - t0).count();
  ASSERT_TRUE(rc.has_value()) << "the launcher did not notice the hung child\n" << launcher.output();
  if (::kill(pid, 0) == 0) ::kill(pid, SIGKILL);
  EXPECT_EQ(*rc, 1) << launcher.output();
  const std::string out = launcher.output();
  EXPECT_NE(out.find("odometry (pid " + std::to_string(pid) + ") is hung: no heartbeat for "), std::string::npos) << out;
  EXPECT_NE(out.find("odometry ended unexpectedly (hung, no heartbeat for "), std::string::npos) << out;
  EXPECT_NE(out.find("FAILED"), std::string::npos) << out;
  // Heartbeats come once a second: found 1 to 2 s after the SIGSTOP (plus the launcher's 100 ms
  // polling), then stopped (SIGCONT lets it handle the SIGTERM) and the rest stopped.
  std::printf("hung child: launcher exited %.2f s after SIGSTOP (heartbeat_timeout 2 s)\n", took);
  EXPECT_GE(took, 0.5);  // not before heartbeat_timeout after the last heartbeat (<= ~1.1 s before the SIGSTOP)
  EXPECT_LE(took, 8.0) << out;
}

// With `restart` the hung child is started again and the run goes on.
TEST_F(LauncherTest, AHungChildWithRestartsIsStartedAgain) {
  const std::string sys = system("heartbeat_timeout: 2\nstop_timeout: 1\nrestart_delay: 0.2\n",
                                 "  - {name: odometry, executable: " + std::string(LCMLOC_ODOMETRY) + ", restart: 1}\n");
  Child launcher(LCMLOC_LAUNCHER, {"--system", sys, "--lcm-url", url_}, path("launcher.out"));
  const int pid = firstPid("lcmloc-odometry", 15s);
  ASSERT_GT(pid, 0) << launcher.output();
  ASSERT_EQ(::kill(pid, SIGSTOP), 0);
  ASSERT_TRUE(waitFor([&] { return pids_["lcmloc-odometry"].size() == 2; }, 15s)) << launcher.output();
  if (::kill(pid, 0) == 0) ::kill(pid, SIGKILL);
  launcher.signal(SIGINT);
  ASSERT_EQ(waitExit(launcher, 15s), std::optional<int>(0)) << launcher.output();
  const std::string out = launcher.output();
  EXPECT_NE(out.find("odometry ended unexpectedly (hung, no heartbeat for "), std::string::npos) << out;
  EXPECT_NE(out.find("starting it again in 0.2 s (1 of 1)"), std::string::npos) << out;
  EXPECT_NE(out.find("(started again 1 time(s))"), std::string::npos) << out;
}

// The logger's failure stopped the whole system. With `critical: false` it is reported, the rest
// runs to its end, and the launcher's exit status says a child failed.
TEST_F(LauncherTest, ANonCriticalChildFailsAndTheRestRunsOn) {
  const std::string scenario =
      writeFile("scenario.yaml", "scenario: {realtime_factor: 5}\nlogger: {output: " + path("run.lcmlog") + "}\n");
  const std::string sys = writeFile(
      "system.yaml", "scenario: scenario.yaml\nprocesses:\n  - {name: logger, executable: " + std::string(LCMLOC_LOGGER) +
                         ", critical: false}\n  - {name: odometry, executable: " + LCMLOC_ODOMETRY +
                         "}\n  - {name: sim, executable: " + LCMLOC_SIM + ", until_exit: true}\n");
  int64_t odometry = 0;
  bool logger_killed = false;
  int64_t odometry_after_kill = 0;
  // The launcher's own heartbeat shows the child given up, on the bus for a monitor.
  int64_t given_up = -1;
  bus_->subscribe<lcmloc::heartbeat_t>("HEARTBEAT", [&](const std::string&, const lcmloc::heartbeat_t& m, int64_t) {
    if (m.process != "lcmloc-launcher") return;
    for (int i = 0; i < m.num_counters; ++i)
      if (m.counter_names[static_cast<std::size_t>(i)] == "given_up") given_up = m.counters[static_cast<std::size_t>(i)];
  });
  bus_->subscribe<lcmloc::odometry_t>("ODOMETRY", [&](const std::string&, const lcmloc::odometry_t&, int64_t) {
    ++odometry;
    if (logger_killed) ++odometry_after_kill;
  });
  Child launcher(LCMLOC_LAUNCHER, {"--system", sys, "--lcm-url", url_}, path("launcher.out"));
  const int logger = firstPid("lcmloc-logger", 15s);
  ASSERT_GT(logger, 0) << launcher.output();
  ASSERT_TRUE(waitFor([&] { return odometry > 10; }, 20s)) << launcher.output();
  EXPECT_EQ(given_up, 0) << launcher.output();
  ASSERT_EQ(::kill(logger, SIGKILL), 0);
  logger_killed = true;
  EXPECT_TRUE(waitFor([&] { return given_up == 1; }, 5s)) << launcher.output();
  const auto rc = waitExit(launcher, 60s);
  ASSERT_TRUE(rc.has_value()) << launcher.output();
  EXPECT_EQ(*rc, 1) << launcher.output();
  const std::string out = launcher.output();
  EXPECT_NE(out.find("logger ended unexpectedly (killed by Killed); it is not critical (critical: false): the others "
                     "keep running WITHOUT it"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("sim finished; stopping the others"), std::string::npos) << out;
  EXPECT_NE(out.find("killed by Killed  FAILED (not critical)"), std::string::npos) << out;
  EXPECT_GT(odometry_after_kill, 100) << out;  // the run went on (about 14 s of 100 Hz at 5x)
}

// A non-critical child that fails during start-up does not keep the others from starting.
TEST_F(LauncherTest, ANonCriticalChildThatFailsAtStartUpIsSkipped) {
  const std::string sys = system("ready_timeout: 2\n", "  - {name: broken, executable: /bin/false, critical: false}\n"
                                                       "  - {name: odometry, executable: " +
                                                           std::string(LCMLOC_ODOMETRY) + "}\n");
  Child launcher(LCMLOC_LAUNCHER, {"--system", sys, "--lcm-url", url_}, path("launcher.out"));
  ASSERT_GT(firstPid("lcmloc-odometry", 15s), 0) << launcher.output();
  launcher.signal(SIGINT);
  ASSERT_EQ(waitExit(launcher, 15s), std::optional<int>(1)) << launcher.output();
  const std::string out = launcher.output();
  EXPECT_NE(out.find("broken ended during start-up (exit 1); it is not critical"), std::string::npos) << out;
  EXPECT_NE(out.find("exit 1  FAILED (not critical)"), std::string::npos) << out;
}

// A udpm URL without recv_buf_size went to the children as it was: the fusion daemon got the
// kernel's default receive buffer (3,875 messages lost in a 4 s stall against 21 with 4 MB).
TEST_F(LauncherTest, ChildrenGetAReceiveBufferUnlessTheUrlSetsOne) {
  const std::string bare = url_.substr(0, url_.find('&'));  // udpm://239.255.76.67:PORT?ttl=0
  ASSERT_EQ(bare.find("recv_buf_size"), std::string::npos);
  struct Case {
    std::string url, head, expected;
  };
  const std::vector<Case> cases{
      {bare, "", bare + "&recv_buf_size=4194304"},
      {bare, "recv_buf_size: 8388608\n", bare + "&recv_buf_size=8388608"},
      {bare + "&recv_buf_size=1048576", "", bare + "&recv_buf_size=1048576"},  // the user's value is kept
      {bare, "recv_buf_size: 0\n", bare},                                        // off: as given
  };
  for (const auto& c : cases) {
    fs::remove(path("one.args"));
    const std::string sys = system("ready_timeout: 0.1\n" + c.head, "  - {name: one, executable: " + argsScript("one") + "}\n");
    Child launcher(LCMLOC_LAUNCHER, {"--system", sys, "--lcm-url", c.url}, path("launcher.out"));
    const std::string args = waitRead(path("one.args"), 10s);
    launcher.signal(SIGINT);
    ASSERT_EQ(launcher.wait(10s), std::optional<int>(0)) << launcher.output();
    EXPECT_NE(args.find("--lcm-url " + c.expected + "\n"), std::string::npos) << c.url << " -> " << args;
    const bool added = c.expected != c.url;
    EXPECT_EQ(launcher.output().find("added to the LCM URL for every child") != std::string::npos, added)
        << launcher.output();
  }
}

// SIGTERM within about 10 ms of the start made the launcher exit 1 (the children it had not
// started yet counted as failed): a stop at any moment once it handles signals is orderly.
TEST_F(LauncherTest, SigtermRightAtStartUpIsAnOrderlyStop) {
  const std::string sys = system("ready_timeout: 5\n", "  - {name: one, executable: " + argsScript("one") +
                                                           "}\n  - {name: two, executable: " + argsScript("two") + "}\n");
  auto handlesSigterm = [](pid_t pid) {
    std::ifstream status("/proc/" + std::to_string(pid) + "/status");
    for (std::string line; std::getline(status, line);)
      if (line.rfind("SigCgt:", 0) == 0) return (std::stoull(line.substr(7), nullptr, 16) >> (SIGTERM - 1)) & 1;
    return 0ull;
  };
  for (int delay_ms : {0, 1, 2, 5, 10, 20}) {
    Child launcher(LCMLOC_LAUNCHER, {"--system", sys, "--lcm-url", url_}, path("launcher.out"));
    const auto deadline = Clock::now() + 5s;
    while (!handlesSigterm(launcher.pid()) && Clock::now() < deadline) std::this_thread::sleep_for(100us);
    ASSERT_TRUE(handlesSigterm(launcher.pid())) << launcher.output();
    std::this_thread::sleep_for(std::chrono::milliseconds(delay_ms));
    launcher.signal(SIGTERM);
    EXPECT_EQ(launcher.wait(15s), std::optional<int>(0)) << "SIGTERM " << delay_ms << " ms after its handler was set\n"
                                                         << launcher.output();
  }
}

TEST_F(LauncherTest, BadWatchSettingsAreConfigurationErrors) {
  const std::string child = "  - {name: odometry, executable: " + std::string(LCMLOC_ODOMETRY);
  struct Case {
    std::string head, processes, expected;
  };
  const std::vector<Case> cases{
      {"heartbeat_timeout: 1\n", child + "}\n", "heartbeat_timeout: 1 s is too short: 0 (off) or at least 2 s"},
      {"heartbeat_timeout: -1\n", child + "}\n", "heartbeat_timeout: value -1 out of range"},
      {"heartbeat_timout: 3\n", child + "}\n", "heartbeat_timout: unknown key"},
      {"recv_buf_size: 1000\n", child + "}\n", "recv_buf_size: 1000 bytes: 0 (URL as given) or at least 65536"},
      {"", child + ", critical: maybe}\n", "processes[0].critical"},
      {"", child + ", until_exit: true, critical: false}\n",
       "processes[0].critical: false with until_exit: true: the until_exit process ends the run, it must be critical"},
  };
  for (const auto& c : cases) {
    const std::string sys = system(c.head, c.processes);
    Child launcher(LCMLOC_LAUNCHER, {"--system", sys, "--lcm-url", url_}, path("launcher.out"));
    ASSERT_EQ(launcher.wait(10s), std::optional<int>(2)) << launcher.output();
    EXPECT_NE(launcher.output().find(sys + ": " + c.expected), std::string::npos) << launcher.output();
  }
}

// A child that crashes again and again soon after its start is started again after a delay that
// doubles each time, up to restart_delay_max, until its restarts are used up; then (not critical)
// the others run on without it.
TEST_F(LauncherTest, RestartsBackOffUpToTheLimit) {
  const std::string flaky = writeFile("flaky.sh", "#!/bin/sh\nsleep 0.3\nexit 3\n");
  const std::string world = writeFile("world.sh", "#!/bin/sh\nsleep 4\n");
  fs::permissions(flaky, fs::perms::owner_all);
  fs::permissions(world, fs::perms::owner_all);
  const std::string sys = system("ready_timeout: 0.1\nrestart_delay: 0.2\nrestart_delay_max: 0.5\n",
                                 "  - {name: flaky, executable: " + flaky + ", restart: 3, critical: false}\n"
                                 "  - {name: world, executable: " + world + ", until_exit: true}\n");
  Child launcher(LCMLOC_LAUNCHER, {"--system", sys, "--lcm-url", url_}, path("launcher.out"));
  const auto rc = waitExit(launcher, 30s);
  ASSERT_TRUE(rc.has_value()) << launcher.output();
  EXPECT_EQ(*rc, 1) << launcher.output();  // flaky failed for good
  const std::string out = launcher.output();
  for (const char* said : {"flaky ended unexpectedly (exit 3); starting it again in 0.2 s (1 of 3)",
                           "flaky ended unexpectedly (exit 3); starting it again in 0.4 s (2 of 3)",
                           "flaky ended unexpectedly (exit 3); starting it again in 0.5 s (3 of 3)",
                           "flaky ended unexpectedly (exit 3), restarted 3 time(s) already; it is not critical",
                           "world finished"})
    EXPECT_NE(out.find(said), std::string::npos) << said << "\n" << out;
}

// Bad system files and requests: a program that does not exist and a process with restart: 0
// (crashing) are each said and left, while the others run on; a duplicate process name is a
// configuration error naming both; `lcmloc-ctl proc` for a host that never answers says so.
TEST_F(LauncherTest, AMissingProgramARestartLimitOfZeroADuplicateNameAndASilentHostAreEachSaid) {
  const std::string crash = writeFile("crash.sh", "#!/bin/sh\nsleep 0.3\nexit 5\n");
  fs::permissions(crash, fs::perms::owner_all);
  const std::string sys = system("ready_timeout: 0.1\nrestart_delay: 0.2\n",
                                 "  - {name: ghost, executable: /nonexistent/lcmloc-ghost, critical: false}\n"
                                 "  - {name: crash, executable: " + crash + ", restart: 0, critical: false}\n"
                                 "  - {name: odometry, executable: " + std::string(LCMLOC_ODOMETRY) + "}\n");
  Child launcher(LCMLOC_LAUNCHER, {"--system", sys, "--lcm-url", url_}, path("launcher.out"));
  const int pid = firstPid("lcmloc-odometry", 15s);
  ASSERT_GT(pid, 0) << launcher.output();
  std::this_thread::sleep_for(1500ms);  // the crash, and no restart of it
  // lcmloc-ctl proc for a host no launcher runs on: no answer, said with the host.
  Child ctl(LCMLOC_CTL, {"proc", "restart", "odometry", "--host", "no-such-host", "--lcm-url", url_, "--timeout", "1.5"},
            path("ctl.out"));
  const auto ctl_rc = ctl.wait(15s);
  ASSERT_TRUE(ctl_rc.has_value()) << ctl.output();
  EXPECT_EQ(*ctl_rc, 4) << ctl.output();
  EXPECT_NE(ctl.output().find("no-such-host"), std::string::npos) << ctl.output();
  // The others ran on: the odometry driver is the same process all along.
  EXPECT_TRUE(waitFor([&] { return pids_["lcmloc-odometry"].size() == 1; }, 2s));
  EXPECT_EQ(::kill(pid, 0), 0) << "odometry driver still running";
  launcher.signal(SIGINT);
  ASSERT_EQ(waitExit(launcher, 15s), std::optional<int>(1)) << launcher.output();
  const std::string out = launcher.output();
  EXPECT_NE(out.find("ghost"), std::string::npos) << out;
  EXPECT_NE(out.find("/nonexistent/lcmloc-ghost"), std::string::npos) << out;
  EXPECT_NE(out.find("crash ended unexpectedly (exit 5)"), std::string::npos) << out;
  EXPECT_EQ(out.find("starting it again"), std::string::npos) << out;  // restart: 0

  // A duplicate name: a configuration error (exit 2) naming both entries.
  const std::string dup = system("", "  - {name: odometry, executable: " + std::string(LCMLOC_ODOMETRY) + "}\n" +
                                         "  - {name: odometry, executable: " + std::string(LCMLOC_MAGRULER) + "}\n");
  Child bad(LCMLOC_LAUNCHER, {"--system", dup, "--lcm-url", url_}, path("dup.out"));
  ASSERT_EQ(bad.wait(10s), std::optional<int>(2)) << bad.output();
  EXPECT_NE(bad.output().find("processes[1].name: 'odometry' is also the name of processes[0]"), std::string::npos)
      << bad.output();
}
