// lcmloc-launcher's work (see launcher.hpp).
#include "launcher.hpp"

#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <cstring>
#include <map>
#include <optional>
#include <thread>

#include <spdlog/spdlog.h>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/files.hpp"
#include "lcmloc/app/heartbeat.hpp"
#include "lcmloc/app/signals.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/heartbeat_t.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

namespace lcmloc::launcher {

using Clock = std::chrono::steady_clock;

namespace {

struct Child {
  ProcessSpec spec;
  pid_t pid = -1;
  bool running = false;
  bool ready = false;        ///< a `running` heartbeat with its pid came since it was started
  int status = 0;            ///< waitpid status once exited
  bool killed = false;       ///< needed SIGKILL
  bool terminated = false;   ///< sent SIGTERM by the launcher (a stop)
  Clock::time_point started;
  double runtime = 0.0;
  int restarts = 0;                         ///< times started again (ProcessSpec::restart)
  std::optional<Clock::time_point> restart_at;  ///< ended unexpectedly: to be started again then
  std::optional<Clock::time_point> last_heartbeat;  ///< of this run (any state, its pid)
  bool hung = false;         ///< stopped by the launcher: no heartbeat for heartbeat_timeout
  double silent_for = 0.0;   ///< [s] without a heartbeat when found hung
  std::optional<Clock::time_point> kill_at;  ///< hung and sent SIGTERM: SIGKILL then
  bool given_up = false;     ///< non-critical, failed for good: the others run without it
  bool warned_silent = false;  ///< (started again) no first heartbeat within ready_timeout, said
};

std::string resolveExecutable(const std::string& exe) {
  namespace fs = std::filesystem;
  if (exe.find('/') != std::string::npos) return exe;
  std::error_code ec;
  const auto self = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const auto sibling = self.parent_path() / exe;
    if (fs::exists(sibling)) return sibling.string();
  }
  return exe;  // execvp searches PATH
}

/// Starts the child in a process group of its own. Between fork and exec the child must not run
/// the launcher's signal handler (a SIGTERM would only set a flag in a copy about to be
/// replaced, and be lost): SIGINT/SIGTERM are blocked across fork and set back to their default
/// action in the child before they are unblocked, so such a signal ends the child (a stop).
/// The child gets none of the launcher's file descriptors (LCM sockets and pipes) and the
/// default action for the signals the launcher ignores.
pid_t spawn(const Child& c, const std::string& scenario, const std::string& url) {
  std::vector<std::string> args{resolveExecutable(c.spec.executable), "--config", scenario, "--lcm-url", url};
  args.insert(args.end(), c.spec.args.begin(), c.spec.args.end());
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  sigset_t stop_signals, before;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  ::sigprocmask(SIG_BLOCK, &stop_signals, &before);
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::setpgid(0, 0);                      // Ctrl-C reaches the launcher only: it stops us in order
    for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGPIPE, SIGXFSZ}) ::signal(sig, SIG_DFL);
    ::sigprocmask(SIG_SETMASK, &before, nullptr);
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);   // and we stop if the launcher dies
    if (::getppid() != parent) ::_exit(127);
    ::close_range(3, ~0U, 0);
    ::execvp(argv[0], argv.data());
    std::fprintf(stderr, "lcmloc-launcher: cannot execute %s: %s\n", argv[0], std::strerror(errno));
    ::_exit(127);
  }
  const int fork_errno = errno;
  if (pid > 0) ::setpgid(pid, pid);  // (also here: the group exists before we signal it)
  ::sigprocmask(SIG_SETMASK, &before, nullptr);
  if (pid < 0) throw std::runtime_error("fork failed for " + c.spec.name + ": " + std::strerror(fork_errno));
  return pid;
}

/// Sends sig to the child's process group (the child and what it started), or to the child
/// alone while it has no group yet.
void signalChild(const Child& c, int sig) {
  if (::kill(-c.pid, sig) != 0) ::kill(c.pid, sig);
}

/// SIGTERM, then SIGCONT: a child stopped by SIGSTOP (or a debugger) handles the SIGTERM and
/// ends in order (the logger closes its file) instead of waiting for the SIGKILL.
void terminateChild(const Child& c) {
  signalChild(c, SIGTERM);
  signalChild(c, SIGCONT);
}

/// Ended by the SIGTERM of a stop (before it had set up its own handling of it): stopped.
bool stoppedBySigterm(const Child& c) {
  return c.terminated && !c.killed && WIFSIGNALED(c.status) && WTERMSIG(c.status) == SIGTERM;
}

