#include "latency_bench.hpp"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <thread>

#include <fmt/format.h>
#include <lcm/lcm-cpp.hpp>

#include "lcmloc/app/child_process.hpp"
#include "lcmloc/app/config.hpp"
#include "lcmloc/gps_fix_t.hpp"
#include "lcmloc/imu_t.hpp"
#include "lcmloc/magruler_t.hpp"
#include "lcmloc/odometry_t.hpp"

namespace lcmloc::latency {
namespace {

using Clock = std::chrono::steady_clock;
const char* const kProbeIn = "LATENCY_PROBE";
const char* const kProbeOut = "LATENCY_PROBE_RELAYED";

int64_t wallUs() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

/// CPU seconds (user + system) of process pid (/proc/PID/stat fields 14 and 15); 0 when gone.
double cpuSeconds(pid_t pid) {
  std::ifstream f("/proc/" + std::to_string(pid) + "/stat");
  std::string s;
  std::getline(f, s);
  const auto close = s.rfind(')');
  if (close == std::string::npos) return 0;
  std::istringstream in(s.substr(close + 2));
  std::vector<std::string> v;
  for (std::string field; in >> field;) v.push_back(field);
  if (v.size() < 13) return 0;
  return (std::stod(v[11]) + std::stod(v[12])) / static_cast<double>(sysconf(_SC_CLK_TCK));
}

/// The bare subscriber: the daemon's input channels, each message decoded, nothing else.
struct Bare {
  int64_t n = 0;
  template <typename T>
  void on(const lcm::ReceiveBuffer*, const std::string&, const T* m) {
    n += m->seq >= 0;
  }
};
[[noreturn]] void bareSubscriber(const std::string& url, const app::ChannelConfig& ch) {
  lcm::LCM lcm(url);
  Bare b;
  lcm.subscribe(ch.odometry, &Bare::on<lcmloc::odometry_t>, &b);
  lcm.subscribe(ch.imu, &Bare::on<lcmloc::imu_t>, &b);
  lcm.subscribe(ch.gps, &Bare::on<lcmloc::gps_fix_t>, &b);
  lcm.subscribe(ch.magruler.front(), &Bare::on<lcmloc::magruler_t>, &b);
  for (;;) lcm.handleTimeout(100);  // until killed
}

/// Re-publishes kProbeIn on kProbeOut as it is (the raw relay).
struct Relay {
  lcm::LCM* lcm;
  void on(const lcm::ReceiveBuffer* rb, const std::string&) { lcm->publish(kProbeOut, rb->data, rb->data_size); }
};

/// Latency of each POSE, POSE_CONTROL and relayed probe: arrival minus its utime (the first
/// field, after the 8-byte type fingerprint).
struct Receiver {
  std::string pose, control;
  std::atomic<bool>* measuring;
  std::mutex mu;
  std::vector<double> relay, ctl, canonical;
  void on(const lcm::ReceiveBuffer* rb, const std::string& ch) {
    if (rb->data_size < 16 || !measuring->load()) return;
    const auto* p = static_cast<const uint8_t*>(rb->data) + 8;
    uint64_t u = 0;
    for (int i = 0; i < 8; ++i) u = (u << 8) | p[i];
    const double ms = static_cast<double>(rb->recv_utime - static_cast<int64_t>(u)) * 1e-3;
    std::lock_guard<std::mutex> lock(mu);
    (ch == control ? ctl : ch == pose ? canonical : relay).push_back(ms);
  }
};

}  // namespace

Latency summarize(std::vector<double> ms) {
  Latency l;
  l.n = static_cast<int64_t>(ms.size());
  if (ms.empty()) return l;
  std::sort(ms.begin(), ms.end());
  auto at = [&](double q) {
    const auto r = static_cast<std::size_t>(std::ceil(q * static_cast<double>(ms.size())));
    return ms[std::min(ms.size() - 1, r > 0 ? r - 1 : 0)];
  };
  l.p50 = at(0.5);
  l.p99 = at(0.99);
  l.max = ms.back();
  return l;
}

BenchResult run(const BenchOptions& o) {
  const app::SystemConfig cfg = app::loadSystemConfig(o.config);
  const app::ChannelConfig& ch = cfg.channels;
  BenchResult r;
  r.reorder_window_s = cfg.fusion.horizon();  // (the reorder window, or a sensor's larger expected delay)
  const pid_t bare = fork();  // (before any thread)
  if (bare < 0) throw std::runtime_error("fork failed");
  if (bare == 0) bareSubscriber(o.lcm_url, ch);
  std::vector<std::string> args{o.fusion, "--lcm-url", o.lcm_url, "--config", o.config};
  if (!o.filter.empty()) args.insert(args.end(), {"--filter", o.filter});
  const std::string daemon_log = o.report.empty() ? "/dev/null" : o.report + ".fusion.log";
  const pid_t daemon = app::spawnWithOutput(args, daemon_log);

  std::atomic<bool> stop{false}, measuring{false};
  Receiver rx{ch.pose, ch.pose_control, &measuring, {}, {}, {}, {}};
  std::thread relay_thread([&] {
    lcm::LCM lcm(o.lcm_url);
    Relay relay{&lcm};
    lcm.subscribe(kProbeIn, &Relay::on, &relay);
    while (!stop) lcm.handleTimeout(50);
  });
  std::thread rx_thread([&] {
    lcm::LCM lcm(o.lcm_url);
    for (const std::string& c : {ch.pose, ch.pose_control, std::string(kProbeOut)}) lcm.subscribe(c, &Receiver::on, &rx);
    while (!stop) lcm.handleTimeout(50);
  });

  lcm::LCM out(o.lcm_url);
  const auto t0 = Clock::now();
  const auto warm_end = t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(o.warmup_s));
  const auto end = warm_end + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(o.duration_s));
  double cpu0_daemon = 0, cpu0_bare = 0;
  int64_t gps_seq = 0, ruler_seq = 0;
  for (int64_t k = 0;; ++k) {
    const auto next = t0 + std::chrono::milliseconds(10) * k;
    if (next >= end) break;
    std::this_thread::sleep_until(next);
    if (!measuring && next >= warm_end) {
      cpu0_daemon = cpuSeconds(daemon);
      cpu0_bare = cpuSeconds(bare);
      r.rss_first_kb = app::procStatusKb(daemon, "VmRSS");
      measuring = true;
    }
    const int64_t now = wallUs();
    lcmloc::odometry_t odo{};
    odo.utime = now;
    odo.seq = k;
    odo.delta_s = 0.1;  // 10 m/s
    odo.ticks = 100;
    odo.has_steering = true;
    out.publish(ch.odometry, &odo);
    lcmloc::imu_t imu{};
    imu.utime = now;
    imu.seq = k;
    imu.accel[2] = 9.81;
    imu.mag[0] = 0.2;
    imu.mag[2] = -0.4;
    out.publish(ch.imu, &imu);
    out.publish(kProbeIn, &odo);
    r.sent += measuring ? 2 : 0;
    if (k % 10 == 0) {
      lcmloc::gps_fix_t g{};
      g.utime = now;
      g.seq = gps_seq++;
      g.latitude = cfg.datum.latitude;
      g.longitude = cfg.datum.longitude;
      g.fix_type = 3;
      g.satellites = 10;
      g.hdop = 1.0;
      g.position_std = 2.0;
      out.publish(ch.gps, &g);
      r.sent += measuring ? 1 : 0;
    }
    if (k % 20 == 5) {
      lcmloc::magruler_t m{};
      m.utime = now;
      m.seq = ruler_seq++;
      m.num_sensors = 13;
      m.readings.assign(13, 0.45);
      m.detected = true;
      m.lateral_offset = 0.01;
      m.quality = 0.9;
      out.publish(ch.magruler.front(), &m);
      r.sent += measuring ? 1 : 0;
    }
    if (measuring && k % 100 == 0) r.rss_last_kb = app::procStatusKb(daemon, "VmRSS");
  }
  std::this_thread::sleep_for(std::chrono::duration<double>(cfg.fusion.horizon() + 0.05));  // the last poses
  measuring = false;
  r.daemon_cpu_s = cpuSeconds(daemon) - cpu0_daemon;
  r.bare_cpu_s = cpuSeconds(bare) - cpu0_bare;
  r.rss_last_kb = app::procStatusKb(daemon, "VmRSS");
  r.rss_peak_kb = app::procStatusKb(daemon, "VmHWM");
  ::kill(daemon, SIGTERM);
  ::kill(bare, SIGKILL);
  const auto stop_deadline = Clock::now() + std::chrono::seconds(5);  // a hung daemon is killed
  while (::waitpid(daemon, nullptr, WNOHANG) == 0) {
    if (Clock::now() > stop_deadline) {
      ::kill(daemon, SIGKILL);
      ::waitpid(daemon, nullptr, 0);
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ::waitpid(bare, nullptr, 0);
  stop = true;
  relay_thread.join();
  rx_thread.join();
  r.relay = summarize(rx.relay);
  r.control = summarize(rx.ctl);
  r.canonical = summarize(rx.canonical);
  if (r.canonical.n == 0)
    throw std::runtime_error("no " + ch.pose + " from " + o.fusion + " on " + o.lcm_url + " (its output: " +
                             daemon_log + ")");
  return r;
}

namespace {
std::string json(const Latency& l) {
  return fmt::format("{{\"n\": {}, \"p50_ms\": {:.4f}, \"p99_ms\": {:.4f}, \"max_ms\": {:.4f}}}", l.n, l.p50, l.p99,
                     l.max);
}
}  // namespace

std::string toJson(const BenchOptions& o, const BenchResult& r) {
  return fmt::format(
      "{{\n  \"lcm_url\": \"{}\",\n  \"duration_s\": {},\n  \"reorder_window_s\": {},\n  \"inputs_sent\": {},\n"
      "  \"relay\": {},\n  \"control\": {},\n  \"canonical\": {},\n"
      "  \"cpu\": {{\"daemon_s\": {:.4f}, \"bare_subscriber_s\": {:.4f}, \"ratio\": {:.3f}}},\n"
      "  \"rss_kb\": {{\"first\": {}, \"last\": {}, \"peak\": {}}}\n}}\n",
      o.lcm_url, o.duration_s, r.reorder_window_s, r.sent, json(r.relay), json(r.control), json(r.canonical),
      r.daemon_cpu_s, r.bare_cpu_s, r.bare_cpu_s > 0 ? r.daemon_cpu_s / r.bare_cpu_s : 0.0, r.rss_first_kb,
      r.rss_last_kb, r.rss_peak_kb);
}

std::string toText(const BenchResult& r) {
  std::string s = fmt::format("{:<34} {:>7} {:>9} {:>9} {:>9}\n", "latency [ms]", "n", "p50", "p99", "max");
  auto row = [&](const char* name, const Latency& l) {
    s += fmt::format("{:<34} {:>7} {:>9.3f} {:>9.3f} {:>9.3f}\n", name, l.n, l.p50, l.p99, l.max);
  };
  row("raw LCM relay", r.relay);
  row("control pose (POSE_CONTROL)", r.control);
  row(fmt::format("canonical pose (POSE, horizon {:.3f} s)", r.reorder_window_s).c_str(), r.canonical);
  s += fmt::format("CPU [s]: daemon {:.3f}, bare subscriber {:.3f} (ratio {:.2f})\n", r.daemon_cpu_s, r.bare_cpu_s,
                   r.bare_cpu_s > 0 ? r.daemon_cpu_s / r.bare_cpu_s : 0.0);
  s += fmt::format("daemon RSS [kB]: after warm-up {}, at the end {}, peak {}\n", r.rss_first_kb, r.rss_last_kb,
                   r.rss_peak_kb);
  return s;
}

}  // namespace lcmloc::latency
