#pragma once
// Fig. 5 of seeds/004 §III as a Monte Carlo experiment: three landmarks at the corners of an
// equilateral triangle, bearings from the vision model (sim::VisionSensor, the code of
// lcmloc-vision), position and heading solved by the error-triangle method and by damped least
// squares (lcmloc::core::landmark), errors against the Cramér-Rao bound. No LCM, no clock.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "lcmloc/sim/vision_sensor.hpp"

namespace lcmloc::landmark_experiment {

/// The two readings of "three artificial landmarks and 1000 m apart".
enum class Reading { kFromVehicle, kApart };
std::string readingName(Reading r);  ///< "from_vehicle", "apart"

struct Options {
  int runs = 100;
  uint64_t seed = 1;
  double distance = 1000.0;            ///< the paper's "1000 m" [m]
  Eigen::Vector2d ins_offset{500.0, -500.0};  ///< INS position error (east, north) [m]
  /// INS heading error [rad] in the paper's sense (heading clockwise from north, eq. 9):
  /// -30' puts the INS heading 30' counter-clockwise of the truth.
  double ins_heading_error = -30.0 * 60.0 * sim::kArcSec;
  double true_heading = 0.0;           ///< true heading, clockwise from north [rad] (§III: north)
  /// Off-centre case: vehicle at centre + fraction * circumradius (east, north).
  Eigen::Vector2d off_centre{0.3, -0.2};
  double paper_position = 0.1;         ///< §III: errors per axis "mostly less than 0.1 m" [m]
  double paper_heading_2sigma = 20.0 * sim::kArcSec;  ///< §III: 20" (2 sigma) [rad]
  int histogram_bins = 40;
  /// Called with (done, total) runs over all cases; may be empty.
  std::function<void(int64_t, int64_t)> progress;
};

/// Errors of one method over the runs of one case (the refused runs are counted, not averaged).
struct MethodStats {
  std::string method;                  ///< "triangle", "least_squares", "gauss_newton", "uncorrected"
  int ok = 0, refused = 0;
  std::string first_refusal;
  // Horizontal position error |p - p_true| [m].
  double pos_mean = 0, pos_rms = 0, pos_p95 = 0, pos_max = 0;
  Eigen::Vector2d axis_mean = Eigen::Vector2d::Zero();  ///< bias (east, north) [m]
  Eigen::Vector2d axis_rms = Eigen::Vector2d::Zero();   ///< (east, north) [m]
  double within_paper = 0;             ///< fraction of runs with both |e_east|, |e_north| < paper_position
  Eigen::Vector2d axis_within_paper = Eigen::Vector2d::Zero();  ///< same per axis (east, north)
  // Heading error (fix - truth) [rad]; not defined for "uncorrected" (it keeps the INS heading).
  double heading_mean = 0, heading_std = 0, heading_rms = 0, heading_p95 = 0;
  std::vector<Eigen::Vector2d> pos_errors;  ///< per accepted run (east, north) [m]
  std::vector<double> heading_errors;       ///< per accepted run [rad]
};

struct CaseResult {
  std::string name;                    ///< e.g. "apart_centre"
  Reading reading = Reading::kApart;
  bool centre = true;
  double circumradius = 0;             ///< [m]
  std::vector<Eigen::Vector2d> landmarks;
  Eigen::Vector2d vehicle = Eigen::Vector2d::Zero();
  double ranges[3] = {0, 0, 0};        ///< vehicle-landmark distances [m]
  double condition = 0;                ///< range-scaled condition number at the truth
  // Cramér-Rao bound at the truth for the effective bearing sigma (noise and quantization).
  Eigen::Matrix3d crb = Eigen::Matrix3d::Zero();  ///< (x, y, psi)
  double crb_pos_rms = 0;              ///< sqrt(Cxx + Cyy) [m]
  double crb_heading_std = 0;          ///< sqrt(Cpsipsi) [rad]
  double crb_within_paper = 0;         ///< P(|e_east|, |e_north| < paper_position) for N(0, CRB position block)
  std::vector<MethodStats> methods;
};

struct Result {
  Options options;
  sim::VisionSensorConfig vision;
  double sigma_effective = 0;          ///< sqrt(std^2 + resolution^2 / 12) [rad]
  std::vector<CaseResult> cases;       ///< from_vehicle/apart x centre/off_centre
  /// Which reading the paper's position figure fits: the centre case whose fraction of runs
  /// with both axis errors below 0.1 m (least squares) is at least one half; "both" / "neither".
  std::string position_fit;
  std::string conclusion;              ///< one paragraph in words
  /// Bearing noise (1 sigma) that would make the least-squares 2-sigma heading equal to the
  /// paper's 20" at the centre (heading error scales with the noise) [rad].
  double implied_bearing_std = 0;
};

/// Landmarks (ids 1, 2, 3) of a reading: equilateral triangle centred on the origin, first
/// corner due north; circumradius distance (from vehicle) or distance / sqrt(3) (apart).
std::vector<sim::Landmark> triangleLandmarks(Reading r, double distance);

/// Runs the experiment. Throws std::invalid_argument for bad options or vision config.
Result run(const sim::VisionSensorConfig& vision, const Options& opt);

/// One recorded observation (e.g. VISION of a multi-process run) with the true pose at its time.
struct Observation {
  int64_t utime = 0;
  double x = 0, y = 0, heading = 0;  ///< true pose, heading CCW from east [rad]
  sim::VisionSample sample;
};

/// The fix on recorded observations: the INS pose of each is the truth plus opt.ins_offset and
/// opt.ins_heading_error. One case named "log"; its CRB fields are the root mean of the bounds at
/// the observed poses (sigma: the observations' bearing_std). Observations without exactly three
/// bearings are refused by the fix and counted. Throws std::invalid_argument for a bad map or
/// an empty list.
Result runObservations(const std::vector<sim::Landmark>& map, const std::vector<Observation>& obs,
                       const Options& opt);

/// report.json, per-case data files and figures (gnuplot) into dir. Returns false when gnuplot
/// failed (report.json is written anyway).
bool writeReport(const Result& r, const std::string& dir);

/// Fixed-width table of the results (what the command prints).
std::string summaryTable(const Result& r);

}  // namespace lcmloc::landmark_experiment