std::string describeStatus(const Child& c) {
  if (c.running) return "still running";
  const std::string hung = c.hung ? fmt::format("hung, no heartbeat for {:.1f} s; ", c.silent_for) : "";
  if (WIFEXITED(c.status)) return hung + "exit " + std::to_string(WEXITSTATUS(c.status));
  if (stoppedBySigterm(c)) return hung + "stopped by SIGTERM";
  if (WIFSIGNALED(c.status))
    return hung + std::string("killed by ") + strsignal(WTERMSIG(c.status)) + (c.killed ? " (stop timeout)" : "");
  return hung + "unknown";
}

bool failed(const Child& c) {
  if (c.hung) return true;
  if (stoppedBySigterm(c)) return false;
  return c.killed || !WIFEXITED(c.status) || WEXITSTATUS(c.status) != 0;
}

/// While a non-critical child is down for good, the launcher says so again this often.
constexpr double kNonCriticalReminder = 60.0;  // [s]

class Launcher {
 public:
  Launcher(LaunchConfig cfg, std::string scenario, std::string url)
      : cfg_(std::move(cfg)), scenario_(std::move(scenario)), url_(std::move(url)) {}

  int run() {
    const auto sys = simconfig::loadSimSystemConfig(scenario_);  // validate every section before starting anything
    for (const auto& spec : cfg_.processes) {
      children_.emplace_back();
      children_.back().spec = spec;
    }
    std::optional<bus::Bus> bus;
    try {
      bus.emplace(url_);
    } catch (const bus::TransportError&) {
      // A SIGTERM right at start-up interrupts LCM's start (its self-test): that is a stop.
      if (!app::stopRequested()) throw;
    }
    // Only our own children's heartbeats count, from their start on: a heartbeat of another
    // process (on another host its pid may be any number) cannot make a child ready before it
    // is, and nothing is kept per pid seen.
    if (bus)
      bus->subscribe<lcmloc::heartbeat_t>(sys.channels.heartbeat,
                                          [this](const std::string&, const lcmloc::heartbeat_t& m, int64_t) {
                                            for (auto& c : children_) {
                                              if (!c.running || c.pid != m.pid) continue;
                                              c.last_heartbeat = Clock::now();
                                              if (m.state == "running") c.ready = true;
                                            }
                                          });

    // Its own HEARTBEAT: a monitor (lcm-spy) sees the system's state, e.g. a non-critical child
    // given up, on the bus and not only in the launcher's log.
    if (bus)
      hb_.emplace(*bus, sys.channels.heartbeat, "lcmloc-launcher", [this] { return counters(); });
    bool ok = bus && startAll(*bus);
    std::optional<Clock::time_point> drain_until;
    auto last_pass = Clock::now();
    auto next_reminder = Clock::now() + secs(kNonCriticalReminder);
    while (ok && !app::stopRequested()) {
      hb_->tick();
      bus->handle(100);
      const auto now = Clock::now();
      // The launcher itself did not run (suspended, stopped, starved): its children's silence
      // meanwhile says nothing about them.
      if (cfg_.heartbeat_timeout > 0 && now - last_pass > secs(cfg_.heartbeat_timeout / 2)) {
        spdlog::warn("the launcher did not run for {:.1f} s: heartbeat clocks start again",
                     std::chrono::duration<double>(now - last_pass).count());
        for (auto& c : children_)
          if (c.last_heartbeat) c.last_heartbeat = now;
      }
      last_pass = now;
      for (auto& c : children_) {
        if (c.restart_at && Clock::now() >= *c.restart_at && !drain_until) restart(c);
        if (!reap(c, false)) {
          watch(c);
          continue;
        }
        if (c.spec.until_exit && !failed(c)) {
          spdlog::info("{} finished; stopping the others in {:.1f} s", c.spec.name, cfg_.drain_time);
          drain_until = Clock::now() + secs(cfg_.drain_time);
        } else if (c.restarts < c.spec.restart && !drain_until) {
          spdlog::warn("{} ended unexpectedly ({}); starting it again in {:.1f} s ({} of {})", c.spec.name,
                       describeStatus(c), cfg_.restart_delay, c.restarts + 1, c.spec.restart);
          c.restart_at = Clock::now() + secs(cfg_.restart_delay);
        } else if (!c.spec.critical) {
          giveUp(c, "ended unexpectedly (" + describeStatus(c) + ")" +
                        (c.spec.restart ? fmt::format(", restarted {} time(s) already", c.restarts) : ""));
        } else {
          spdlog::error("{} ended unexpectedly ({}){}", c.spec.name, describeStatus(c),
                        c.spec.restart ? fmt::format(", restarted {} time(s) already", c.restarts) : "");
          ok = false;
        }
      }
      if (Clock::now() >= next_reminder) {
        remindGivenUp();
        next_reminder = Clock::now() + secs(kNonCriticalReminder);
      }
      if (drain_until && Clock::now() >= *drain_until) break;
    }
    if (app::stopRequested()) spdlog::info("stop requested (signal {}): stopping all", app::stopSignal());
    if (hb_) hb_->publish("stopping");
    stopAll();
    return summary();
  }

