// lcmloc-replay --bench: offline replay throughput on a long synthetic log.
#include "bench.hpp"

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

#include "lcmloc/common/process.hpp"
#include "lcmloc/eval/log_reader.hpp"
#include "lcmloc/magruler_t.hpp"
#include "lcmloc/odometry_t.hpp"
#include "lcmloc/replay/replay.hpp"

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

/// Reads every event and decodes the sensor messages into their lcmtypes; returns events read.
int64_t readAndDecode(const std::string& path, const common::ChannelConfig& ch, int64_t* decoded) {
  eval::LogScanner scanner(path, nullptr);
  const std::set<std::string> rulers(ch.magruler.begin(), ch.magruler.end());
  lcmloc::odometry_t odo;
  lcmloc::magruler_t mr;
  int64_t n = 0;
  while (const lcm::LogEvent* ev = scanner.next()) {
    if (ev->channel == ch.odometry) {
      if (odo.decode(ev->data, 0, ev->datalen) >= 0) ++n;
    } else if (rulers.count(ev->channel)) {
      if (mr.decode(ev->data, 0, ev->datalen) >= 0) ++n;
    }
  }
  *decoded = n;
  return scanner.eventsRead();
}

}  // namespace

int runBench(const common::SystemConfig& base, const BenchOptions& opts) {
  namespace fs = std::filesystem;
  using Clock = std::chrono::steady_clock;
  fs::create_directories(opts.dir);
  const std::string log = (fs::path(opts.dir) / "synthetic.lcmlog").string();
  const std::string out = (fs::path(opts.dir) / "replay_out.lcmlog").string();

  common::SystemConfig cfg = base;
  cfg.scenario = ovalScenario(base.scenario, OvalTrack{}, opts.duration_s);
  cfg.fusion.shadow.clear();

  if (!(opts.keep_log && fs::exists(log))) {
    spdlog::info("generating {:.0f} s of synthetic odometry + ruler detections into {}", opts.duration_s, log);
    const auto t0 = Clock::now();
    const auto st = writeSyntheticLog(cfg.scenario, opts.duration_s, log, cfg.channels);
    spdlog::info("generated {} odometry, {} detections over {:.0f} m ({} markers) in {:.1f} s", st.odometry,
                 st.detections, st.distance_m, st.markers,
                 std::chrono::duration<double>(Clock::now() - t0).count());
  }

  std::vector<double> rate_read, rate_dr, rate_ukf, rate_ukf_nofile;
  std::vector<double> cpu_read, cpu_dr, cpu_ukf, cpu_ukf_nofile;  ///< messages per CPU second
  int64_t events = 0, decoded = 0;
  ReplayResult last_dr, last_ukf;
  for (int rep = 0; rep < opts.repetitions && !common::stopRequested(); ++rep) {
    auto t0 = Clock::now();
    double c0 = cpuSeconds();
    events = readAndDecode(log, cfg.channels, &decoded);
    rate_read.push_back(events / std::chrono::duration<double>(Clock::now() - t0).count());
    cpu_read.push_back(events / (cpuSeconds() - c0));

    for (const char* filter : {"dead_reckoning", "ukf_gated"}) {
      common::SystemConfig c = cfg;
      c.fusion.filter.type = filter;
      ReplayOptions ro;
      ro.input = log;
      ro.output = out;
      ro.progress_period_s = 0;
      c0 = cpuSeconds();
      const ReplayResult r = replayLog(c, ro);
      const double rate = r.events_read / r.seconds;
      (std::string(filter) == "dead_reckoning" ? rate_dr : rate_ukf).push_back(rate);
      (std::string(filter) == "dead_reckoning" ? cpu_dr : cpu_ukf).push_back(r.events_read / (cpuSeconds() - c0));
      (std::string(filter) == "dead_reckoning" ? last_dr : last_ukf) = r;
    }
    {  // the same, outputs encoded but not written: what the file writing costs
      common::SystemConfig c = cfg;
      c.fusion.filter.type = "ukf_gated";
      ReplayOptions ro;
      ro.input = log;
      ro.progress_period_s = 0;
      c0 = cpuSeconds();
      const ReplayResult r = replayLog(c, ro);
      rate_ukf_nofile.push_back(r.events_read / r.seconds);
      cpu_ukf_nofile.push_back(r.events_read / (cpuSeconds() - c0));
    }
    spdlog::info("repetition {}: read+decode {:.0f}/s, dead_reckoning {:.0f}/s, ukf_gated {:.0f}/s, ukf_gated "
                 "without output file {:.0f}/s", rep + 1, rate_read.back(), rate_dr.back(), rate_ukf.back(),
                 rate_ukf_nofile.back());
  }
  if (rate_read.empty()) return common::kExitRuntimeError;
  const double m_read = median(rate_read), m_dr = median(rate_dr), m_ukf = median(rate_ukf),
               m_nofile = median(rate_ukf_nofile);
  const double c_read = median(cpu_read), c_dr = median(cpu_dr), c_ukf = median(cpu_ukf),
               c_nofile = median(cpu_ukf_nofile);
  std::string table = fmt::format("{:<32}{:>14}{:>10}{:>16}{:>10}\n", "what", "messages/s", "ratio",
                                  "msgs/CPU-s", "ratio");
  auto row = [&](const char* what, double wall, double cpu) {
    table += fmt::format("{:<32}{:>14.0f}{:>10.2f}{:>16.0f}{:>10.2f}\n", what, wall, wall / m_read, cpu, cpu / c_read);
  };
  row("read+decode", m_read, c_read);
  row("dead_reckoning replay", m_dr, c_dr);
  row("ukf_gated replay", m_ukf, c_ukf);
  row("ukf_gated, no output file", m_nofile, c_nofile);
  std::cout << fmt::format(
      "synthetic log: {} events ({} decoded sensor messages), {:.0f} s of message time, {} repetitions\n{}"
      "ukf_gated replay / read+decode = {:.2f} (aim: >= 0.5; per CPU second {:.2f}); written per replay: {} "
      "events\n",
      events, decoded, opts.duration_s, rate_read.size(), table, m_ukf / m_read, c_ukf / c_read, last_ukf.written);

  nlohmann::json j;
  j["log"] = {{"events", events}, {"decoded", decoded}, {"duration_s", opts.duration_s}, {"path", log}};
  j["repetitions"] = rate_read.size();
  j["read_decode"] = {{"median_msgs_per_s", m_read}, {"runs", rate_read},
                      {"median_msgs_per_cpu_s", c_read}, {"cpu_runs", cpu_read}};
  j["dead_reckoning"] = {{"median_msgs_per_s", m_dr}, {"runs", rate_dr}, {"ratio_to_read", m_dr / m_read},
                         {"median_msgs_per_cpu_s", c_dr}, {"cpu_runs", cpu_dr}, {"cpu_ratio_to_read", c_dr / c_read},
                         {"used", last_dr.used}, {"written", last_dr.written}};
  j["ukf_gated"] = {{"median_msgs_per_s", m_ukf}, {"runs", rate_ukf}, {"ratio_to_read", m_ukf / m_read},
                    {"median_msgs_per_cpu_s", c_ukf}, {"cpu_runs", cpu_ukf}, {"cpu_ratio_to_read", c_ukf / c_read},
                    {"used", last_ukf.used}, {"written", last_ukf.written}};
  j["ukf_gated_no_output_file"] = {{"median_msgs_per_s", m_nofile}, {"runs", rate_ukf_nofile},
                                   {"ratio_to_read", m_nofile / m_read}, {"median_msgs_per_cpu_s", c_nofile},
                                   {"cpu_runs", cpu_ukf_nofile}, {"cpu_ratio_to_read", c_nofile / c_read}};
  const std::string report = (fs::path(opts.dir) / "bench.json").string();
  std::ofstream(report) << j.dump(2) << "\n";
  std::cout << "report: " << report << "\n";
  fs::remove(out);
  return common::kExitOk;
}

}  // namespace lcmloc::replay
