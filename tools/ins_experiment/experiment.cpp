#include "lcmloc/ins_experiment/experiment.hpp"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <optional>
#include <vector>

#include <nlohmann/json.hpp>

#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/engine.hpp"
#include "lcmloc/core/scoring.hpp"
#include "lcmloc/eval/gnuplot.hpp"
#include "lcmloc/eval/report.hpp"

namespace lcmloc::ins_experiment {

RunResult run(const std::string& name, const sim::InsSimConfig& cfg, const core::FilterConfig& base,
              int64_t start_utime, const Options& opt, const StepSink& sink,
              const std::function<void(double)>& progress) {
  RunResult r;
  r.name = name;
  r.start = cfg.start;
  sim::InsSim sim(cfg, start_utime);

  core::EngineConfig ec;
  ec.filter = base;
  ec.filter.type = "odo_ins";
  ec.filter.ins.latitude = cfg.latitude;
  ec.filter.ins.longitude = cfg.longitude;
  ec.filter.ins.height = cfg.height;
  ec.filter.initial_pose = core::Vec3(0.0, 0.0, cfg.heading);
  ec.shadow = {"odo_ins_uncal"};
  ec.reorder_window_us = 0;  // inputs are produced in order
  std::optional<sim::VisionSensor> vision;
  if (opt.fixes) {
    ec.landmarks = sim::landmarkMap(opt.landmarks);
    ec.fix = opt.fix;
    ec.fix_gate = opt.fix_gate;
    vision.emplace(opt.vision, opt.landmarks, opt.vision_seed);
  }
  std::map<std::string, core::FilterState> latest;
  core::EngineOutputs out;
  out.on_state = [&](const std::string& f, bool, const core::FilterState& s) { latest[f] = s; };
  out.on_decision = [&](const std::string& f, bool active, const core::GateDecision& d) {
    if (active && f == "odo_ins" && d.reason == "imu_gap") ++r.imu_gaps;
    if (active && d.sensor == "VISION" && !d.accepted && d.reason != "bad_input") ++r.fix_refused;
  };
  core::FusionEngine engine(ec, {}, out);
  // Vision at this step's truth; three bearings: the fix, with the errors before and after it.
  auto fix = [&](const sim::InsSimStep& st, int64_t& seq) {
    const auto obs = vision->sample(st.truth);
    if (!obs || obs->ids.size() != 3) return;
    auto err = [&](const char* f) {
      auto i = latest.find(f);
      return i == latest.end() ? NAN : std::hypot(i->second.x[0] - st.truth.x, i->second.x[1] - st.truth.y);
    };
    FixPoint p{(st.truth.utime - start_utime) * 1e-6, st.truth.distance, err("odo_ins"), 0, err("odo_ins_uncal"), 0};
    core::EngineInput in;
    in.channel = "VISION";
    in.seq = seq++;
    in.utime = obs->utime;
    core::BearingsInput b;
    b.utime = obs->utime;
    b.seq = in.seq;
    b.ids = obs->ids;
    b.bearings = obs->bearings;
    b.bearing_std = obs->bearing_std;
    in.payload = b;
    engine.push(std::move(in));
    engine.flush();
    p.after_cal = err("odo_ins");
    p.after_uncal = err("odo_ins_uncal");
    r.fixes.push_back(p);
  };

  const sim::InsSimStep s0 = sim.initial();
  if (sink) sink(s0);
  if (vision) vision->sample(s0.truth);  // as lcmloc-vision: the first observation at the first truth
  int64_t odo_seq = 0, imu_seq = 0, vision_seq = 0;
  double motion_start = -1, next_record = 0, next_progress = 0.1;
  bool start_recorded = false, ten_recorded = false, sixty_recorded = false;
  // Dead reckoning with the odo_ins heading: frozen scale estimate (after the calibration
  // stage) and no scale estimate (traditional).
  core::Vec2 dr_cal = core::Vec2::Zero(), dr_uncal = core::Vec2::Zero();
  double last_err = 0, last_std = 0;
  double one_order_candidate = -1, std_candidate = -1, std_at_start = 0;
  std::vector<double> k_err_after_10;  // |scale error| from 10 s after the motion started
  int64_t k_below_after_10 = 0;
  sim::InsSimStep st;
  while (!sim.finished()) {
    st = sim.step();
    if (sink) sink(st);
    const double t = (st.truth.utime - start_utime) * 1e-6;
    if (st.odometry) {
      core::EngineInput in;
      in.channel = "ODOMETRY";
      in.seq = odo_seq++;
      in.utime = st.odometry->input.utime;
      in.payload = st.odometry->input;
      engine.push(std::move(in));
    }
    if (st.imu) {
      core::EngineInput in;
      in.channel = "IMU";
      in.seq = imu_seq++;
      in.utime = st.imu->utime;
      in.payload = st.imu->input(in.channel, in.seq);
      engine.push(std::move(in));
    }
    engine.flush();  // the state of this step (compared with this step's truth)
    if (vision) fix(st, vision_seq);
    auto it = latest.find("odo_ins");
    auto iu = latest.find("odo_ins_uncal");
    if (it == latest.end() || iu == latest.end() || it->second.x.size() < 4) continue;
    const core::FilterState& fc = it->second;
    const core::FilterState& fu = iu->second;
    const double k_est = fc.x[3], k_std = std::sqrt(std::max(0.0, fc.P(3, 3)));
    if (motion_start < 0 && st.truth.speed > 0) {
      motion_start = t;
      r.motion_start_s = t;
      r.k_true0 = st.scale_error;
    }
    if (st.odometry) {
      const double ds = st.odometry->input.delta_s;
      const double th = fc.x[2];
      if (t <= motion_start + opt.calibration_stage || motion_start < 0) r.k_frozen = k_est;
      dr_cal += ds / (1.0 + r.k_frozen) * core::Vec2(std::cos(th), std::sin(th));
      dr_uncal += ds * core::Vec2(std::cos(th), std::sin(th));
    }
    const double err = std::abs(k_est - st.scale_error);
    last_err = err;
    last_std = k_std;
    if (motion_start >= 0) {
      const double tm = t - motion_start;
      // First odometer update after the motion started (the estimate has moved since).
      if (!start_recorded && st.odometry && tm > 0) {
        start_recorded = true;
        r.k_err_at_start = err;
        r.k_std_at_start = std_at_start = k_std;
      }
      if (!ten_recorded && tm >= 10.0) {
        ten_recorded = true;
        r.k_err_10s = err;
        r.k_std_10s = k_std;
      }
      if (!sixty_recorded && tm >= 60.0) {
        sixty_recorded = true;
        r.k_err_60s = err;
      }
      const double lim = std::abs(r.k_true0) / 10.0;
      if (start_recorded && err < lim && one_order_candidate < 0) one_order_candidate = tm;
      if (tm >= 10.0) {
        r.k_err_max_after_10s = std::max(r.k_err_max_after_10s, err);
        k_err_after_10.push_back(err);
        if (err < lim) ++k_below_after_10;
      }
      if (start_recorded && k_std < std_at_start / 10.0 && std_candidate < 0) std_candidate = tm;
      if (tm <= opt.early_window) r.scale.push_back({t, st.scale_error, k_est, k_std});
    }
    const double ec_ = std::hypot(fc.x[0] - st.truth.x, fc.x[1] - st.truth.y);
    const double eu = std::hypot(fu.x[0] - st.truth.x, fu.x[1] - st.truth.y);
    r.max_err_cal = std::max(r.max_err_cal, ec_);
    r.max_err_uncal = std::max(r.max_err_uncal, eu);
    if (t >= next_record) {
      next_record += opt.record_period;
      if (motion_start < 0 || t - motion_start > opt.early_window)
        r.scale.push_back({t, st.scale_error, k_est, k_std});
      r.position.push_back({t, st.truth.distance, ec_, eu, (dr_cal - core::Vec2(st.truth.x, st.truth.y)).norm(),
                            (dr_uncal - core::Vec2(st.truth.x, st.truth.y)).norm(),
                            core::wrapAngle(fc.x[2] - st.truth.heading)});
    }
    if (progress && t >= next_progress * cfg.duration) {
      progress(next_progress);
      next_progress += 0.1;
    }
  }
  engine.flush();
  const auto& fc = latest.at("odo_ins");
  const auto& fu = latest.at("odo_ins_uncal");
  r.duration_s = (st.truth.utime - start_utime) * 1e-6;
  r.distance_m = st.truth.distance;
  r.final_err_cal = std::hypot(fc.x[0] - st.truth.x, fc.x[1] - st.truth.y);
  r.final_err_uncal = std::hypot(fu.x[0] - st.truth.x, fu.x[1] - st.truth.y);
  r.final_err_dr_cal = (dr_cal - core::Vec2(st.truth.x, st.truth.y)).norm();
  r.final_err_dr_uncal = (dr_uncal - core::Vec2(st.truth.x, st.truth.y)).norm();
  r.final_heading_err_cal = core::wrapAngle(fc.x[2] - st.truth.heading);
  r.k_err_final = last_err;
  r.k_std_final = last_std;
  r.t_one_order_s = one_order_candidate;
  const auto k_n_after_10 = static_cast<int64_t>(k_err_after_10.size());
  r.k_err_rms_after_10s = core::rms(k_err_after_10);
  r.k_fraction_one_order_after_10s = k_n_after_10 ? double(k_below_after_10) / k_n_after_10 : 0.0;
  r.t_std_one_order_s = std_candidate;
  return r;
}

bool writeReport(const std::vector<RunResult>& runs, const sim::InsSimConfig& cfg, const Options& opt,
                 const std::string& dir) {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  nlohmann::json j;
  j["paper"] = {{"scale_drop", "about one order of magnitude within about 10 s"},
                {"trajectory", "3600 s, about 65 km, starting, speeding, turning"}};
  j["sensor_grade"] = {{"gyro_markov_deg_h", cfg.gyro_markov}, {"gyro_tau_s", cfg.gyro_tau},
                       {"gyro_white_deg_h", cfg.gyro_white}, {"accel_markov_g", cfg.accel_markov},
                       {"accel_tau_s", cfg.accel_tau}, {"accel_white_g", cfg.accel_white},
                       {"scale_error", cfg.scale_error}, {"scale_markov", cfg.scale_markov},
                       {"scale_tau_s", cfg.scale_tau}, {"scale_white", cfg.scale_white}};
  j["seed"] = cfg.seed;
  j["rate_hz"] = cfg.rate_hz;
  j["calibration_stage_s"] = opt.calibration_stage;
  for (const auto& r : runs) {
    j["runs"][r.name] = {
        {"start", r.start},
        {"duration_s", r.duration_s},
        {"distance_m", r.distance_m},
        {"motion_start_s", r.motion_start_s},
        {"scale",
         {{"k_true_at_start", r.k_true0},
          {"abs_error_first_update", r.k_err_at_start},
          {"sigma_first_update", r.k_std_at_start},
          {"abs_error_10s", r.k_err_10s},
          {"sigma_10s", r.k_std_10s},
          {"drop_factor_10s", r.k_err_10s > 0 ? r.k_err_at_start / r.k_err_10s : 0.0},
          {"sigma_drop_factor_10s", r.k_std_10s > 0 ? r.k_std_at_start / r.k_std_10s : 0.0},
          {"abs_error_60s", r.k_err_60s},
          {"abs_error_final", r.k_err_final},
          {"sigma_final", r.k_std_final},
          {"time_to_one_order_s", r.t_one_order_s},
          {"abs_error_rms_after_10s", r.k_err_rms_after_10s},
          {"abs_error_max_after_10s", r.k_err_max_after_10s},
          {"fraction_within_one_order_after_10s", r.k_fraction_one_order_after_10s},
          {"time_sigma_one_order_s", r.t_std_one_order_s}}},
        {"position",
         {{"odo_ins_final_m", r.final_err_cal},
          {"odo_ins_max_m", r.max_err_cal},
          {"odo_ins_uncal_final_m", r.final_err_uncal},
          {"odo_ins_uncal_max_m", r.max_err_uncal},
          {"dr_calibrated_final_m", r.final_err_dr_cal},
          {"dr_traditional_final_m", r.final_err_dr_uncal},
          {"dr_frozen_scale", r.k_frozen},
          {"odo_ins_final_heading_error_rad", r.final_heading_err_cal},
          {"odo_ins_final_error_per_distance", r.distance_m > 0 ? r.final_err_cal / r.distance_m : 0.0},
          {"odo_ins_uncal_final_error_per_distance", r.distance_m > 0 ? r.final_err_uncal / r.distance_m : 0.0}}},
        {"imu_gaps", r.imu_gaps}};
    if (opt.fixes) {
      auto& f = j["runs"][r.name]["fixes"];
      f["count"] = r.fixes.size();
      f["refused"] = r.fix_refused;
      f["list"] = nlohmann::json::array();
      for (const auto& p : r.fixes)
        f["list"].push_back({{"t_s", p.t}, {"distance_m", p.distance}, {"odo_ins_before_m", p.before_cal},
                             {"odo_ins_after_m", p.after_cal}, {"odo_ins_uncal_before_m", p.before_uncal},
                             {"odo_ins_uncal_after_m", p.after_uncal}});
    }
    std::ofstream s(dir + "/scale_" + r.name + ".dat");
    s << "# t[s] t_from_motion_start[s] k_true k_est abs_err sigma\n" << std::setprecision(9);
    for (const auto& p : r.scale)
      s << p.t << ' ' << p.t - r.motion_start_s << ' ' << p.k_true << ' ' << p.k_est << ' '
        << std::abs(p.k_est - p.k_true) << ' ' << p.k_std << '\n';
    std::ofstream q(dir + "/position_" + r.name + ".dat");
    q << "# t[s] distance[m] err_odo_ins err_odo_ins_uncal err_dr_cal err_dr_trad heading_err_odo_ins[rad]\n";
    for (const auto& p : r.position)
      q << p.t << ' ' << p.distance << ' ' << p.err_cal << ' ' << p.err_uncal << ' ' << p.err_dr_cal << ' '
        << p.err_dr_uncal << ' ' << p.heading_err_cal << '\n';
  }
  eval::writeJson(j, dir + "/report.json");
  std::ofstream gp(dir + "/plot.gp");
  gp << "set terminal pngcairo size 900,600 noenhanced\nset grid\n"
     << "set output 'fig1_scale.png'\nset title 'Fig. 1: odometer scale-error estimate, first 60 s of motion'\n"
     << "set xlabel 'time since the vehicle started [s]'\nset ylabel '|K_est - K_true|, filter 1 sigma'\n"
     << "set logscale y\nset format y '%g'\nset xrange [0:60]\nset key top right\nplot ";
  const char* colors[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e"};
  for (std::size_t i = 0; i < runs.size(); ++i)
    gp << (i ? ", " : "") << "'scale_" << runs[i].name << ".dat' using 2:5 with lines lw 2 lc rgb '"
       << colors[i % 5] << "' title '" << runs[i].name << ": |error|', 'scale_" << runs[i].name
       << ".dat' using 2:6 with lines dt 2 lc rgb '" << colors[i % 5] << "' title '" << runs[i].name
       << ": sigma'";
  gp << "\nset output 'fig1b_scale_run.png'\nset title 'Fig. 1b: scale-error estimate over the run'\n"
     << "set xlabel 't [s]'\nset autoscale x\nplot ";
  for (std::size_t i = 0; i < runs.size(); ++i)
    gp << (i ? ", " : "") << "'scale_" << runs[i].name << ".dat' using 1:5 with lines lc rgb '" << colors[i % 5]
       << "' title '" << runs[i].name << ": |error|'";
  gp << "\nset output 'fig2_position.png'\nset title 'Fig. 2: position error, calibrated vs traditional'\n"
     << "set xlabel 't [s]'\nset ylabel 'horizontal error [m]'\nset autoscale\nset yrange [0.01:*]\nset format y '%g'\nset logscale y\nset key top left\nplot ";
  if (!runs.empty()) {
    const std::string f = "'position_" + runs[0].name + ".dat'";
    gp << f << " using 1:3 with lines lw 2 lc rgb '#1f77b4' title 'odo_ins (calibrated, closed loop)', " << f
       << " using 1:4 with lines lw 2 lc rgb '#d62728' title 'odo_ins_uncal (traditional)', " << f
       << " using 1:5 with lines dt 2 lc rgb '#1f77b4' title 'dead reckoning, calibrated scale', " << f
       << " using 1:6 with lines dt 2 lc rgb '#d62728' title 'dead reckoning, no scale'";
  }
  gp << "\n";
  gp.close();
  return eval::runGnuplot(dir, "plot.gp") == 0;
}

}  // namespace lcmloc::ins_experiment
