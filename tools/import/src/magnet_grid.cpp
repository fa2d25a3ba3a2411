#include "lcmloc/import/magnet_grid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/csv.hpp"
#include "lcmloc/core/vehicle_model.hpp"
#include "lcmloc/eval/gnuplot.hpp"
#include "lcmloc/logio/log_reader.hpp"
#include "lcmloc/eval/trajectory.hpp"
#include "lcmloc/fusion_status_t.hpp"
#include "lcmloc/gate_decision_t.hpp"
#include "lcmloc/import/checks.hpp"
#include "lcmloc/import/event_log.hpp"
#include "lcmloc/magruler_t.hpp"
#include "lcmloc/odometry_t.hpp"
#include "lcmloc/pose_t.hpp"
#include "lcmloc/replay/replay.hpp"
#include "lcmloc/eval/report.hpp"

namespace lcmloc::import {
namespace fs = std::filesystem;
namespace {

constexpr double kPi = 3.14159265358979323846;

/// An open magnet pass: consecutive samples in which a group of closed switches stays at about
/// the same place in the row.
struct Pass {
  double centre_sum = 0, last_centre = 0;
  int n = 0;
  int64_t t_first = 0, t_last = 0;
  bool seen = false;
};

/// Centres (bit index, fractional for a group) of the groups of adjacent closed switches.
std::vector<double> groups(int byte) {
  std::vector<double> out;
  int i = 0;
  while (i < 8) {
    if ((byte >> i) & 1) { ++i; continue; }
    int j = i;
    while (j + 1 < 8 && !((byte >> (j + 1)) & 1)) ++j;
    out.push_back(0.5 * (i + j));
    i = j + 1;
  }
  return out;
}


}  // namespace

MagnetGridImport importMagnetGrid(const MagnetGridOptions& opt) {
  if (opt.bit0 != "right" && opt.bit0 != "left") throw std::invalid_argument("bit0 must be 'right' or 'left'");
  if (!(opt.wheel_radius > 0 && opt.track > 0 && opt.dots_per_rev > 0 && opt.grid > 0 && opt.reed_offset > 0))
    throw std::invalid_argument("wheel radius, track, dots per revolution, grid and reed offset must be > 0");
  // What goes into config.yaml and map.csv: refused with the flag's name, before anything is
  // written, rather than by the replay naming the generated file.
  checkFilterValue("--filter", "type", opt.filter);
  checkFilterValue("--pv-diag", "pv_diag", fmt::format("[{}, {}]", opt.pv_diag[0], opt.pv_diag[1]));
  checkFilterValue("--pw-diag", "pw_diag", fmt::format("[{}, {}, {}]", opt.pw_diag[0], opt.pw_diag[1], opt.pw_diag[2]));
  checkFilterValue("--pw-turn", "pw_turn", fmt::format("{}", opt.pw_turn));
  checkFilterValue("--reach", "reach_forward", fmt::format("{}", opt.reach));
  if (!std::isfinite(opt.grid_angle))
    throw app::ConfigError("--grid-angle", "", fmt::format("{} is not an angle [rad]", opt.grid_angle));
  if (!opt.out_dir.empty())
    for (const char* name : {"run.lcmlog", "map.csv", "config.yaml"})
      app::refuseOutputOverInputs("--output", (fs::path(opt.out_dir) / name).string(), {opt.input});
  std::ifstream in(opt.input);
  if (!in) throw std::runtime_error("cannot open '" + opt.input + "'");
  MagnetGridImport r;
  const double side = opt.bit0 == "right" ? 1.0 : -1.0;
  const double dot = 2.0 * kPi * opt.wheel_radius / opt.dots_per_rev;
  EventLog log;
  std::string line;
  int64_t lineno = 0, seq_odo = 0;
  bool have_prev = false;
  double l_prev = 0, r_prev = 0;
  core::Vec3 pose = core::Vec3::Zero();
  std::vector<Pass> open;
  std::vector<std::pair<int64_t, core::Vec3>> poses;  // (utime, dead-reckoned pose) for the grid anchor
  auto close = [&](const Pass& p) {
    MagnetDetection d;
    d.utime = (p.t_first + p.t_last) / 2;
    d.lateral = side * (p.centre_sum / p.n - 3.5) * opt.reed_pitch;
    d.samples = p.n;
    r.detections.push_back(d);
  };
  auto refuse = [&](const std::string& why) {
    ++r.refused;
    r.refusals.emplace_back(lineno, why);
  };
  // Read every row first (the time-order rule looks at the rows after each): the four numbers,
  // or why the row is refused; times in microseconds; then the time-order rule.
  struct Sample {
    int64_t line = 0;
    double v[4] = {0, 0, 0, 0};
    std::string why;  ///< "" = usable so far
  };
  std::vector<Sample> samples;
  std::vector<std::optional<int64_t>> utimes;
  while (std::getline(in, line)) {
    ++lineno;
    std::istringstream ss(line);
    std::vector<std::string> f;
    std::string tok;
    while (ss >> tok) f.push_back(tok);
    if (f.empty()) continue;
    Sample& sm = samples.emplace_back();
    sm.line = lineno;
    utimes.emplace_back();
    if (f.size() < 4) { sm.why = fmt::format("expected at least 4 columns, got {}", f.size()); continue; }
    bool ok = true;
    for (int i = 0; i < 4 && ok; ++i) ok = app::csv::parseNumber(f[static_cast<std::size_t>(i)], i + 1, sm.v[i], sm.why);
    if (!ok) continue;
    if (sm.v[2] < 0 || sm.v[2] > 255 || sm.v[2] != std::floor(sm.v[2])) {
      sm.why = fmt::format("reed byte {} not in 0..255", f[2]);
      continue;
    }
    if (sm.v[3] < 0) { sm.why = "negative time"; continue; }
    utimes.back() = toMicros(sm.v[3], 1e6);
    if (!utimes.back()) sm.why = fmt::format("time {} s out of range", f[3]);
  }
  const auto order = checkTimeOrder(utimes, true);
  for (std::size_t i = 0; i < samples.size(); ++i)
    if (order[i].kind != TimeVerdict::Kept)
      samples[i].why = timeOrderReason(utimes, i, order[i], true,
                                       [&](std::size_t k) { return fmt::format("{} s", samples[k].v[3]); });
  for (std::size_t k = 0; k < samples.size(); ++k) {
    lineno = samples[k].line;
    const double* v = samples[k].v;
    ++r.rows;
    if (!samples[k].why.empty()) { refuse(samples[k].why); continue; }
    const int64_t t = *utimes[k];
    if (have_prev && (std::abs(v[0] - l_prev) > opt.max_step_dots || std::abs(v[1] - r_prev) > opt.max_step_dots)) {
      refuse(fmt::format("encoder jump ({}, {}) dots above {}", v[0] - l_prev, v[1] - r_prev, opt.max_step_dots));
      continue;
    }
    // odometry over (previous row, this row]
    lcmloc::odometry_t m{};
    m.utime = t;
    m.seq = seq_odo++;
    if (have_prev) {
      const double dl = (v[0] - l_prev) * dot, dr = (v[1] - r_prev) * dot;
      m.delta_s = 0.5 * (dl + dr);
      m.delta_theta = (dr - dl) / opt.track;
      m.ticks = static_cast<int64_t>(std::llround(0.5 * ((v[0] - l_prev) + (v[1] - r_prev))));
    }
    m.has_steering = false;
    pose = core::propagatePose(pose, m.delta_s, m.delta_theta);
    r.distance_m += std::abs(m.delta_s);
    r.turned_rad += std::abs(m.delta_theta);
    log.add(m.utime, 0, "ODOMETRY", m);
    ++r.odometry;
    r.dead_reckoning.push_back(pose);
    poses.emplace_back(t, pose);
    // reed switches: continue or open passes, close the ones not seen
    const int byte = static_cast<int>(v[2]);
    if (byte != 255) ++r.detecting_samples;
    for (auto& p : open) p.seen = false;
    for (double c : groups(byte)) {
      Pass* match = nullptr;
      for (auto& p : open)
        if (!p.seen && std::abs(p.last_centre - c) <= 1.5) { match = &p; break; }
      if (!match) {
        open.push_back({});
        match = &open.back();
        match->t_first = t;
      }
      match->centre_sum += c;
      match->last_centre = c;
      ++match->n;
      match->t_last = t;
      match->seen = true;
    }
    for (auto it = open.begin(); it != open.end();) {
      if (!it->seen) { close(*it); it = open.erase(it); } else ++it;
    }
    have_prev = true;
    l_prev = v[0];
    r_prev = v[1];
  }
  for (const auto& p : open) close(p);
  if (r.odometry == 0) throw std::runtime_error("'" + opt.input + "': no usable row");
  std::sort(r.detections.begin(), r.detections.end(),
            [](const MagnetDetection& a, const MagnetDetection& b) { return a.utime < b.utime; });
  r.first_utime = poses.front().first;
  r.last_utime = poses.back().first;

  for (std::size_t i = 0; i < r.detections.size(); ++i) {
    const auto& d = r.detections[i];
    lcmloc::magruler_t m{};
    m.utime = d.utime;
    m.seq = static_cast<int64_t>(i);
    m.num_sensors = 0;  // the reed byte is not a field reading
    m.detected = true;
    m.lateral_offset = d.lateral;
    m.quality = 1.0;
    log.add(m.utime, 1, "MAGRULER", m);
  }

  // The grid: a node at the first detected magnet as dead reckoning places it, axes at
  // grid_angle from the start heading, covering the dead-reckoned reed-row track + margin.
  core::Vec3 at = poses.front().second;
  if (!r.detections.empty()) {
    const int64_t td = r.detections.front().utime;
    for (const auto& [t, p] : poses)
      if (t <= td) at = p;
    const double lat = r.detections.front().lateral;
    r.anchor = core::Vec2(at.x() + opt.reed_offset * std::cos(at.z()) - lat * std::sin(at.z()),
                          at.y() + opt.reed_offset * std::sin(at.z()) + lat * std::cos(at.z()));
  }
  const double ca = std::cos(opt.grid_angle), sa = std::sin(opt.grid_angle);
  double umin = 1e9, umax = -1e9, vmin = 1e9, vmax = -1e9;
  for (const auto& [t, p] : poses) {
    const double x = p.x() + opt.reed_offset * std::cos(p.z()) - r.anchor.x();
    const double y = p.y() + opt.reed_offset * std::sin(p.z()) - r.anchor.y();
    const double u = ca * x + sa * y, w = -sa * x + ca * y;
    umin = std::min(umin, u); umax = std::max(umax, u);
    vmin = std::min(vmin, w); vmax = std::max(vmax, w);
  }
  const int i0 = static_cast<int>(std::floor((umin - opt.grid_margin) / opt.grid));
  const int i1 = static_cast<int>(std::ceil((umax + opt.grid_margin) / opt.grid));
  const int j0 = static_cast<int>(std::floor((vmin - opt.grid_margin) / opt.grid));
  const int j1 = static_cast<int>(std::ceil((vmax + opt.grid_margin) / opt.grid));
  int id = 0;
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      const double u = i * opt.grid, w = j * opt.grid;
      r.map.push_back({id++, r.anchor.x() + ca * u - sa * w, r.anchor.y() + sa * u + ca * w});
    }

