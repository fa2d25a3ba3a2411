// lcmloc-launcher: starts the processes of a system file as children (in list order, each once
// its heartbeat shows it running), watches them, starts a child that ended unexpectedly again
// when its `restart` allows, and stops them in reverse order when the until_exit process (the
// simulator) has finished, when a child fails for good, or on Ctrl-C. Exits non-zero if any
// child failed (in its last run).
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

#include "launch_config.hpp"
#include "lcmloc/common/config.hpp"
#include "lcmloc/common/process.hpp"
#include "lcmloc/heartbeat_t.hpp"

using namespace lcmloc;
using Clock = std::chrono::steady_clock;

namespace {

struct Child {
  launcher::ProcessSpec spec;
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

/// Ended by the SIGTERM of a stop (before it had set up its own handling of it): stopped.
bool stoppedBySigterm(const Child& c) {
  return c.terminated && !c.killed && WIFSIGNALED(c.status) && WTERMSIG(c.status) == SIGTERM;
}

std::string describeStatus(const Child& c) {
  if (c.running) return "still running";
  if (WIFEXITED(c.status)) return "exit " + std::to_string(WEXITSTATUS(c.status));
  if (stoppedBySigterm(c)) return "stopped by SIGTERM";
  if (WIFSIGNALED(c.status))
    return std::string("killed by ") + strsignal(WTERMSIG(c.status)) + (c.killed ? " (stop timeout)" : "");
  return "unknown";
}

bool failed(const Child& c) {
  if (stoppedBySigterm(c)) return false;
  return c.killed || !WIFEXITED(c.status) || WEXITSTATUS(c.status) != 0;
}

class Launcher {
 public:
  Launcher(launcher::LaunchConfig cfg, std::string scenario, std::string url)
      : cfg_(std::move(cfg)), scenario_(std::move(scenario)), url_(std::move(url)) {}

  int run() {
    const auto sys = common::loadSystemConfig(scenario_);  // validate before starting anything
    common::Bus bus(url_);
    // Only our own children's heartbeats count, from their start on: a heartbeat of another
    // process (on another host its pid may be any number) cannot make a child ready before it
    // is, and nothing is kept per pid seen.
    bus.subscribe<lcmloc::heartbeat_t>(sys.channels.heartbeat,
                                       [this](const std::string&, const lcmloc::heartbeat_t& m, int64_t) {
                                         if (m.state != "running") return;
                                         for (auto& c : children_)
                                           if (c.running && c.pid == m.pid) c.ready = true;
                                       });
    for (const auto& spec : cfg_.processes) {
      children_.emplace_back();
      children_.back().spec = spec;
    }

    bool ok = startAll(bus);
    std::optional<Clock::time_point> drain_until;
    while (ok && !common::stopRequested()) {
      bus.handle(100);
      for (auto& c : children_) {
        if (c.restart_at && Clock::now() >= *c.restart_at && !drain_until) restart(c);
        if (!reap(c, false)) continue;
        if (c.spec.until_exit && !failed(c)) {
          spdlog::info("{} finished; stopping the others in {:.1f} s", c.spec.name, cfg_.drain_time);
          drain_until = Clock::now() + secs(cfg_.drain_time);
        } else if (c.restarts < c.spec.restart && !drain_until) {
          spdlog::warn("{} ended unexpectedly ({}); starting it again in {:.1f} s ({} of {})", c.spec.name,
                       describeStatus(c), cfg_.restart_delay, c.restarts + 1, c.spec.restart);
          c.restart_at = Clock::now() + secs(cfg_.restart_delay);
        } else {
          spdlog::error("{} ended unexpectedly ({}){}", c.spec.name, describeStatus(c),
                        c.spec.restart ? fmt::format(", restarted {} time(s) already", c.restarts) : "");
          ok = false;
        }
      }
      if (drain_until && Clock::now() >= *drain_until) break;
    }
    if (common::stopRequested()) spdlog::info("stop requested (signal {}): stopping all", common::stopSignal());
    stopAll();
    return summary();
  }

 private:
  static Clock::duration secs(double s) {
    return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
  }

  bool startAll(common::Bus& bus) {
    for (auto& c : children_) {
      if (common::stopRequested()) return false;
      c.pid = spawn(c, scenario_, url_);
      c.running = true;
      c.ready = false;
      c.started = Clock::now();
      spdlog::info("started {} (pid {})", c.spec.name, c.pid);
      const auto deadline = Clock::now() + secs(cfg_.ready_timeout);
      while (!c.ready && Clock::now() < deadline && !common::stopRequested()) {
        bus.handle(50);
        if (reap(c, false)) {
          spdlog::error("{} ended during start-up ({})", c.spec.name, describeStatus(c));
          return false;
        }
      }
      if (!c.ready && cfg_.ready_timeout > 0)
        spdlog::warn("{}: no heartbeat within {:.1f} s; continuing", c.spec.name, cfg_.ready_timeout);
    }
    return true;
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
    c.runtime = std::chrono::duration<double>(Clock::now() - c.started).count();
    return true;
  }

  /// SIGTERM in reverse start order, each waited for (bounded) before the next, then SIGKILL.
  void stopAll() {
    for (auto it = children_.rbegin(); it != children_.rend(); ++it) {
      Child& c = *it;
      if (!c.running) continue;
      c.terminated = true;
      signalChild(c, SIGTERM);
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
    for (const auto& c : children_) {
      if (c.pid < 0) {
        spdlog::info("  {:<16} not started", c.spec.name);
        continue;
      }
      const bool bad = failed(c);
      any_failed |= bad;
      spdlog::info("  {:<16} pid {:<7} {:>7.2f} s  {}  {}{}", c.spec.name, c.pid, c.runtime, describeStatus(c),
                   bad ? "FAILED" : "ok", c.restarts ? fmt::format("  (started again {} time(s))", c.restarts) : "");
    }
    for (const auto& c : children_) any_failed |= (c.pid < 0);
    return any_failed ? common::kExitRuntimeError : common::kExitOk;
  }

  launcher::LaunchConfig cfg_;
  std::string scenario_, url_;
  std::vector<Child> children_;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-launcher: starts, watches (starting again those with `restart: N` that crash) and stops the "
               "processes of a system file"};
  common::CommonOptions opts;
  opts.config = "-";  // placeholder: the system file names the scenario unless --config is given
  common::addCommonOptions(app, opts);
  app.get_option("--config")->description("scenario YAML for every child (default: the system file's `scenario`)");
  std::string system = std::string(LCMLOC_CONFIG_DIR) + "/system.yaml";
  app.add_option("--system", system, "system file: processes to run")->capture_default_str();

  return common::runProcess(app, argc, argv, opts, "lcmloc-launcher", [&] {
    auto cfg = launcher::loadLaunchConfig(system);
    std::string scenario = opts.config != "-" ? opts.config : cfg.scenario;
    if (scenario.empty()) scenario = common::defaultConfigPath();
    scenario = std::filesystem::absolute(scenario).string();
    spdlog::info("system {}: {} processes, scenario {}, LCM {}", system, cfg.processes.size(), scenario,
                 opts.lcm_url);
    return Launcher(std::move(cfg), scenario, opts.lcm_url).run();
  });
}
