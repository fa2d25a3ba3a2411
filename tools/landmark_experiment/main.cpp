// lcmloc-landmark-experiment: Fig. 5 of seeds/004 §III. Monte Carlo of the three-landmark fix
// (error triangle and damped least squares) with bearings from the vision model of lcmloc-vision,
// both readings of "1000 m", vehicle at the centre and off centre, against the Cramér-Rao bound.
#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/process.hpp"
#include "lcmloc/eval/log_reader.hpp"
#include "lcmloc/ground_truth_t.hpp"
#include "lcmloc/landmark_bearings_t.hpp"
#include "lcmloc/landmark_experiment/experiment.hpp"

using namespace lcmloc;

namespace {

/// VISION observations of a log with the GROUND_TRUTH pose of the same utime. Undecodable or
/// non-finite messages are counted and skipped; a VISION message with no truth at its time too.
/// A damaged log is read up to and past the damage (eval's reader); each damaged place is logged
/// and *damaged set.
std::vector<landmark_experiment::Observation> readLog(const std::string& path, const common::ChannelConfig& ch,
                                                      bool* damaged) {
  std::map<int64_t, lcmloc::ground_truth_t> truth;
  std::vector<lcmloc::landmark_bearings_t> vision;
  int64_t bad = 0;
  const auto scan = eval::scanLog(path, [&](const eval::RawEvent& ev) {
    if (*ev.channel == ch.ground_truth) {
      lcmloc::ground_truth_t m{};
      if (!eval::decodeEvent(ev, m) || !std::isfinite(m.x) || !std::isfinite(m.y) || !std::isfinite(m.heading)) {
        ++bad;
        return;
      }
      truth[m.utime] = m;
    } else if (*ev.channel == ch.vision) {
      lcmloc::landmark_bearings_t m;
      if (!eval::decodeEvent(ev, m)) {
        ++bad;
        return;
      }
      vision.push_back(m);
    }
  }, &common::stopFlag());
  for (const auto& i : scan.issues) spdlog::warn("DAMAGE in {}: {}", path, i.describe());
  if (scan.interrupted) spdlog::warn("{}: interrupted after {} events: solving those", path, scan.events_read);
  *damaged = scan.damaged;
  std::vector<landmark_experiment::Observation> obs;
  int64_t no_truth = 0;
  for (const auto& v : vision) {
    const auto it = truth.find(v.utime);
    if (it == truth.end()) {
      ++no_truth;
      continue;
    }
    landmark_experiment::Observation o;
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

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "lcmloc-landmark-experiment: Fig. 5 of seeds/004 §III (three-landmark position and heading fix), "
      "Monte Carlo. Bearing noise, resolution and seed come from the `vision` section of the config; "
      "the landmarks are placed by the experiment (equilateral triangle, both readings of the distance), "
      "not taken from the config's `landmarks` map. Exit: 0 ok, 1 error, 2 bad arguments or config, 3 --log "
      "damaged (its intact events solved; each damaged place reported)"};
  common::CommonOptions opts;
  opts.config = common::configDir() + "/landmark_paper.yaml";
  common::addCommonOptions(app, opts);
  landmark_experiment::Options eo;
  std::string out = "out/landmark_experiment";
  uint64_t seed = 0;
  double heading_arcmin = eo.ins_heading_error / models::kArcSec / 60.0;
  std::vector<double> ins_offset{eo.ins_offset.x(), eo.ins_offset.y()};
  std::vector<double> off_centre{eo.off_centre.x(), eo.off_centre.y()};
  app.add_option("--runs", eo.runs, "Monte Carlo runs per case (10000 for stable statistics)")
      ->check(CLI::Range(1, 10000000))->capture_default_str();
  app.add_option("--seed", seed, "override the seed (default: vision.seed, else derived from scenario.seed)")
      ->check(lcmloc::common::seed());
  app.add_option("--out", out, "output directory (report.json, figures)")->capture_default_str();
  app.add_option("--distance", eo.distance, "the paper's landmark distance [m]")
      ->check(CLI::Range(1.0, 1e6))->capture_default_str();
  app.add_option("--ins-offset", ins_offset, "INS position error east,north [m]")
      ->delimiter(',')->expected(2)->capture_default_str();
  app.add_option("--heading-error", heading_arcmin,
                 "INS heading error [arcmin], heading clockwise from north as in the paper")
      ->check(CLI::Range(-600.0, 600.0))->capture_default_str();
  std::string log_file;
  app.add_option("--log", log_file,
                 "instead of the Monte Carlo: solve the VISION observations of a recorded run (e.g. "
                 "lcmloc-launcher --system config/landmark_system.yaml) against its GROUND_TRUTH, with the "
                 "config's `landmarks` map and the INS error above")
      ->check(CLI::ExistingFile);
  app.add_option("--off-centre", off_centre, "off-centre vehicle east,north as fractions of the circumradius")
      ->delimiter(',')->expected(2)->capture_default_str();

  return common::runProcess(app, argc, argv, opts, "lcmloc-landmark-experiment", [&] {
    const auto cfg = common::loadSystemConfig(opts.config);
    if (std::hypot(off_centre[0], off_centre[1]) >= 0.9)
      throw common::ConfigError("--off-centre", "",
                                fmt::format("{},{} is not inside 0.9 circumradius (the danger circle is at 1)",
                                            off_centre[0], off_centre[1]));
    common::prepareOutputDir(out);
    const auto& v = cfg.scenario.vision;
    eo.seed = seed ? seed : v.seed ? v.seed : models::componentSeed(cfg.scenario.seed, "vision");
    eo.ins_offset = Eigen::Vector2d(ins_offset[0], ins_offset[1]);
    eo.off_centre = Eigen::Vector2d(off_centre[0], off_centre[1]);
    eo.ins_heading_error = heading_arcmin * 60.0 * models::kArcSec;
    const auto t0 = std::chrono::steady_clock::now();
    auto last = t0;
    eo.progress = [&](int64_t done, int64_t total) {
      const auto now = std::chrono::steady_clock::now();
      if (done < total && now - last < std::chrono::seconds(1)) return;
      last = now;
      spdlog::info("{}/{} runs ({:.0f} %)", done, total, 100.0 * static_cast<double>(done) / static_cast<double>(total));
    };
    if (log_file.empty())
      spdlog::info("{} runs per case, seed {}, noise {:.1f}\", resolution {:.1f}\", distance {} m", eo.runs, eo.seed,
                 v.bearing_std / models::kArcSec, v.resolution / models::kArcSec, eo.distance);
    if (!log_file.empty() && cfg.scenario.landmarks.empty())
      throw common::ConfigError(cfg.file, "landmarks", "--log needs the landmark map of the recorded run");
    bool damaged = false;
    const auto r = log_file.empty()
                       ? landmark_experiment::run(v, eo)
                       : landmark_experiment::runObservations(cfg.scenario.landmarks,
                                                              readLog(log_file, cfg.channels, &damaged), eo);
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const bool plotted = landmark_experiment::writeReport(r, out);
    std::fputs(landmark_experiment::summaryTable(r).c_str(), stdout);
    std::printf("%d %s solved in %.2f s; report: %s/report.json%s\n", r.options.runs,
                log_file.empty() ? "runs x 4 cases" : "observations", elapsed, out.c_str(),
                plotted ? ", figures <case>.png" : " (gnuplot failed: no figures)");
    return damaged ? common::kExitInputDamaged : common::kExitOk;
  });
}
