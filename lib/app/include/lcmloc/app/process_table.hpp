#pragma once
// The processes of a running system as seen on the bus: every HEARTBEAT gathered per (host, pid),
// the launchers' own heartbeats naming their children (name, pid, state, restarts), message rates
// from heartbeat counters, and the clock offset of each host (heartbeat time against receive
// time). lcmloc-launcher prints it as its live status, lcmloc-ctl status from any host, and
// lcmloc-preflight takes the clock offsets from it.
#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "lcmloc/heartbeat_t.hpp"

namespace lcmloc::app {

/// A launcher's child as its heartbeat counters say (proc.<name>.pid/.state/.restarts).
enum class ProcState : int64_t { Starting = 1, Running = 2, Restarting = 3, Stopped = 4, Failed = 5, Exited = 6 };
const char* procStateName(ProcState s);

/// The launcher's heartbeat counters of one child (launcherCounters reads them back).
std::vector<std::pair<std::string, int64_t>> childCounters(const std::string& name, int64_t pid, ProcState state,
                                                           int64_t restarts);

struct ProcessRow {
  std::string name;         ///< the launcher's name of it, else the heartbeat's process
  std::string host;
  int64_t pid = -1;
  std::string state;        ///< the launcher's state, else the heartbeat's
  int64_t restarts = -1;    ///< -1: not under a launcher seen on the bus
  double cpu_percent = -1;  ///< -1: not known
  int64_t rss_bytes = -1;
  double rate_in = -1, rate_out = -1;  ///< [messages/s] from the counters received/in and published/written
  double age = -1;          ///< [s] since its last heartbeat; -1: none seen
};

struct HostClock {
  double offset = 0;  ///< [s] median of (receive time here - heartbeat time there): > 0 = that host is behind
  double spread = 0;  ///< [s] largest minus smallest sample
  int samples = 0;
};

class ProcessTable {
 public:
  using Clock = std::chrono::steady_clock;
  /// One heartbeat; recv_utime is the local wall-clock receive time [us] (LCM's).
  void observe(const lcmloc::heartbeat_t& m, int64_t recv_utime, Clock::time_point now = Clock::now());
  /// One row per process seen: the children of every launcher seen first (in its order), then
  /// the rest by host and name.
  std::vector<ProcessRow> rows(Clock::time_point now = Clock::now()) const;
  /// The clock offset of every host seen, by host name.
  std::map<std::string, HostClock> clocks() const;
  bool empty() const { return procs_.empty(); }

 private:
  struct Seen {
    lcmloc::heartbeat_t last, previous;
    bool has_previous = false;
    Clock::time_point at;
  };
  std::map<std::pair<std::string, int64_t>, Seen> procs_;  ///< by (host, pid)
  std::map<std::string, std::vector<double>> offsets_;     ///< by host [s], the latest kMaxSamples
  /// (host, pid) of every launcher child seen: once the launcher names another pid for it, the
  /// old one (crashed, stopped) is not shown as a process of its own.
  std::map<std::pair<std::string, int64_t>, bool> children_;
};

/// The table as text, one header line and one line per row.
std::string formatProcessTable(const std::vector<ProcessRow>& rows);

}  // namespace lcmloc::app
