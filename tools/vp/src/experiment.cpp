#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <optional>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "lcmloc/core/scoring.hpp"
#include "lcmloc/eval/gnuplot.hpp"
#include "lcmloc/logio/log_reader.hpp"
#include "lcmloc/eval/trajectory.hpp"
#include "lcmloc/fusion_status_t.hpp"
#include "lcmloc/gate_decision_t.hpp"
#include "lcmloc/pose_t.hpp"
#include "lcmloc/replay/replay.hpp"
#include "lcmloc/vp/vp.hpp"
#include "lcmloc/eval/report.hpp"
#include "lcmloc/fit/fit_log.hpp"
#include "lcmloc/fit/innovation_fit.hpp"

namespace lcmloc::vp {

bool interpolate(const std::vector<std::array<double, 3>>& tr, double t, double& x, double& y) {
  if (tr.empty() || t < tr.front()[0] || t > tr.back()[0]) return false;
  auto it = std::lower_bound(tr.begin(), tr.end(), t, [](const std::array<double, 3>& p, double v) { return p[0] < v; });
  if (it == tr.begin() || (*it)[0] == t) {
    x = (*it)[1];
    y = (*it)[2];
    return true;
  }
  const auto& b = *it;
  const auto& a = *(it - 1);
  const double w = (t - a[0]) / (b[0] - a[0]);
  x = a[1] + w * (b[1] - a[1]);
  y = a[2] + w * (b[2] - a[2]);
  return true;
}

namespace {
/// The import options of the experiment: its log in out_dir, the datum and channels of cfg.
ImportOptions experimentImport(const app::SystemConfig& cfg, ImportOptions imp, const ExperimentOptions& opt) {
  imp.output = opt.out_dir + "/vp.lcmlog";
  imp.datum = cfg.datum;
  imp.odometry_channel = cfg.channels.odometry;
  imp.gps_channel = cfg.channels.gps;
  return imp;
}
}  // namespace

void checkExperimentOptions(const app::SystemConfig& cfg, const ImportOptions& imp, const ExperimentOptions& opt) {
  if (opt.filters.empty()) throw app::ConfigError("--filters", "", "no filter given");
  app::checkFilterList(opt.filters, "--filters", "filters");
  if (imp.holdout_every < 2)
    throw app::ConfigError(
        "--holdout-every", "",
        fmt::format("{} is not >= 2: {}", imp.holdout_every,
                    imp.holdout_every == 1 ? "every fix would be held out and the filters would run without GPS"
                                           : "no fix would be held out and nothing scored"));
  checkImportOptions(experimentImport(cfg, imp, opt));
}

ExperimentResult runExperiment(const app::SystemConfig& cfg0, ImportOptions imp, const ExperimentOptions& opt) {
  namespace fs = std::filesystem;
  const auto t_start = std::chrono::steady_clock::now();
  checkExperimentOptions(cfg0, imp, opt);
  fs::create_directories(opt.out_dir);
  ExperimentResult res;
  imp = experimentImport(cfg0, imp, opt);
  res.log_path = imp.output;
  res.import = importVictoriaPark(imp);
  spdlog::info("imported -> {}\n{}", res.log_path, importSummary(imp, res.import, 5));
  const auto& fixes = res.import.fixes;
  if (fixes.empty()) throw std::runtime_error("no GPS fix imported: nothing to score against");
  const double t0 = static_cast<double>(res.import.first_utime) * 1e-6;

  // initial pose from the first (filter-visible) fixes
  core::Vec3 init = cfg0.fusion.filter.initial_pose;
  if (opt.init_from_gps) {
    const Fix* first = nullptr;
    for (const auto& f : fixes) {
      if (f.heldout) continue;
      if (!first) {
        first = &f;
        init = core::Vec3(f.x, f.y, init[2]);
      } else if (std::hypot(f.x - first->x, f.y - first->y) >= opt.init_course_m) {
        init[2] = std::atan2(f.y - first->y, f.x - first->x);
        break;
      }
    }
    spdlog::info("initial pose from GPS: x {:.2f} m, y {:.2f} m, heading {:.3f} rad", init[0], init[1], init[2]);
  }

  std::optional<fit::Recording> recording;  // the imported log as the noise fit reads it
  for (const auto& type : opt.filters) {
    if (imp.stop && imp.stop()) break;
    app::SystemConfig cfg = cfg0;
    YAML::Node n;
    n["type"] = type;
    cfg.fusion.filter = app::parseFilterConfig(n, cfg0.fusion.filter, "--filters", "fusion.filter");
    cfg.fusion.filter.initial_pose = init;
    cfg.fusion.shadow.clear();
    if (opt.fit_noise && type != "dead_reckoning") {
      if (!recording) recording = fit::readRecording(res.log_path, cfg).recording;  // the same log for every filter
      fit::InnovationFitOptions fo;
      fo.channels = {cfg.channels.odometry, cfg.channels.landmarks, cfg.channels.beacons, cfg.channels.gps};
      const auto fitted = fit::fitByInnovations(*recording, app::engineConfig(cfg), fo);
      cfg.fusion.filter = fitted.filter;
      spdlog::info("{}: noise fitted to the innovations of the fixes it is given: position_rw {:.4g} m/sqrt(s) (mean "
                   "prediction error {:.3g} m, {:.3g} m as configured), gps_std {:.4g} m{}",
                   type, cfg.fusion.filter.gnss.position_rw, fitted.rw_error.second, fitted.rw_error.first,
                   cfg.fusion.filter.gnss.gps_std, fitted.notes.empty() ? "" : "; " + fmt::format("{}", fmt::join(fitted.notes, "; ")));
    }
    replay::ReplayOptions ro;
    ro.input = res.log_path;
    ro.output = opt.out_dir + "/" + type + ".lcmlog";
    ro.progress_period_s = 5.0;
    ro.stop = imp.stop;
    const auto rr = replay::replayLog(cfg, ro);
    spdlog::info("{}: {} events read, {} used, {} rejected, {} written in {:.2f} s", type, rr.events_read, rr.used,
                 rr.rejected, rr.written, rr.seconds);
    Score s;
    s.filter = type;
    s.position_rw = cfg.fusion.filter.gnss.position_rw;
    s.gps_std = cfg.fusion.filter.gnss.gps_std;
    std::optional<int64_t> refused_since;  // the first refused fix of the current run
    logio::scanLog(ro.output, [&](const logio::RawEvent& e) {
      if (*e.channel == cfg.channels.pose) {
        lcmloc::pose_t p;
        if (logio::decodeEvent(e, p) && p.dim >= 2) {
          ++s.poses;
          const double t = static_cast<double>(p.utime) * 1e-6 - t0;
          if (!s.track.empty() && t == s.track.back()[0]) s.track.back() = {t, p.state[0], p.state[1]};
          else s.track.push_back({t, p.state[0], p.state[1]});
        }
      } else if (*e.channel == cfg.channels.gate) {
        lcmloc::gate_decision_t g;
        if (logio::decodeEvent(e, g) && g.sensor == cfg.channels.gps && g.reason != "no_fix") {
          (g.accepted ? s.gps_accepted : s.gps_rejected)++;
          if (!g.accepted && !refused_since) refused_since = g.utime;
          if (g.accepted && refused_since) {
            s.longest_rejection_s = std::max(s.longest_rejection_s, 1e-6 * static_cast<double>(g.utime - *refused_since));
            refused_since.reset();
          }
        }
      } else if (*e.channel == cfg.channels.status) {
        lcmloc::fusion_status_t st;
        if (logio::decodeEvent(e, st)) {
          if (st.event == "lockout") ++s.lockouts;
          if (st.event == "relocalized") ++s.relocalized;
        }
      }
    });
    std::error_code ec;
    fs::remove(ro.output, ec);  // the pose stream is in the data files; the log is large
    std::vector<double> errs;
    for (const auto& f : fixes) {
      if (!f.heldout) continue;
      double x = 0, y = 0;
      const double t = static_cast<double>(f.utime) * 1e-6 - t0;
      if (!interpolate(s.track, t, x, y)) continue;
      const double e = std::hypot(x - f.x, y - f.y);
      s.t.push_back(t);
      s.err.push_back(e);
    }
    s.scored = static_cast<int64_t>(s.err.size());
    const auto st = core::errorStats(s.err);
    s.rmse_m = st.rmse;
    s.median_m = st.median;
    s.p95_m = st.p95;
    s.max_m = st.max;
    res.scores.push_back(std::move(s));
  }

  // report.json
  nlohmann::json j;
  const auto& ir = res.import;
  j["import"] = {{"odometry_rows", ir.odometry_rows}, {"odometry_refused", ir.odometry_refused},
                 {"odometry_messages", ir.odometry_written}, {"gps_rows", ir.gps_rows},
                 {"gps_refused", ir.gps_refused}, {"gps_fixes_to_filter", ir.gps_written},
                 {"gps_fixes_held_out", ir.heldout_written}, {"holdout_every", imp.holdout_every},
                 {"holdout_phase", imp.holdout_phase}, {"distance_m", ir.distance_m},
                 {"duration_s", (ir.last_utime - ir.first_utime) * 1e-6}, {"wheelbase_m", imp.wheelbase},
                 {"encoder_offset_m", imp.encoder_offset}};
  j["initial_pose"] = {init[0], init[1], init[2]};
  j["course_distance_m"] = cfg0.fusion.filter.gnss.course_distance;
  for (const auto& s : res.scores)
    j["filters"][s.filter] = {{"poses", s.poses}, {"heldout_scored", s.scored}, {"rmse_m", s.rmse_m},
                              {"median_m", s.median_m}, {"p95_m", s.p95_m}, {"max_m", s.max_m},
                              {"gps_accepted", s.gps_accepted}, {"gps_rejected", s.gps_rejected},
                              {"lockouts", s.lockouts}, {"relocalized", s.relocalized},
                              {"longest_rejection_s", s.longest_rejection_s}, {"position_rw", s.position_rw},
                              {"gps_std", s.gps_std}};
  j["noise_fitted"] = opt.fit_noise;
  eval::writeJson(j, opt.out_dir + "/report.json");

  // figures
  {
    std::ofstream g(opt.out_dir + "/gps.dat"), h(opt.out_dir + "/heldout.dat");
    g << "# t[s] x y\n";
    h << "# t[s] x y\n";
    for (const auto& f : fixes)
      (f.heldout ? h : g) << static_cast<double>(f.utime) * 1e-6 - t0 << ' ' << f.x << ' ' << f.y << '\n';
  }
  std::string pa, pb;
  const char* colors[] = {"#d62728", "#1f77b4", "#2ca02c", "#9467bd", "#ff7f0e"};
  int ci = 0;
  for (const auto& s : res.scores) {
    std::ofstream d(opt.out_dir + "/" + s.filter + "_track.dat");
    d << "# t[s] x y (every 10th pose)\n";
    for (std::size_t i = 0; i < s.track.size(); i += 10)
      d << s.track[i][0] << ' ' << s.track[i][1] << ' ' << s.track[i][2] << '\n';
    std::ofstream e(opt.out_dir + "/" + s.filter + "_err.dat");
    e << "# t[s] error at the held-out fix [m]\n";
    for (std::size_t i = 0; i < s.t.size(); ++i) e << s.t[i] << ' ' << s.err[i] << '\n';
    const std::string c = colors[ci++ % 5];
    pa += fmt::format(", '{}_track.dat' using 2:3 with lines lw 1.5 lc rgb '{}' title '{} (RMSE {:.2f} m)'", s.filter,
                      c, s.filter, s.rmse_m);
    pb += fmt::format("{}'{}_err.dat' using 1:2 with points pt 7 ps 0.4 lc rgb '{}' title '{}'", pb.empty() ? "" : ", ",
                      s.filter, c, s.filter);
  }
  {
    std::ofstream gp(opt.out_dir + "/plot.gp");
    gp << "set terminal pngcairo size 1200,1000 noenhanced\nset grid\nset output 'drive.png'\n"
       << "set title 'Victoria Park: GPS fixes given to the filter, held-out fixes, fused tracks'\n"
       << "set xlabel 'x east [m]'\nset ylabel 'y north [m]'\nset size ratio -1\nset key outside bottom center horizontal\n"
       << "plot 'gps.dat' using 2:3 with points pt 7 ps 0.35 lc rgb '#aaaaaa' title 'GPS (to the filter)', "
       << "'heldout.dat' using 2:3 with points pt 6 ps 0.6 lc rgb 'black' title 'GPS held out'" << pa << "\n";
    if (!pb.empty())
      gp << "set output 'error.png'\nset terminal pngcairo size 1200,600 noenhanced\nset size noratio\n"
         << "set title 'Error of the fused track at the held-out fixes'\nset xlabel 't [s]'\n"
         << "set ylabel 'error [m]'\nset logscale y\nset key top left\nplot " << pb << "\n";
  }
  if (eval::runGnuplot(opt.out_dir, "plot.gp") != 0) spdlog::warn("gnuplot failed (see {}/gnuplot.log): no figures", opt.out_dir);
  res.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  return res;
}

}  // namespace lcmloc::vp
