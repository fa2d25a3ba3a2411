// lcmloc-replay --bench (bench.hpp): offline replay throughput on a long synthetic log.
#include "lcmloc/drivers/scenario_map.hpp"
#include "lcmloc/replay/bench.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <set>
#include <vector>

#include <time.h>

#include <fmt/format.h>
#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/signals.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/logio/log_reader.hpp"
#include "lcmloc/magruler_t.hpp"
#include "lcmloc/odometry_t.hpp"
#include "lcmloc/replay/replay.hpp"
#include "lcmloc/eval/report.hpp"

namespace lcmloc::replay {
namespace {

/// CPU time of this process [s] (the machine is shared: wall rates depend on the other load).
double cpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// Where readAndDecode keeps its sum (a side effect the compiler must leave in).
volatile double decoded_sum = 0;

/// Reads every event and decodes the sensor messages into their lcmtypes, with the decoder the
/// daemon uses (bus::decodeMessage); returns events read. Every decoded field goes into a sum
/// that is kept: the compiler cannot skip the decoding.
int64_t readAndDecode(const std::string& path, const app::ChannelConfig& ch, int64_t* decoded) {
  logio::LogScanner scanner(path, nullptr);
  const std::set<std::string> rulers(ch.magruler.begin(), ch.magruler.end());
  lcmloc::odometry_t odo;
  lcmloc::magruler_t mr;
  int64_t n = 0;
  double sum = 0;
  while (const lcm::LogEvent* ev = scanner.next()) {
    const auto* data = static_cast<const uint8_t*>(ev->data);
    const auto size = static_cast<std::size_t>(ev->datalen);
    if (ev->channel == ch.odometry) {
      if (bus::decodeMessage(odo, data, size) >= 0) {
        ++n;
        sum += static_cast<double>(odo.utime + odo.seq + odo.ticks) + odo.delta_s + odo.steering + odo.delta_theta +
               (odo.has_steering ? 1.0 : 0.0);
      }
    } else if (rulers.count(ev->channel)) {
      if (bus::decodeMessage(mr, data, size) >= 0) {
        ++n;
        sum += static_cast<double>(mr.utime + mr.seq) + mr.lateral_offset + mr.quality +
               static_cast<double>(mr.readings.size());
      }
    }
  }
  decoded_sum = sum;
  *decoded = n;
  return scanner.eventsRead();
}

/// Why a kept synthetic log does not fit this run ("" when it does): damaged, not the
/// configured channels, or another length of message time than duration_s.
std::string keptLogProblem(const std::string& path, const simconfig::SimSystemConfig& cfg, double duration_s) {
  std::vector<logio::LogIssue> issues;
  logio::LogScanner scanner(path, &issues);
  int64_t first = -1, last = -1, odometry = 0;
  while (const lcm::LogEvent* ev = scanner.next()) {
    if (ev->channel != cfg.channels.odometry) continue;
    if (first < 0) first = ev->timestamp;
    last = ev->timestamp;
    ++odometry;
  }
  if (scanner.damaged()) return "is damaged (" + (issues.empty() ? std::string("unreadable bytes") : issues.front().describe()) + ")";
  if (odometry < 2) return "has no " + cfg.channels.odometry + " messages";
  // One odometry period short of duration_s at the most (the first message is at the start).
  const double span = static_cast<double>(last - first) * 1e-6;
  const double period = cfg.scenario.odometry.rate_hz > 0 ? 1.0 / cfg.scenario.odometry.rate_hz : 0.0;
  if (std::abs(span - duration_s) > period + 1e-6)
    return fmt::format("covers {:.3f} s of message time, not the {:.3f} s of --bench-duration", span, duration_s);
  return "";
}

}  // namespace

int runBench(const simconfig::SimSystemConfig& base, const BenchOptions& opts) {
  namespace fs = std::filesystem;
  using Clock = std::chrono::steady_clock;
  fs::create_directories(opts.dir);
  const std::string log = (fs::path(opts.dir) / "synthetic.lcmlog").string();
  const std::string out = (fs::path(opts.dir) / "replay_out.lcmlog").string();

  simconfig::SimSystemConfig cfg = base;
  cfg.scenario = ovalScenario(base.scenario, OvalTrack{}, opts.duration_s);
  cfg.fusion.shadow.clear();
  cfg.fusion.map_file = (fs::path(opts.dir) / "synthetic_map.csv").string();  // the oval's markers
  drivers::writeScenarioMap(cfg, cfg.fusion.map_file);

  /// One measured configuration: filter, fusion.output_every, output file or not, one thread or two.
  struct Case {
    std::string key, label, filter;
    int output_every = 1;
    bool file = true;
    bool one_thread = false;  ///< ReplayOptions::read_ahead off (the live daemon's: all in one thread)
    std::vector<double> wall, cpu;  ///< messages per wall / CPU second, one per repetition
    /// wall, cpu over those of the read + decode measured just before it (side by side: the
    /// shared machine's load changes within a repetition).
    std::vector<double> wall_ratio, cpu_ratio;
    std::vector<double> reading_ns, applying_ns;  ///< CPU per message of each side [ns]
    std::vector<double> sleeps;                   ///< ReplayResult::handoff_sleeps
    ReplayResult last;
  };
  std::vector<Case> cases;
  auto add = [&cases](const std::string& key, const std::string& label, const char* filter, int every, bool file,
                      bool one_thread = false) {
    Case k;
    k.key = key;
    k.label = label;
    k.filter = filter;
    k.output_every = every;
    k.file = file;
    k.one_thread = one_thread;
    cases.push_back(std::move(k));
  };
  add("dead_reckoning", "dead_reckoning replay", "dead_reckoning", 1, true);
  add("ukf_gated", "ukf_gated replay", "ukf_gated", 1, true);
  add("ukf_gated_no_output_file", "ukf_gated, no output file", "ukf_gated", 1, false);
  add("ukf_gated_one_thread", "ukf_gated, one thread", "ukf_gated", 1, true, true);
  if (opts.output_every > 1) {
    const std::string n = std::to_string(opts.output_every);
    add("dead_reckoning_output_every_" + n, "dead_reckoning, output_every " + n, "dead_reckoning", opts.output_every,
        true);
    add("ukf_gated_output_every_" + n, "ukf_gated, output_every " + n, "ukf_gated", opts.output_every, true);
    add("ukf_gated_output_every_" + n + "_no_output_file", "ukf_gated, output_every " + n + ", no file", "ukf_gated",
        opts.output_every, false);
    add("ukf_gated_output_every_" + n + "_one_thread", "ukf_gated, output_every " + n + ", one thread", "ukf_gated",
        opts.output_every, true, true);
  }
  if (!opts.cases.empty()) {
    std::vector<Case> chosen;
    for (const std::string& key : opts.cases) {
      const auto it = std::find_if(cases.begin(), cases.end(), [&](const Case& k) { return k.key == key; });
      if (it == cases.end()) {
        std::string known;
        for (const Case& k : cases) known += (known.empty() ? "" : ", ") + k.key;
        spdlog::error("--bench-case {}: no such case (with --bench-output-every {}: {})", key, opts.output_every,
                      known);
        return app::kExitConfigError;
      }
      if (std::none_of(chosen.begin(), chosen.end(), [&](const Case& k) { return k.key == key; })) chosen.push_back(*it);
    }
    cases = std::move(chosen);
  }
  bool generate = !(opts.keep_log && fs::exists(log));
  if (!generate) {
    const std::string why = keptLogProblem(log, cfg, opts.duration_s);
    if (!why.empty()) {
      spdlog::warn("--bench-keep-log: {} {}: generating it again", log, why);
      generate = true;
    }
  }
  if (generate) {
    spdlog::info("generating {:.0f} s of synthetic odometry + ruler detections into {}", opts.duration_s, log);
    const auto t0 = Clock::now();
    auto last_line = t0;
    const auto st = writeSyntheticLog(cfg.scenario, opts.duration_s, log, cfg.channels, [&](double done) {
      if (Clock::now() - last_line >= std::chrono::seconds(2)) {
        last_line = Clock::now();
        spdlog::info("generating: {:.0f}%", 100.0 * done);
      }
      return !app::stopRequested();
    });
    if (st.stopped) {
      std::error_code ec;
      fs::remove(log, ec);
      spdlog::warn("stopped while generating the synthetic log; the partial log is removed");
      return app::kExitRuntimeError;
    }
    spdlog::info("generated {} odometry, {} detections over {:.0f} m ({} markers) in {:.1f} s", st.odometry,
                 st.detections, st.distance_m, st.markers,
                 std::chrono::duration<double>(Clock::now() - t0).count());
  }

  std::vector<double> rate_read, cpu_read;
  int64_t events = 0, decoded = 0;
  auto readOnce = [&] {
    const auto t0 = Clock::now();
    const double c0 = cpuSeconds();
    events = readAndDecode(log, cfg.channels, &decoded);
    rate_read.push_back(events / std::chrono::duration<double>(Clock::now() - t0).count());
    cpu_read.push_back(events / (cpuSeconds() - c0));
  };
  int reps_done = 0;
  for (int rep = 0; rep < opts.repetitions && !app::stopRequested(); ++rep) {
    std::string line = fmt::format("repetition {}:", rep + 1);
    for (Case& k : cases) {
      readOnce();  // the baseline next to each case
      app::SystemConfig c = cfg;
      c.fusion.filter.type = k.filter;
      c.fusion.output_every = k.output_every;
      ReplayOptions ro;
      ro.input = log;
      if (k.file) ro.output = out;  // otherwise the outputs are encoded but not written
      ro.progress_period_s = 0;
      ro.read_ahead = !k.one_thread;
      const double c0 = cpuSeconds();
      const ReplayResult r = replayLog(c, ro);
      k.wall.push_back(r.events_read / r.seconds);
      k.cpu.push_back(r.events_read / (cpuSeconds() - c0));
      k.reading_ns.push_back(1e9 * r.reading_cpu_s / static_cast<double>(r.events_read));
      k.applying_ns.push_back(1e9 * r.applying_cpu_s / static_cast<double>(r.events_read));
      k.sleeps.push_back(static_cast<double>(r.handoff_sleeps));
      k.wall_ratio.push_back(k.wall.back() / rate_read.back());
      k.cpu_ratio.push_back(k.cpu.back() / cpu_read.back());
      k.last = r;
      // Each case writes a new output file (what a replay into a new path costs), not one in
      // place of the case's before: removing that one is not the replay's work.
      std::error_code ec;
      fs::remove(out, ec);
      line += fmt::format(" read+decode {:.0f}/s, {} {:.0f}/s ({:.2f});", rate_read.back(), k.label, k.wall.back(),
                          k.wall_ratio.back());
    }
    spdlog::info("{}", line);
    ++reps_done;
  }
  if (reps_done == 0) return app::kExitRuntimeError;
  const double m_read = median(rate_read), c_read = median(cpu_read);
  std::string table = fmt::format("{:<40}{:>14}{:>10}{:>16}{:>10}{:>11}\n", "what", "messages/s", "ratio",
                                  "msgs/CPU-s", "ratio", "written");
  table += fmt::format("{:<40}{:>14.0f}{:>10.2f}{:>16.0f}{:>10.2f}{:>11}\n", "read+decode", m_read, 1.0, c_read, 1.0, "");
  nlohmann::json j;
  j["log"] = {{"events", events}, {"decoded", decoded}, {"duration_s", opts.duration_s}, {"path", log}};
  j["repetitions"] = reps_done;
  j["read_decode"] = {{"median_msgs_per_s", m_read}, {"runs", rate_read},
                      {"median_msgs_per_cpu_s", c_read}, {"cpu_runs", cpu_read}};
  std::string verdict;
  std::string sides =
      fmt::format("CPU per message [ns] of each side, and times a thread slept for the other, medians:\n"
                  "{:<40}{:>10}{:>10}{:>10}\n{:<40}{:>10.0f}\n",
                  "what", "reading", "applying", "sleeps", "read+decode", 1e9 / c_read);
  for (const Case& k : cases) {
    const double w = median(k.wall), c = median(k.cpu), wr = median(k.wall_ratio), cr = median(k.cpu_ratio);
    table += fmt::format("{:<40}{:>14.0f}{:>10.2f}{:>16.0f}{:>10.2f}{:>11}\n", k.label, w, wr, c, cr, k.last.written);
    j[k.key] = {{"filter", k.filter}, {"output_every", k.output_every}, {"output_file", k.file},
                {"one_thread", k.one_thread}, {"median_msgs_per_s", w}, {"runs", k.wall},
                {"ratio_to_read", wr}, {"ratio_runs", k.wall_ratio}, {"median_msgs_per_cpu_s", c}, {"cpu_runs", k.cpu},
                {"cpu_ratio_to_read", cr}, {"cpu_ratio_runs", k.cpu_ratio}, {"used", k.last.used},
                {"written", k.last.written}, {"median_reading_cpu_ns_per_msg", median(k.reading_ns)},
                {"median_applying_cpu_ns_per_msg", median(k.applying_ns)},
                {"median_handoff_sleeps", median(k.sleeps)}};
    sides += fmt::format("{:<40}{:>10.0f}{:>10.0f}{:>10}\n", k.label, median(k.reading_ns), median(k.applying_ns),
                         k.one_thread ? std::string() : fmt::format("{:.0f}", median(k.sleeps)));
    if (k.filter == "ukf_gated" && k.file && !k.one_thread)
      verdict += fmt::format("{} / read+decode = {:.2f} (per CPU second {:.2f}): aim (>= 0.5) {}\n", k.label, wr, cr,
                             wr >= 0.5 ? "met" : "not met");
  }
  std::cout << fmt::format(
      "synthetic log: {} events ({} decoded sensor messages), {:.0f} s of message time, {} repetitions\n{}{}{}",
      events, decoded, opts.duration_s, reps_done, table, sides, verdict);
  const std::string report = (fs::path(opts.dir) / "bench.json").string();
  eval::writeJson(j, report);
  std::cout << "report: " << report << "\n";
  fs::remove(out);
  return app::kExitOk;
}

}  // namespace lcmloc::replay
