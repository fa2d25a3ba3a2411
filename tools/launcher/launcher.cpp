// lcmloc-launcher's work (see launcher.hpp).
#include "launcher.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <optional>
#include <thread>

#include <spdlog/spdlog.h>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/files.hpp"
#include "lcmloc/app/heartbeat.hpp"
#include "lcmloc/app/process_table.hpp"
#include "lcmloc/app/signals.hpp"
#include "lcmloc/app/text.hpp"
#include "lcmloc/bus/transport.hpp"
#include "child.hpp"
#include "lcmloc/heartbeat_t.hpp"
#include "lcmloc/process_command_t.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

namespace lcmloc::launcher {

namespace {

/// While a non-critical child is down for good, the launcher says so again this often.
constexpr double kNonCriticalReminder = 60.0;  // [s]

class Launcher {
 public:
  Launcher(LaunchConfig cfg, std::string scenario, std::string url)
      : cfg_(std::move(cfg)), scenario_(std::move(scenario)), url_(std::move(url)) {}
  ~Launcher() {
    std::error_code ec;
    if (own_run_dir_) std::filesystem::remove_all(run_dir_, ec);
  }

  int run() {
    const auto sys = simconfig::loadSimSystemConfig(scenario_);  // validate every section before starting anything
    for (const auto& spec : cfg_.processes) {
      children_.emplace_back();
      children_.back().spec = spec;
    }
    makeRunDir();
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
                                          [this](const std::string&, const lcmloc::heartbeat_t& m, int64_t recv) {
                                            table_.observe(m, recv);
                                            if (m.host != host_) return;
                                            for (auto& c : children_) {
                                              if (!c.running || c.pid != m.pid) continue;
                                              c.last_heartbeat = Clock::now();
                                              if (m.state == "running") c.ready = true;
                                            }
                                          });

