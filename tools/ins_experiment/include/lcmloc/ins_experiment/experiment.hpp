#pragma once
// §II of Wang & Wang (seeds/004) as a scenario: the odometry/INS filter with online odometer
// scale calibration ("odo_ins") against the traditional integration that ignores the scale
// error ("odo_ins_uncal"), on the paper's 3600 s / ~65 km trajectory with the paper's sensor
// grade. Runs the same models as lcmloc-ins-sim (lib/sim InsSim) through the same fusion
// engine as lcmloc-fusion, in process. Reproduces Fig. 1 (scale-error estimate over time) and
// Fig. 2 (position error, calibrated vs traditional).
#include <functional>
#include <string>
#include <vector>

#include "lcmloc/core/engine.hpp"
#include "lcmloc/core/filter.hpp"
#include "lcmloc/sim/ins_sim.hpp"
#include "lcmloc/sim/vision_sensor.hpp"

namespace lcmloc::ins_experiment {

struct Options {
  double record_period = 1.0;    ///< position samples kept for the figures [s]
  double early_window = 60.0;    ///< scale samples kept at full rate after the motion starts [s]
  double calibration_stage = 60.0;  ///< dead reckoning freezes the scale estimate this long after the start [s]
  /// Three-landmark fixes (seeds/004 §III): when set, a VisionSensor (lcmloc-vision's model) sees
  /// `landmarks` from the truth and every observation with three bearings goes to the engine as
  /// VISION, re-initializing odo_ins and odo_ins_uncal; the run reports the error before/after.
  bool fixes = false;
  sim::VisionSensorConfig vision;
  std::vector<sim::Landmark> landmarks;
  uint64_t vision_seed = 5;
  core::landmark::FixOptions fix;  ///< the engine's fix options and gate (`fusion.landmark_fix`)
  core::LandmarkFixGate fix_gate;
};

/// One three-landmark fix: position errors just before and just after it.
struct FixPoint {
  double t, distance;
  double before_cal, after_cal;      ///< odo_ins [m]
  double before_uncal, after_uncal;  ///< odo_ins_uncal [m]
};

struct ScalePoint { double t, k_true, k_est, k_std; };
struct PositionPoint {
  double t, distance;
  double err_cal, err_uncal;        ///< closed-loop filters odo_ins, odo_ins_uncal [m]
  double err_dr_cal, err_dr_uncal;  ///< dead reckoning with the frozen / no scale estimate [m]
  double heading_err_cal;           ///< odo_ins theta error [rad]
};

struct RunResult {
  std::string name;                 ///< e.g. "hard_start"
  std::string start;                ///< InsSimConfig::start
  double duration_s = 0, distance_m = 0, motion_start_s = 0;
  // Scale calibration (|K_est - K_true|, and the filter's own 1 sigma).
  double k_true0 = 0;
  double k_err_at_start = 0, k_std_at_start = 0;  ///< first odometer update after the motion starts
  double k_err_10s = 0, k_std_10s = 0;            ///< 10 s after the motion starts
  double k_err_60s = 0, k_err_final = 0, k_std_final = 0;
  double t_one_order_s = -1;        ///< after the start until |err| first < |K0| / 10 (-1: never)
  double t_std_one_order_s = -1;    ///< until the filter's sigma first < its start / 10
  double k_err_rms_after_10s = 0, k_err_max_after_10s = 0;  ///< from 10 s after the start to the end
  double k_fraction_one_order_after_10s = 0;  ///< share of that time with |err| < |K0| / 10
  // Position errors.
  double final_err_cal = 0, final_err_uncal = 0, max_err_cal = 0, max_err_uncal = 0;
  double final_err_dr_cal = 0, final_err_dr_uncal = 0, final_heading_err_cal = 0;
  double k_frozen = 0;              ///< scale estimate used by the calibrated dead reckoning
  int imu_gaps = 0;                 ///< "imu_gap" decisions of odo_ins
  int fix_refused = 0;              ///< observations with three bearings the engine did not apply
  std::vector<FixPoint> fixes;      ///< Options::fixes
  std::vector<ScalePoint> scale;
  std::vector<PositionPoint> position;
};

/// Called with every simulation step (e.g. to write the sensor log).
using StepSink = std::function<void(const sim::InsSimStep&)>;

/// One run of the scenario (cfg.start decides hard or gentle start). base: fusion.filter (its
/// type is replaced by odo_ins / odo_ins_uncal; ins.latitude/longitude/height and the initial
/// heading follow the simulation). Progress: called every 10 % of the run.
RunResult run(const std::string& name, const sim::InsSimConfig& cfg, const core::FilterConfig& base,
              int64_t start_utime, const Options& opt, const StepSink& sink = {},
              const std::function<void(double)>& progress = {});

/// report.json, data files, plot.gp, fig1_scale.png, fig1b_scale_run.png, fig2_position.png.
/// Returns false when gnuplot failed (the report is written anyway).
bool writeReport(const std::vector<RunResult>& runs, const sim::InsSimConfig& cfg, const Options& opt,
                 const std::string& dir);

}  // namespace lcmloc::ins_experiment