  if (!opt.out_dir.empty()) {
    fs::create_directories(opt.out_dir);
    r.log_path = (fs::path(opt.out_dir) / "run.lcmlog").string();
    r.map_path = (fs::path(opt.out_dir) / "map.csv").string();
    r.config_path = (fs::path(opt.out_dir) / "config.yaml").string();
    log.write(r.log_path);
    app::csv::writeMap(r.map_path, r.map);
    std::ofstream c(r.config_path);
    c << "# Written by lcmloc-magnet-grid --import-only from " << opt.input << " (docs/magnet_grid.md).\n"
      << "# Replay: lcmloc-replay run.lcmlog --config config.yaml -o estimates.lcmlog\n"
      << "scenario: {name: " << opt.name << ", seed: 1, realtime_factor: 0.0}\n"
      << "markers: {count: 0}              # the map is fusion.map_file (the 55 mm grid)\n"
      << "fusion:\n"
      << "  shadow: [dead_reckoning]\n"
      << "  map_file: map.csv\n"
      << "  filter:\n"
      << "    type: " << opt.filter << "\n"
      << fmt::format("    wheelbase: {}             # unused: the odometry carries delta_theta\n", opt.track)
      << fmt::format("    ruler_offset: {}            # reed row ahead of the wheel axle [m]\n", opt.reed_offset)
      << fmt::format("    ruler_half_width: {}       # 8 switches {} m apart [m]\n", 3.5 * opt.reed_pitch, opt.reed_pitch)
      << "    initial_pose: [0.0, 0.0, 0.0]     # the start pose defines the frame\n"
      << fmt::format("    p0_diag: [{}, {}, {}]\n", opt.p0_diag[0], opt.p0_diag[1], opt.p0_diag[2])
      << fmt::format("    pw_diag: [{}, {}, {}]\n", opt.pw_diag[0], opt.pw_diag[1], opt.pw_diag[2])
      << fmt::format("    pw_distance: {}\n", opt.pw_distance)
      << fmt::format("    pw_turn: {}\n", opt.pw_turn)
      << fmt::format("    pv_diag: [{}, {}]        # range (along track) [m^2], bearing [rad^2]\n", opt.pv_diag[0],
                     opt.pv_diag[1])
      << fmt::format("    reach_forward: {}\n    reach_lateral: {}\n", opt.reach, opt.reach)
      << "    gate: {enabled: true, probability: 0.99, dof: 0}\n";
    if (!c) throw std::runtime_error("cannot write '" + r.config_path + "'");
  }
  return r;
}

