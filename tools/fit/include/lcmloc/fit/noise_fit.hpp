#pragma once
// Noise learned from a recording with ground truth (lcmloc-fit-noise, and lcmloc-import when
// its data has a truth): each sensor's residuals against what the truth says it should have
// measured, and the odometry's error growth against the truth's motion, give the filter's
// measurement and process noise. No middleware: the log is read in fit_log.cpp.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "lcmloc/core/types.hpp"
#include "lcmloc/eval/trajectory.hpp"

namespace lcmloc::fit {

/// One truth sample: the evaluation's (has_heading false: position only).
using TruthSample = eval::TruthPose;

/// What the fit reads: the truth, the odometry and the measurements, in time order.
struct Recording {
  std::vector<TruthSample> truth;
  std::vector<core::OdometryInput> odometry;
  std::vector<core::LandmarkObservation> landmarks;
  std::vector<core::BeaconRange> beacons;
  std::vector<core::GpsInput> gps;
  core::MarkerMap map;
  double wheelbase = 2.5;      ///< for odometry with a steering angle
  double pw_distance = 2.0;    ///< the filter's Pw accumulates over this travel [m]
};

struct FitOptions {
  double max_truth_gap_s = 0.5;   ///< a residual between truth samples further apart is not used
  double max_window_s = 5.0;      ///< an odometry window ends after this long or pw_distance of travel
  double max_odometry_gap_s = 0.5;  ///< a window with odometry further apart is dropped
  double max_pair_gap_s = 2.0;     ///< successive observations of one landmark further apart are not a pair
};

/// Residuals of one quantity: robust spread (1.4826 MAD about the median), mean and RMS.
struct Residuals {
  int64_t n = 0;
  double median = 0, mean = 0, sigma = 0, rms = 0;
};
Residuals residualStats(std::vector<double> v);

struct NoiseFit {
  std::optional<Residuals> landmark_range, landmark_bearing, beacon_range, gps;  ///< gps: per axis
  std::map<int, Residuals> beacon_range_by_id;  ///< a beacon's median residual is its range bias
  /// Odometry process noise: pw_diag (x, y, theta) per pw_distance of travel and pw_turn (heading
  /// variance per radian turned), from the windows' errors.
  std::optional<core::Vec3> pw_diag;
  std::optional<double> pw_turn;
  int64_t odometry_windows = 0;
  /// Scales of the odometry against the truth, by least squares over windows of about 1 s:
  /// truth distance = (1 + k) odometry distance, truth turn = (1 + g) odometry turn (the turn from
  /// the truth heading, or from its direction of travel when it has none). `ratio` = 1 + k or
  /// 1 + g, `se` its standard error, `n` the windows.
  struct Scale {
    double ratio = 1.0, se = 0.0;
    int64_t n = 0;
    /// The ratio differs from 1 by more than 3 standard errors and by more than `min` (a scale
    /// the filter should start from, rather than from 1).
    bool significant(double min = 0.02) const { return n >= 5 && std::abs(ratio - 1.0) > std::max(3.0 * se, min); }
  };
  std::optional<Scale> odometry_scale, yaw_rate_scale;
  /// How much later than its time the odometry's motion shows in the truth (a vehicle that reports
  /// its commanded speed and turn rate, or a clock offset): the lag, on a 10 ms grid within +-1 s,
  /// that minimizes the RMS of the heading change over windows of about 1 s against the truth's
  /// (the odometry's turn scaled by least squares at each lag). `rms_at_zero`, `rms`: that RMS
  /// without a lag and at it [rad]; `n`: the windows. When significant the scales and the process
  /// noise are fitted to the odometry moved by the lag (the importer moves it so in the log).
  struct Lag {
    double seconds = 0.0, rms_at_zero = 0.0, rms = 0.0;
    double truth_rms = 0.0;  ///< RMS of the truth's heading change over the windows [rad]
    int64_t n = 0;
    /// At least 20 ms, the RMS at least 10 % below that without it, over 50 windows or more, and
    /// the odometry's turn a good model of the truth's at the lag (RMS at most half the truth's
    /// own: a truth whose heading is noise, e.g. a position-only truth's direction of travel at
    /// walking pace, cannot tell a lag).
    bool significant() const {
      return n >= 50 && std::abs(seconds) >= 0.02 && rms < 0.9 * rms_at_zero && rms <= 0.5 * truth_rms;
    }
  };
  std::optional<Lag> odometry_lag;
  /// The beacons' range bias, when at least one beacon's median residual differs from 0 by more
  /// than 3 standard errors of that median (1.2533 sigma / sqrt(n), at least 5 residuals) and
  /// by more than 0.02 m: a prior for the filter's range-bias states. `mean`: the median of every
  /// beacon's residuals together; `std`: the farthest beacon's median from it, or 3 standard
  /// errors of the mean, at least 0.05 m. `beacons`: how many were significant, of `of`.
  struct RangeBias {
    double mean = 0.0, std = 0.05;
    int beacons = 0, of = 0;
  };
  std::optional<RangeBias> beacon_bias;
  /// How alike successive landmark observations' errors are: the correlation of the residuals of
  /// two successive observations of one landmark (at most `max_pair_gap_s` apart), range and
  /// bearing. An error that persists from one observation to the next (the landmark's place in
  /// the map, a range error that depends on the distance) tells the filter no more the second
  /// time: `factor` = (1 + rho) / (1 - rho) of the larger rho (an AR(1) sequence's observations
  /// per independent one; rho <= 0 gives 1, rho is taken at most 0.98), the filter's
  /// landmarks.correlation_factor. At least 30 pairs.
  struct Correlation {
    double range_rho = 0.0, bearing_rho = 0.0, factor = 1.0;
    int64_t pairs = 0;
  };
  std::optional<Correlation> landmark_correlation;
  std::vector<std::string> notes;  ///< what could not be fitted and why
};

/// Fits what the recording allows (a measurement kind needs rows of known identity inside the
/// truth's span; the bearing and the odometry's heading need a truth heading).
NoiseFit fitAgainstTruth(const Recording& r, const FitOptions& opt = {});

/// Pearson's correlation of the pairs (a_i, b_i); 0 when either has no spread.
double correlation(const std::vector<double>& a, const std::vector<double>& b);

/// The growth of a variance over windows of travel: a per unit of s and b per unit of r (a, b >= 0)
/// such that the errors e_i (e2_i = e_i^2) are most likely as zero-mean Gaussian with variance
/// a s_i + b r_i (the heading's error per distance and per radian turned).
std::pair<double, double> fitVarianceGrowth(const std::vector<double>& e2, const std::vector<double>& s,
                                            const std::vector<double>& r);

/// The fit as a YAML fragment of `fusion.filter` keys (only the fitted ones), with comments
/// saying where each value comes from; merge it into a config or read it with --config.
std::string configFragment(const NoiseFit& f, double pw_distance);

}  // namespace lcmloc::fit
