#pragma once
// lcmloc-preflight's checks of the LCM set-up on this host, before the system starts or while it
// runs: the route and ttl of the udpm:// URL, net.core.rmem_max against the receive buffer the URL
// asks for, LCM's self-test, a publisher on each expected channel, and the clock offset of every
// host whose heartbeats are heard. Each finding says what to do about it.
#include <map>
#include <string>
#include <vector>

#include "lcmloc/app/process_table.hpp"

namespace lcmloc::preflight {

/// lcmloc-preflight's own exit code, after the shared ones (app::ExitCode, 0 to 3).
inline constexpr int kExitCheckFailed = 4;

struct Finding {
  enum Level { Ok, Note, Warn, Fail } level = Ok;
  std::string check;  ///< route, ttl, rmem_max, self-test, channel CH, clock HOST
  std::string what;   ///< what was found
  std::string fix;    ///< what to do ("" when nothing)
};

struct Options {
  std::string url;
  bool multi_host = false;             ///< the system spans hosts: ttl 0 and a route via lo are errors
  std::string rmem_max_file = "/proc/sys/net/core/rmem_max";
  std::vector<std::string> expect;     ///< channels that must have a publisher
  double listen = 2.0;                 ///< [s, wall] to listen for expected channels and heartbeats
  double max_clock_offset = 0.01;      ///< [s] between a host and this one
  std::string heartbeat_channel = "HEARTBEAT";
};

/// The multicast group and port of a udpm:// URL, its ttl (LCM's default 0) and recv_buf_size.
struct UdpmUrl {
  std::string group;
  int port = 0;
  int ttl = 0;
  long long recv_buf_size = 0;
};
/// Throws app::UsageError for a URL that is not udpm://GROUP:PORT[?...].
UdpmUrl parseUdpm(const std::string& url);

Finding checkRoute(const UdpmUrl& u, bool multi_host);
Finding checkTtl(const UdpmUrl& u, bool multi_host);
Finding checkReceiveBuffer(const UdpmUrl& u, const std::string& rmem_max_file);
Finding selfTest(const std::string& url);
/// Listens on the bus for opts.listen seconds: a finding per expected channel and per host heard.
std::vector<Finding> listen(const Options& opts);
/// The clock findings from a table of heartbeats (this host's offset is its own latency).
std::vector<Finding> checkClocks(const app::ProcessTable& table, double max_offset);

/// Every check in order; the route, ttl and buffer first (LCM's start fails without a route).
std::vector<Finding> runAll(const Options& opts);

/// "ok    route: ..." lines, a "  -> " line with the fix under each problem.
std::string format(const std::vector<Finding>& findings);

}  // namespace lcmloc::preflight
