#pragma once
// The magnet-grid runs of Ecole Centrale de Nantes (../shared/data/magnet_grid_ecn): a small
// differential-drive robot with a row of 8 reed switches over magnets on a 55 mm square grid.
// Import (encoder counts -> differential-drive odometry, reed byte -> magnetic-ruler detections
// with a lateral offset, the grid -> map.csv, a config for lcmloc-replay) and the experiment
// (replay with the gated ruler UKF, gate and innovation statistics, track over the grid).
// docs/magnet_grid.md.
#include <cstdint>
#include <string>
#include <vector>

#include "lcmloc/core/types.hpp"

namespace lcmloc::import {

struct MagnetGridOptions {
  std::string input;                 ///< a run file (whitespace separated: encL encR reedByte time_s ...)
  std::string out_dir;               ///< run.lcmlog, map.csv, config.yaml ("" = import and count only)
  std::string name = "run";          ///< scenario name in config.yaml
  // robot (README of the data set)
  double wheel_radius = 0.0215;      ///< [m]
  double track = 0.112;              ///< distance between the wheels [m]
  double dots_per_rev = 360.0;       ///< encoder counts per wheel revolution
  double reed_offset = 0.08;         ///< reed row ahead of the wheel axle [m]
  double reed_pitch = 0.010;         ///< switch spacing [m]
  /// Side of bit 0: "right" puts bit i at body y = (i - 3.5) pitch (bit 0 on the right, body y
  /// to the left), "left" at -(i - 3.5) pitch.
  std::string bit0 = "right";
  double max_step_dots = 200.0;      ///< an encoder jump above this in one sample is refused [dots]
  // map
  double grid = 0.055;               ///< magnet spacing [m]
  double grid_margin = 0.3;          ///< grid extends this far beyond the dead-reckoned track [m]
  double grid_angle = 0.0;           ///< grid axes vs the start heading [rad]
  // filter (written into config.yaml)
  std::string filter = "ukf_gated";
  core::Vec3 p0_diag{1e-4, 1e-4, 3e-3};   ///< initial variances: relative to the anchored grid
  core::Vec3 pw_diag{4e-5, 4e-5, 4e-3};   ///< process noise per pw_distance of travel
  double pw_distance = 1.0;               ///< [m]
  double pw_turn = 2e-3;                  ///< heading variance per radian turned [rad^2/rad]
  /// Detection noise: range [m^2] (along track), bearing [rad^2]: the 10 mm switch pitch as a
  /// uniform quantisation, 10 mm / sqrt(12) = 2.9 mm, in both directions (bearing: over 80 mm).
  core::Vec2 pv_diag{8.4e-6, 1.31e-3};
  double reach = 0.02;                    ///< reach_forward = reach_lateral [m]
};

struct MagnetDetection {
  int64_t utime = 0;
  double lateral = 0;                ///< body y of the magnet at the reed row [m]
  int samples = 0;                   ///< samples of the pass
};

struct MagnetGridImport {
  int64_t rows = 0, refused = 0;
  std::vector<std::pair<int64_t, std::string>> refusals;   ///< (line, reason)
  int64_t odometry = 0;
  std::vector<MagnetDetection> detections;                  ///< one per magnet pass
  int64_t detecting_samples = 0;     ///< samples with at least one switch closed
  int64_t first_utime = 0, last_utime = 0;
  double distance_m = 0, turned_rad = 0;                    ///< sum |delta_s|, sum |delta_theta|
  std::vector<core::Vec3> dead_reckoning;                   ///< pose after each row
  core::MarkerMap map;
  core::Vec2 anchor = core::Vec2::Zero();                   ///< grid node at the first detection
  std::string log_path, map_path, config_path;
};

/// Reads one run and (when out_dir is set) writes the log, the map and the config. Throws
/// std::runtime_error when the file cannot be read or nothing usable is in it.
MagnetGridImport importMagnetGrid(const MagnetGridOptions& opt);

/// Summary of a replay of an imported run.
struct MagnetGridReport {
  std::string run;
  int64_t detections = 0, accepted = 0, rejected_gate = 0, no_candidate = 0, lockouts = 0;
  int64_t with_candidate = 0;        ///< decisions with an associated magnet (accepted + gate)
  double nis_mean = 0;               ///< over decisions with a candidate (expected: 2 = dof)
  double nis_median = 0;             ///< expected 1.386
  double within_gate = 0;            ///< fraction of those with NIS <= gate (expected 0.99)
  double within_95 = 0;              ///< fraction with NIS <= 5.991 (expected 0.95)
  double nis_mean_accepted = 0;
  double gate = 0;
  int distinct_magnets = 0;          ///< magnets accepted at least once
  double final_sigma_xy = 0;         ///< sqrt(P_xx + P_yy) at the end [m]
  double final_sigma_theta = 0;      ///< [rad]
  /// Largest 1-sigma of the reed-row position (x, y and reed_offset x heading) just before a
  /// detection, the first (the grid's anchor) excluded [m]: far below half the magnet spacing
  /// (27.5 mm) the nearest magnet is unambiguous.
  double max_prior_sigma = 0;
  double dr_gap_m = 0;               ///< final distance between the gated and dead-reckoned tracks [m]
};

/// Imports opt.input into opt.out_dir, replays it with config.yaml (the gated filter plus a
/// dead_reckoning shadow), writes report.json, track.dat, magnets.dat, plot.gp and track.png
/// (gnuplot) into out_dir.
MagnetGridReport runMagnetGrid(const MagnetGridOptions& opt, MagnetGridImport* imported = nullptr);

}  // namespace lcmloc::import