 private:
  static Clock::duration secs(double s) {
    return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
  }

  bool startAll(bus::Bus& bus) {
    for (auto& c : children_) {
      if (app::stopRequested()) return false;
      c.pid = spawn(c, scenario_, url_);
      c.running = true;
      c.ready = false;
      c.started = Clock::now();
      spdlog::info("started {} (pid {})", c.spec.name, c.pid);
      const auto deadline = Clock::now() + secs(cfg_.ready_timeout);
      bool ended = false;
      while (!c.ready && Clock::now() < deadline && !app::stopRequested()) {
        hb_->tick();
        bus.handle(50);
        if ((ended = reap(c, false))) break;
      }
      if (ended) {
        if (c.spec.critical) {
          spdlog::error("{} ended during start-up ({})", c.spec.name, describeStatus(c));
          return false;
        }
        giveUp(c, "ended during start-up (" + describeStatus(c) + ")");
        continue;
      }
      if (!c.ready && cfg_.ready_timeout > 0 && !app::stopRequested())
        spdlog::warn("{}: no heartbeat within {:.1f} s; continuing{}", c.spec.name, cfg_.ready_timeout,
                     cfg_.heartbeat_timeout > 0 ? " (its heartbeat is watched from its first one on)" : "");
      c.warned_silent = true;
    }
    return true;
  }

  /// A non-critical child that failed for good: said loudly, and the others go on.
  void giveUp(Child& c, const std::string& what) {
    c.given_up = true;
    spdlog::error("{} {}; it is not critical (critical: false): the others keep running WITHOUT it, and the "
                  "launcher will exit non-zero",
                  c.spec.name, what);
  }

  void remindGivenUp() const {
    std::string names;
    for (const auto& c : children_)
      if (c.given_up) names += (names.empty() ? "" : ", ") + c.spec.name;
    if (!names.empty()) spdlog::error("still running without {} (failed; not critical)", names);
  }

  /// The liveness of a running child: silent for heartbeat_timeout after a heartbeat, it is
  /// hung and stopped (SIGTERM and SIGCONT now, SIGKILL after stop_timeout); its end is then
  /// taken as a crash by the loop. A child that never sent a heartbeat (not an lcmloc process)
  /// is not watched (the start-up said so).
  void watch(Child& c) {
    if (!c.running) return;
    const auto now = Clock::now();
    if (c.kill_at && now >= *c.kill_at) {
      spdlog::error("{} (hung) did not stop within {:.1f} s of SIGTERM: SIGKILL", c.spec.name, cfg_.stop_timeout);
      signalChild(c, SIGKILL);
      c.killed = true;
      c.kill_at.reset();
      return;
    }
    if (!c.last_heartbeat) {
      if (!c.warned_silent && cfg_.ready_timeout > 0 && now - c.started > secs(cfg_.ready_timeout)) {
        spdlog::warn("{}: no heartbeat within {:.1f} s of its start", c.spec.name, cfg_.ready_timeout);
        c.warned_silent = true;
      }
      return;
    }
    if (cfg_.heartbeat_timeout <= 0 || c.hung) return;
    const double silent = std::chrono::duration<double>(now - *c.last_heartbeat).count();
    if (silent <= cfg_.heartbeat_timeout) return;
    c.hung = true;
    c.silent_for = silent;
    spdlog::error("{} (pid {}) is hung: no heartbeat for {:.1f} s (heartbeat_timeout {:.1f} s); stopping it "
                  "(SIGTERM, SIGKILL after {:.1f} s) and taking it as crashed",
                  c.spec.name, c.pid, silent, cfg_.heartbeat_timeout, cfg_.stop_timeout);
    terminateChild(c);
    c.kill_at = now + secs(cfg_.stop_timeout);
  }

  /// Starts a child that ended unexpectedly again (its first heartbeat is not waited for: the
  /// others keep running meanwhile).
  void restart(Child& c) {
    c.restart_at.reset();
    ++c.restarts;
    c.pid = spawn(c, scenario_, url_);
    c.running = true;
    c.ready = false;
    c.killed = false;
    c.terminated = false;
    c.hung = false;
    c.kill_at.reset();
    c.last_heartbeat.reset();
    c.warned_silent = false;
    c.started = Clock::now();
    spdlog::info("started {} again (pid {}, {} of {})", c.spec.name, c.pid, c.restarts, c.spec.restart);
  }

