// lcmloc-landmark-experiment's work after its command line (command.hpp).
#include "lcmloc/landmark_experiment/command.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/files.hpp"
#include "lcmloc/app/signals.hpp"
#include "lcmloc/logio/log_reader.hpp"
#include "lcmloc/ground_truth_t.hpp"
#include "lcmloc/landmark_bearings_t.hpp"

namespace lcmloc::landmark_experiment {

/// VISION observations of a log with the GROUND_TRUTH pose of the same utime. Undecodable or
/// non-finite messages are counted and skipped; a VISION message with no truth at its time too.
/// A damaged log is read up to and past the damage (eval's reader); each damaged place is logged
/// and *damaged set.
std::vector<Observation> readObservations(const std::string& path, const app::ChannelConfig& ch,
                                                      bool* damaged) {
  std::map<int64_t, lcmloc::ground_truth_t> truth;
  std::vector<lcmloc::landmark_bearings_t> vision;
  int64_t bad = 0;
  const auto scan = logio::scanLog(path, [&](const logio::RawEvent& ev) {
    if (*ev.channel == ch.ground_truth) {
      lcmloc::ground_truth_t m{};
      if (!logio::decodeEvent(ev, m) || !std::isfinite(m.x) || !std::isfinite(m.y) || !std::isfinite(m.heading)) {
        ++bad;
        return;
      }
      truth[m.utime] = m;
    } else if (*ev.channel == ch.vision) {
      lcmloc::landmark_bearings_t m;
      if (!logio::decodeEvent(ev, m)) {
        ++bad;
        return;
      }
      vision.push_back(m);
    }
  }, &app::stopFlag());
  for (const auto& i : scan.issues) spdlog::warn("DAMAGE in {}: {}", path, i.describe());
  if (scan.interrupted) spdlog::warn("{}: interrupted after {} events: solving those", path, scan.events_read);
  *damaged = scan.damaged;
  std::vector<Observation> obs;
  int64_t no_truth = 0;
  for (const auto& v : vision) {
    const auto it = truth.find(v.utime);
    if (it == truth.end()) {
      ++no_truth;
      continue;
    }
    Observation o;
    o.utime = v.utime;
    o.x = it->second.x;
    o.y = it->second.y;
    o.heading = it->second.heading;
    o.sample.utime = v.utime;
    o.sample.ids.assign(v.landmark_ids.begin(), v.landmark_ids.end());
    o.sample.bearings = v.bearings;
    o.sample.bearing_std = v.bearing_std;
    obs.push_back(std::move(o));
  }
  spdlog::info("{}: {} {} and {} {} messages; {} observations with truth, {} without, {} bad messages", path,
               truth.size(), ch.ground_truth, vision.size(), ch.vision, obs.size(), no_truth, bad);
  if (obs.empty())
    throw std::runtime_error("log '" + path + "' has no " + ch.vision + " message with " + ch.ground_truth +
                             " at the same utime");
  return obs;
}

int runCommand(const simconfig::SimSystemConfig& cfg, CommandOptions o) {
  if (std::hypot(o.off_centre[0], o.off_centre[1]) >= 0.9)
    throw app::ConfigError("--off-centre", "",
                              fmt::format("{},{} is not inside 0.9 circumradius (the danger circle is at 1)",
                                          o.off_centre[0], o.off_centre[1]));
  app::prepareOutputDir(o.output, o.overwrite);
  const auto& v = cfg.scenario.vision;
  o.experiment.seed = o.seed ? o.seed : v.seed ? v.seed : sim::componentSeed(cfg.scenario.seed, "vision");
  o.experiment.ins_offset = Eigen::Vector2d(o.ins_offset[0], o.ins_offset[1]);
  o.experiment.off_centre = Eigen::Vector2d(o.off_centre[0], o.off_centre[1]);
  o.experiment.ins_heading_error = o.heading_arcmin * 60.0 * sim::kArcSec;
  const auto t0 = std::chrono::steady_clock::now();
  auto last = t0;
  o.experiment.progress = [&](int64_t done, int64_t total) {
    const auto now = std::chrono::steady_clock::now();
    if (done < total && now - last < std::chrono::seconds(1)) return;
    last = now;
    spdlog::info("{}/{} runs ({:.0f} %)", done, total, 100.0 * static_cast<double>(done) / static_cast<double>(total));
  };
  if (o.log.empty())
    spdlog::info("{} runs per case, seed {}, noise {:.1f}\", resolution {:.1f}\", distance {} m", o.experiment.runs,
                 o.experiment.seed, v.bearing_std / sim::kArcSec, v.resolution / sim::kArcSec, o.experiment.distance);
  if (!o.log.empty() && cfg.scenario.landmarks.empty())
    throw app::ConfigError(cfg.file, "landmarks", "--log needs the landmark map of the recorded run");
  bool damaged = false;
  const auto r = o.log.empty() ? run(v, o.experiment)
                               : runObservations(cfg.scenario.landmarks,
                                                 readObservations(o.log, cfg.channels, &damaged), o.experiment);
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const bool plotted = writeReport(r, o.output);
  std::fputs(summaryTable(r).c_str(), stdout);
  std::printf("%d %s solved in %.2f s; report: %s/report.json%s\n", r.options.runs,
              o.log.empty() ? "runs x 4 cases" : "observations", elapsed, o.output.c_str(),
              plotted ? ", figures <case>.png" : " (gnuplot failed: no figures)");
  return damaged ? app::kExitInputDamaged : app::kExitOk;
}

}  // namespace lcmloc::landmark_experiment
