#pragma once
// A child of lcmloc-launcher: its state, and starting, signalling and describing it.
#include <sys/types.h>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

#include "launch_config.hpp"

namespace lcmloc::launcher {

using Clock = std::chrono::steady_clock;

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
  bool held = false;         ///< stopped on request (process_command_t "stop"): not started again
  bool restart_requested = false;  ///< stopped on request to be started again at once ("restart")
  int backoff = 0;           ///< restarts in a row after short runs: the next delay is restart_delay * 2^backoff
};


/// The executable's path: a bare name is looked up next to lcmloc-launcher, then in PATH.
std::string resolveExecutable(const std::string& exe);

/// The child's arguments with every "{run_dir}" replaced by run_dir.
std::vector<std::string> expandArgs(const std::vector<std::string>& args, const std::string& run_dir);

/// Starts the child (--config scenario --lcm-url url and its args) in a process group of its own.
pid_t spawn(const Child& c, const std::string& scenario, const std::string& url, const std::string& run_dir);

/// Sends sig to the child's process group (the child and what it started), or to the child
/// alone while it has no group yet.
void signalChild(const Child& c, int sig);

/// SIGCONT, then SIGTERM: a child stopped by SIGSTOP (or a debugger) goes on, handles the
/// SIGTERM and ends in order (the logger closes its file) instead of waiting for the SIGKILL.
void terminateChild(const Child& c);

/// Ended by the SIGTERM of a stop (before it had set up its own handling of it): stopped.
bool stoppedBySigterm(const Child& c);

std::string describeStatus(const Child& c);

bool failed(const Child& c);

}  // namespace lcmloc::launcher