MagnetGridReport runMagnetGrid(const MagnetGridOptions& opt, MagnetGridImport* imported) {
  if (opt.out_dir.empty()) throw std::invalid_argument("runMagnetGrid needs an output directory");
  const auto imp = importMagnetGrid(opt);
  if (imported) *imported = imp;
  const auto cfg = app::loadSystemConfig(imp.config_path);
  replay::ReplayOptions ro;
  ro.input = imp.log_path;
  ro.output = (fs::path(opt.out_dir) / "estimates.lcmlog").string();
  ro.progress_period_s = 0;
  replay::replayLog(cfg, ro);

  MagnetGridReport rep;
  rep.run = opt.name;
  rep.detections = static_cast<int64_t>(imp.detections.size());
  const std::string active = cfg.fusion.filter.type;
  const std::string dr_channel = cfg.channels.pose + "_DEAD_RECKONING";
  std::vector<double> nis, nis_acc;
  std::set<int> magnets;
  std::vector<std::array<double, 4>> track, dr;  // t, x, y, theta
  std::vector<std::array<double, 3>> accepted_at, rejected_at;  // magnet x, y / reed-row x, y
  lcmloc::pose_t last{};
  double prior_sigma = 0;
  int64_t decisions = 0;  // of the reed-row position, from the last pose before a decision
  bool have_last = false;
  const double t0 = imp.first_utime * 1e-6;
  logio::scanLog(ro.output, [&](const logio::RawEvent& e) {
    if (*e.channel == cfg.channels.pose) {
      lcmloc::pose_t p;
      if (logio::decodeEvent(e, p) && p.dim >= 3) {
        track.push_back({p.utime * 1e-6 - t0, p.state[0], p.state[1], p.state[2]});
        last = p;
        have_last = true;
        prior_sigma = std::sqrt(std::max(0.0, p.covariance[0][0] + p.covariance[1][1] +
                                                  opt.reed_offset * opt.reed_offset * p.covariance[2][2]));
      }
    } else if (*e.channel == dr_channel) {
      lcmloc::pose_t p;
      if (logio::decodeEvent(e, p) && p.dim >= 3) dr.push_back({p.utime * 1e-6 - t0, p.state[0], p.state[1], p.state[2]});
    } else if (*e.channel == cfg.channels.gate) {
      lcmloc::gate_decision_t g;
      if (!logio::decodeEvent(e, g) || g.filter != active) return;
      rep.gate = g.gate;
      if (decisions++ > 0)  // the first pass is the grid's anchor: associated by construction
        rep.max_prior_sigma = std::max(rep.max_prior_sigma, prior_sigma);
      if (g.accepted) ++rep.accepted;
      else if (g.reason == "gate") ++rep.rejected_gate;
      else if (g.reason == "no_candidate") ++rep.no_candidate;
      if (g.marker_id >= 0 && g.dim == 2) {
        nis.push_back(g.mahalanobis);
        if (g.accepted) {
          nis_acc.push_back(g.mahalanobis);
          magnets.insert(g.marker_id);
        }
        const auto& m = imp.map[static_cast<std::size_t>(g.marker_id)];
        (g.accepted ? accepted_at : rejected_at).push_back({g.utime * 1e-6 - t0, m.x, m.y});
      }
    } else if (*e.channel == cfg.channels.status) {
      lcmloc::fusion_status_t st;
      if (logio::decodeEvent(e, st) && st.event == "lockout") ++rep.lockouts;
    }
  });
  rep.with_candidate = static_cast<int64_t>(nis.size());
  if (!nis.empty()) {
    double s = 0;
    int within = 0, w95 = 0;
    for (double v : nis) {
      s += v;
      within += v <= rep.gate;
      w95 += v <= 5.991464547107979;
    }
    rep.nis_mean = s / nis.size();
    rep.nis_median = eval::percentile(nis, 0.5);
    rep.within_gate = static_cast<double>(within) / nis.size();
    rep.within_95 = static_cast<double>(w95) / nis.size();
  }
  if (!nis_acc.empty()) {
    double s = 0;
    for (double v : nis_acc) s += v;
    rep.nis_mean_accepted = s / nis_acc.size();
  }
  rep.distinct_magnets = static_cast<int>(magnets.size());
  if (have_last && last.dim >= 3) {
    rep.final_sigma_xy = std::sqrt(std::max(0.0, last.covariance[0][0] + last.covariance[1][1]));
    rep.final_sigma_theta = std::sqrt(std::max(0.0, last.covariance[2][2]));
  }
  if (!track.empty() && !dr.empty())
    rep.dr_gap_m = std::hypot(track.back()[1] - dr.back()[1], track.back()[2] - dr.back()[2]);

  // report.json, data files and the plot
  nlohmann::json j;
  j["run"] = opt.name;
  j["input"] = opt.input;
  j["import"] = {{"rows", imp.rows}, {"refused", imp.refused}, {"odometry_messages", imp.odometry},
                 {"detecting_samples", imp.detecting_samples}, {"magnet_passes", imp.detections.size()},
                 {"duration_s", (imp.last_utime - imp.first_utime) * 1e-6}, {"distance_m", imp.distance_m},
                 {"turned_rad", imp.turned_rad}, {"map_magnets", imp.map.size()}, {"bit0", opt.bit0}};
  j["filter"] = active;
  j["gate"] = {{"threshold", rep.gate}, {"accepted", rep.accepted}, {"rejected_gate", rep.rejected_gate},
               {"no_candidate", rep.no_candidate}, {"lockouts", rep.lockouts},
               {"distinct_magnets_accepted", rep.distinct_magnets}};
  j["nis"] = {{"dof", 2}, {"count", rep.with_candidate}, {"mean", rep.nis_mean}, {"expected_mean", 2.0},
              {"median", rep.nis_median}, {"expected_median", 1.386}, {"within_gate", rep.within_gate},
              {"expected_within_gate", 0.99}, {"within_95", rep.within_95}, {"expected_within_95", 0.95},
              {"mean_accepted", rep.nis_mean_accepted}};
  j["association"] = {{"max_prior_sigma_m", rep.max_prior_sigma}, {"half_grid_m", 0.5 * opt.grid},
                      {"note", "largest 1-sigma of the reed-row position before a detection (the first, the grid anchor, excluded) vs half the magnet spacing"}};
  j["final"] = {{"sigma_xy_m", rep.final_sigma_xy}, {"sigma_theta_rad", rep.final_sigma_theta},
                {"gap_to_dead_reckoning_m", rep.dr_gap_m}};
  eval::writeJson(j, (fs::path(opt.out_dir) / "report.json").string());
  {
    std::ofstream g(fs::path(opt.out_dir) / "grid.dat");
    for (const auto& m : imp.map) g << m.x << ' ' << m.y << '\n';
    std::ofstream t(fs::path(opt.out_dir) / "track.dat");
    t << "# t[s] x y theta (" << active << ")\n";
    for (const auto& p : track) t << p[0] << ' ' << p[1] << ' ' << p[2] << ' ' << p[3] << '\n';
    std::ofstream d(fs::path(opt.out_dir) / "dead_reckoning.dat");
    for (const auto& p : dr) d << p[0] << ' ' << p[1] << ' ' << p[2] << ' ' << p[3] << '\n';
    std::ofstream a(fs::path(opt.out_dir) / "accepted.dat"), b(fs::path(opt.out_dir) / "rejected.dat");
    for (const auto& p : accepted_at) a << p[0] << ' ' << p[1] << ' ' << p[2] << '\n';
    for (const auto& p : rejected_at) b << p[0] << ' ' << p[1] << ' ' << p[2] << '\n';
    if (rejected_at.empty()) b << "nan nan nan\n";
    if (accepted_at.empty()) a << "nan nan nan\n";
    std::ofstream gp(fs::path(opt.out_dir) / "plot.gp");
    gp << "set terminal pngcairo size 1000,1000 noenhanced\nset output 'track.png'\nset size ratio -1\n"
       << fmt::format("set title '{}: {} over the 55 mm magnet grid ({} of {} passes accepted, NIS mean {:.2f} vs 2)'\n",
                      opt.name, active, rep.accepted, rep.detections, rep.nis_mean)
       << "set xlabel 'x [m] (start frame)'\nset ylabel 'y [m]'\nset key outside bottom center horizontal\n"
       << "plot 'grid.dat' using 1:2 with points pt 6 ps 0.5 lc rgb '#bbbbbb' title 'magnets', "
       << "'dead_reckoning.dat' using 2:3 with lines lw 1 lc rgb '#ff7f0e' title 'dead reckoning', "
       << "'track.dat' using 2:3 with lines lw 1.5 lc rgb '#1f77b4' title '" << active << "', "
       << "'accepted.dat' using 2:3 with points pt 7 ps 0.8 lc rgb '#2ca02c' title 'associated magnet (accepted)', "
       << "'rejected.dat' using 2:3 with points pt 2 ps 1.0 lc rgb '#d62728' title 'nearest magnet (gate rejected)'\n";
  }
  if (eval::runGnuplot(opt.out_dir, "plot.gp") != 0) spdlog::warn("gnuplot failed (see {}/gnuplot.log): no figure", opt.out_dir);
  return rep;
}

}  // namespace lcmloc::import
