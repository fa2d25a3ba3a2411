#pragma once
// Measurement noise learned from a recording without ground truth, and the consistency of a
// config on any recording: the filter is run over the recording by the fusion engine, as the
// replay runs it, and each sensor's normalized innovations (NIS, v' S^-1 v) are compared with
// the chi-square distribution they follow when the noise is right.
//
// The fit is covariance matching of the innovations: each sensor's default sigma is scaled until
// the median of its NIS equals the chi-square median of its degrees of freedom. The median, not
// the mean: the gate cuts the tail of the NIS and outliers inflate it, while half the decisions
// stay on either side of the median as long as fewer than half are outliers. S = H P H' + R, so
// scaling R does not scale S alike; the scaling is repeated until it settles. When H P H' alone
// already gives NIS above the median the noise cannot be fitted this way: the process noise is
// too small, and the fit says so rather than shrinking R to nothing.
#include <string>
#include <utility>
#include <vector>

#include "lcmloc/core/engine_config.hpp"
#include "lcmloc/fit/noise_fit.hpp"

namespace lcmloc::fit {

/// One sensor's NIS over a run: every decision with a candidate (accepted or refused).
struct SensorNis {
  std::string sensor;           ///< channel
  int dof = 0;                  ///< the innovation's dimension (the largest seen)
  int64_t decided = 0, accepted = 0;
  double mean = 0, median = 0;  ///< of the NIS
  double band_lo = 0, band_hi = 0;  ///< 95 % band of the mean NIS of `decided` samples
  double expected_median = 0;   ///< the chi-square median for dof
  double mean_innovation = 0;   ///< mean norm of the innovations (the prediction error)
  bool consistent() const { return decided > 0 && mean >= band_lo && mean <= band_hi; }
};

/// The names the recording's inputs get on the engine (the log's channels).
struct RecordingChannels {
  std::string odometry = "ODOMETRY", landmarks = "LANDMARKS", beacons = "BEACONS", gps = "GPS";
};

/// The filter of cfg run over the recording (engine with cfg's reorder window, map from r.map);
/// NIS per sensor of the active filter, in the order the sensors first decided.
std::vector<SensorNis> nisPerSensor(const Recording& r, const core::EngineConfig& cfg,
                                     const RecordingChannels& ch = {});


struct InnovationFitOptions {
  int max_iterations = 12;
  double tolerance = 0.05;      ///< stop when every scale is within 1 +- this
  int min_decisions = 20;       ///< fewer decisions of a sensor: its noise is not fitted
  /// The GNSS filters (tvekf, ukf_gps): gnss.position_rw by the prediction error of the fixes
  /// first (the configured value x 2^(k/2), k = -4 .. 12, that gives the smallest mean innovation
  /// norm over every GPS decision), then the sigmas.
  bool position_rw = true;
  RecordingChannels channels;
};

struct InnovationFit {
  core::FilterConfig filter;        ///< cfg's filter with the fitted sigmas
  std::vector<SensorNis> before, after;
  int iterations = 0;
  int runs = 0;                     ///< runs of the filter over the recording, all told
  std::pair<double, double> rw_error{0.0, 0.0};  ///< mean GPS prediction error before and after position_rw [m]
  std::vector<std::string> fitted;  ///< keys changed, e.g. "landmarks.beacon_std"
  std::vector<std::string> notes;   ///< what could not be fitted and why
};

/// Fits landmarks.range_std and bearing_std (one scale), landmarks.beacon_std and gnss.gps_std
/// to the recording's innovations; for the GNSS filters gnss.position_rw first, to the fixes'
/// prediction error (the process noise with which the filter best predicts each next fix: a GPS
/// whose error wanders with time needs more than the vehicle's own motion noise). Recordings
/// whose rows carry their own sigma keep them: the config's default is then not what the filter
/// used, and the fit says so.
InnovationFit fitByInnovations(const Recording& r, core::EngineConfig cfg, const InnovationFitOptions& opt = {});

/// The fit as a YAML fragment of `fusion.filter` keys (only the fitted ones).
std::string configFragment(const InnovationFit& f);

/// cfg with the values fitted against the truth (those the fit has) put in.
core::FilterConfig withFit(core::FilterConfig cfg, const NoiseFit& f, double pw_distance);

/// A table of NIS per sensor against its band, one line per sensor.
std::string nisTable(const std::vector<SensorNis>& nis);

}  // namespace lcmloc::fit