  /// Collects the child's exit status if it has ended (blocking=false: just look).
  bool reap(Child& c, bool blocking) {
    if (!c.running) return false;
    int status = 0;
    const pid_t r = ::waitpid(c.pid, &status, blocking ? 0 : WNOHANG);
    if (r != c.pid) return false;
    c.running = false;
    c.status = status;
    c.kill_at.reset();
    c.runtime = std::chrono::duration<double>(Clock::now() - c.started).count();
    return true;
  }

  /// SIGTERM (and SIGCONT) in reverse start order, each waited for (bounded) before the next,
  /// then SIGKILL.
  void stopAll() {
    for (auto it = children_.rbegin(); it != children_.rend(); ++it) {
      Child& c = *it;
      if (!c.running) continue;
      c.terminated = true;
      terminateChild(c);
      const auto deadline = Clock::now() + secs(cfg_.stop_timeout);
      while (!reap(c, false) && Clock::now() < deadline)
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      if (c.running) {
        spdlog::error("{} did not stop within {:.1f} s: SIGKILL", c.spec.name, cfg_.stop_timeout);
        signalChild(c, SIGKILL);
        c.killed = true;
        reap(c, true);
      }
    }
  }

  int summary() const {
    bool any_failed = false;
    const bool stopped = app::stopRequested();
    for (const auto& c : children_) {
      if (c.pid < 0) {
        // (not started because of a stop request: nothing failed; because another failed: counted)
        spdlog::info("  {:<16} not started{}", c.spec.name, stopped ? " (stop requested)" : "");
        any_failed |= !stopped;
        continue;
      }
      const bool bad = failed(c);
      any_failed |= bad;
      spdlog::info("  {:<16} pid {:<7} {:>7.2f} s  {}  {}{}{}", c.spec.name, c.pid, c.runtime, describeStatus(c),
                   bad ? "FAILED" : "ok", bad && !c.spec.critical ? " (not critical)" : "",
                   c.restarts ? fmt::format("  (started again {} time(s))", c.restarts) : "");
    }
    return any_failed ? app::kExitRuntimeError : app::kExitOk;
  }

  LaunchConfig cfg_;
  std::string scenario_, url_;
  std::vector<Child> children_;
  std::optional<app::Heartbeat> hb_;
  /// The launcher's heartbeat counters: children in the system file, running now, failed for good
  /// (non-critical ones given up), started again so far.
  app::Heartbeat::Counters counters() const {
    int64_t running = 0, given_up = 0, restarts = 0;
    for (const auto& c : children_) {
      running += c.running;
      given_up += c.given_up;
      restarts += c.restarts;
    }
    return {{"children", static_cast<int64_t>(children_.size())}, {"running", running}, {"given_up", given_up},
            {"restarts", restarts}};
  }
};

}  // namespace

int run(LaunchConfig cfg, const std::string& scenario, const std::string& url) {
  return Launcher(std::move(cfg), scenario, url).run();
}

int launch(const std::string& system, const std::string& config, const std::string& lcm_url) {
  auto cfg = loadLaunchConfig(system);
  std::string scenario = !config.empty() ? config : cfg.scenario;
  if (scenario.empty()) scenario = app::defaultConfigPath();
  scenario = std::filesystem::absolute(scenario).string();
  const std::string url = bus::withReceiveBuffer(lcm_url, cfg.recv_buf_size);
  spdlog::info("system {}: {} processes, scenario {}, LCM {}", system, cfg.processes.size(), scenario, url);
  if (url != lcm_url)
    spdlog::info("recv_buf_size={} added to the LCM URL for every child (the kernel's default UDP receive buffer "
                 "drops bursts; a recv_buf_size in --lcm-url is kept; recv_buf_size: 0 in {} leaves the URL as "
                 "given)",
                 cfg.recv_buf_size, system);
  const long long asked = bus::receiveBufferOf(url), rmem_max = bus::kernelRmemMax();
  if (asked > 0 && rmem_max >= 0 && rmem_max < asked)
    spdlog::warn("the kernel caps UDP receive buffers at net.core.rmem_max = {} bytes, less than the "
                 "recv_buf_size={} asked for: bursts may be lost (LCM says so too); as root: sysctl -w "
                 "net.core.rmem_max={} (and in /etc/sysctl.d/ to keep it)",
                 rmem_max, asked, asked);
  return run(std::move(cfg), scenario, url);
}

}  // namespace lcmloc::launcher
