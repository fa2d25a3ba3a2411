#pragma once
// The HEARTBEAT publisher of every process on the bus.
#include <chrono>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "lcmloc/bus/transport.hpp"

namespace lcmloc::app {

/// The name of this host in heartbeats: $LCMLOC_HOST if set and not empty (several "hosts" on one
/// machine: network namespaces, containers sharing a host name), else gethostname().
std::string hostName();

/// CPU time and resident memory of this process (/proc/self/stat and /proc/self/statm).
struct ProcessUsage {
  double cpu_seconds = -1.0;  ///< user + system CPU time [s]; < 0 = not known
  int64_t rss_bytes = -1;     ///< resident set size [bytes]; < 0 = not known
};
ProcessUsage processUsage();

/// Publishes heartbeat_t on the heartbeat channel once per wall second (and at the first tick),
/// with the host, the CPU use since the previous heartbeat and the resident memory.
class Heartbeat {
 public:
  using Counters = std::vector<std::pair<std::string, int64_t>>;
  /// [s] between two heartbeats (lcmloc-launcher's heartbeat_timeout is at least twice this).
  static constexpr double kPeriodSeconds = 1.0;
  Heartbeat(bus::MessageBus& bus, std::string channel, std::string process,
            std::function<Counters()> counters = nullptr);
  /// Publishes if a second of wall time has passed since the last heartbeat (or none was sent).
  void tick();
  /// Publishes now with the given state ("starting", "running", "stopping").
  void publish(const std::string& state);
 private:
  bus::MessageBus& bus_;
  std::string channel_, process_, host_;
  double last_cpu_ = -1.0;  ///< [s] CPU time at the previous heartbeat
  std::function<Counters()> counters_;
  int64_t seq_ = 0;
  std::chrono::steady_clock::time_point last_{};
  bool sent_ = false;
};

}  // namespace lcmloc::app
