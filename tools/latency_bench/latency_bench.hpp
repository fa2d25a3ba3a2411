#pragma once
// lcmloc-latency-bench: runs lcmloc-fusion as a child on a udpm URL and feeds it at nominal rates
// (100 Hz ODOMETRY, 100 Hz IMU, 10 Hz GPS, 5 Hz MAGRULER detections), each message stamped with
// the wall time it is sent at. In the same run, on the same URL, a raw LCM relay (a thread that
// re-publishes each message of one channel on another) carries a 100 Hz probe. A receiver takes
// every POSE, POSE_CONTROL and relayed probe and measures its latency: arrival wall time minus
// the message time it is about (for POSE the input it was computed from; its horizon included).
// A bare subscriber (a child process that subscribes to the same input channels and decodes each
// message) runs beside the daemon: their CPU times over the measured span are compared. The
// daemon's RSS is sampled once per second.
#include <cstdint>
#include <string>
#include <vector>

namespace lcmloc::latency {

struct BenchOptions {
  std::string fusion;  ///< the lcmloc-fusion executable
  std::string config;  ///< its system configuration (channels, filter, reorder window)
  std::string filter;  ///< --filter for the daemon ("" = the configuration's)
  std::string lcm_url = "udpm://239.255.76.67:7691?ttl=0&recv_buf_size=4194304";
  double duration_s = 20.0;  ///< [s, wall] measured
  double warmup_s = 2.0;     ///< [s, wall] before, not measured
  std::string report;        ///< JSON report file ("" = none)
};

/// Latency figures [ms] of one output.
struct Latency {
  int64_t n = 0;
  double p50 = 0, p99 = 0, max = 0;
};
Latency summarize(std::vector<double> ms);

struct BenchResult {
  Latency relay, control, canonical;
  double daemon_cpu_s = 0, bare_cpu_s = 0;  ///< over the measured span
  int64_t rss_first_kb = 0, rss_last_kb = 0, rss_peak_kb = 0;  ///< daemon (VmRSS after warm-up, at the end; VmHWM)
  double reorder_window_s = 0;  ///< the fusion horizon (fusion.reorder_window, or a larger fusion.sensors delay)
  int64_t sent = 0;  ///< input messages sent in the measured span
};

/// Runs the benchmark. Throws std::runtime_error when the daemon cannot be started or sends nothing.
BenchResult run(const BenchOptions& o);
/// The report as JSON.
std::string toJson(const BenchOptions& o, const BenchResult& r);
/// The report as text.
std::string toText(const BenchResult& r);

}  // namespace lcmloc::latency