    // Its own HEARTBEAT: a monitor (lcm-spy) sees the system's state, e.g. a non-critical child
    // given up, on the bus and not only in the launcher's log.
    if (bus) {
      hb_.emplace(*bus, sys.channels.heartbeat, "lcmloc-launcher", [this] { return counters(); });
      bus->subscribe<lcmloc::process_command_t>(
          cfg_.control_channel,
          [this](const std::string&, const lcmloc::process_command_t& m, int64_t) { command(m); });
    }
    bool ok = bus && startAll(*bus);
    std::optional<Clock::time_point> drain_until;
    auto last_pass = Clock::now();
    auto next_reminder = Clock::now() + secs(kNonCriticalReminder);
    auto next_table = Clock::now() + secs(cfg_.status_period);
    while (ok && !app::stopRequested()) {
      hb_->tick();
      bus->handle(100);
      if (answer_) {  // a command was applied: its heartbeat shows the new state at once
        hb_->publish("running");
        answer_ = false;
      }
      const auto now = Clock::now();
      if (cfg_.status_period > 0 && now >= next_table) {
        spdlog::info("status:\n{}", app::formatProcessTable(table_.rows()));
        next_table = now + secs(cfg_.status_period);
      }
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
        if (c.held) {
          spdlog::info("{} stopped on request ({})", c.spec.name, describeStatus(c));
        } else if (c.restart_requested && !drain_until) {
          c.restart_requested = false;
          spdlog::info("{} stopped on request ({}); starting it again", c.spec.name, describeStatus(c));
          start(c, "again on request");
        } else if (c.spec.until_exit && !failed(c)) {
          spdlog::info("{} finished; stopping the others in {:.1f} s", c.spec.name, cfg_.drain_time);
          drain_until = Clock::now() + secs(cfg_.drain_time);
        } else if (c.restarts < c.spec.restart && !drain_until) {
          const double delay = backoff(c);
          spdlog::warn("{} ended unexpectedly ({}); starting it again in {:.1f} s ({} of {})", c.spec.name,
                       describeStatus(c), delay, c.restarts + 1, c.spec.restart);
          c.restart_at = Clock::now() + secs(delay);
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

  void makeRunDir() {
    namespace fs = std::filesystem;
    run_dir_ = cfg_.run_dir;
    if (run_dir_.empty()) {
      run_dir_ = (fs::temp_directory_path() / ("lcmloc-launcher-" + std::to_string(::getpid()))).string();
      std::error_code ec;
      fs::remove_all(run_dir_, ec);  // (a launcher of the same pid before a reboot)
      own_run_dir_ = true;
    }
    std::error_code ec;
    fs::create_directories(run_dir_, ec);
    if (ec) throw app::ConfigError(cfg_.file, "run_dir", "cannot create " + run_dir_ + ": " + ec.message());
  }

  /// [s] before the next restart of c: restart_delay, doubled for each restart in a row after a
  /// run shorter than restart_delay_max, at most restart_delay_max.
  double backoff(Child& c) const {
    if (c.runtime >= cfg_.restart_delay_max) c.backoff = 0;
    const double delay = std::min(cfg_.restart_delay * std::pow(2.0, c.backoff), std::max(cfg_.restart_delay_max, cfg_.restart_delay));
    ++c.backoff;
    return delay;
  }

  /// A process_command_t: stop, start or restart one child by name.
  void command(const lcmloc::process_command_t& m) {
    if (!m.host.empty() && m.host != host_) return;
    auto it = std::find_if(children_.begin(), children_.end(), [&](const Child& c) { return c.spec.name == m.process; });
    if (it == children_.end()) {
      spdlog::warn("{}: no process named '{}' here ({} '{}' ignored)", cfg_.control_channel, app::printable(m.process),
                   app::printable(m.command), app::printable(m.process));
      return;
    }
    Child& c = *it;
    answer_ = true;
    if (m.command == "stop" || m.command == "restart") {
      c.restart_at.reset();
      if (!c.running) {
        if (m.command == "restart") {
          c.held = c.given_up = false;
          start(c, "again on request");
        } else {
          c.held = true;
        }
        return;
      }
      spdlog::info("{}: {} {} (pid {})", cfg_.control_channel, m.command, c.spec.name, c.pid);
      c.held = m.command == "stop";
      c.restart_requested = m.command == "restart";
      c.terminated = true;
      terminateChild(c);
      c.kill_at = Clock::now() + secs(cfg_.stop_timeout);
    } else if (m.command == "start") {
      if (c.running) return;
      c.held = c.given_up = false;
      c.restart_at.reset();
      start(c, "on request");
    } else {
      spdlog::warn("{}: unknown command '{}' (stop, start, restart)", cfg_.control_channel, app::printable(m.command));
      answer_ = false;
    }
  }

  bool startAll(bus::Bus& bus) {
    for (auto& c : children_) {
      if (app::stopRequested()) return false;
      c.pid = spawn(c, scenario_, url_, run_dir_);
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
  /// hung and stopped (SIGCONT and SIGTERM now, SIGKILL after stop_timeout); its end is then
  /// taken as a crash by the loop. A child that never sent a heartbeat (not an lcmloc process)
  /// is not watched (the start-up said so).
  void watch(Child& c) {
    if (!c.running) return;
    const auto now = Clock::now();
    if (c.kill_at && now >= *c.kill_at) {
      spdlog::error("{}{} did not stop within {:.1f} s of SIGTERM: SIGKILL", c.spec.name, c.hung ? " (hung)" : "",
                    cfg_.stop_timeout);
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
    ++c.restarts;
    start(c, fmt::format("again ({} of {})", c.restarts, c.spec.restart));
  }

  void start(Child& c, const std::string& how) {
    c.restart_at.reset();
    c.pid = spawn(c, scenario_, url_, run_dir_);
    c.running = true;
    c.ready = false;
    c.killed = false;
    c.terminated = false;
    c.hung = false;
    c.kill_at.reset();
    c.last_heartbeat.reset();
    c.warned_silent = false;
    c.started = Clock::now();
    spdlog::info("started {} {} (pid {})", c.spec.name, how, c.pid);
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

  /// SIGTERM (after a SIGCONT) in reverse start order, each waited for (bounded) before the next,
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
  std::string host_ = app::hostName();
  std::string run_dir_;
  bool own_run_dir_ = false;
  bool answer_ = false;  ///< a command changed a child: publish the heartbeat now
  app::ProcessTable table_;  ///< every heartbeat on the bus, for the status table
  /// The launcher's heartbeat counters: children in the system file, running now, failed for good
  /// (non-critical ones given up), started again so far.
  app::Heartbeat::Counters counters() const {
    int64_t running = 0, given_up = 0, restarts = 0;
    for (const auto& c : children_) {
      running += c.running;
      given_up += c.given_up;
      restarts += c.restarts;
    }
    app::Heartbeat::Counters out{{"children", static_cast<int64_t>(children_.size())}, {"running", running},
                                 {"given_up", given_up}, {"restarts", restarts}};
    for (const auto& c : children_)
      for (auto& kv : app::childCounters(c.spec.name, c.pid, state(c), c.restarts)) out.push_back(std::move(kv));
    return out;
  }

  static app::ProcState state(const Child& c) {
    using S = app::ProcState;
    if (c.running) return c.ready ? S::Running : S::Starting;
    if (c.restart_at) return S::Restarting;
    if (c.held) return S::Stopped;
    if (c.given_up || (c.pid > 0 && failed(c))) return S::Failed;
    return c.pid > 0 ? S::Exited : S::Starting;
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
