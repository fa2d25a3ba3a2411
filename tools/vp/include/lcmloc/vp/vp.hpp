#pragma once
// Victoria Park (ACFR, ../shared/data/victoria_park): import of the CSV files into an LCM log of
// our types (ODOMETRY, GPS, held-out fixes on GPS_HELDOUT) and the held-out-fix experiment
// (replay through the fusion daemon's code, score against the held-out fixes). docs/tvekf.md.
#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "lcmloc/app/config.hpp"

namespace lcmloc::vp {

/// --encoder-offset H [m]: the encoder wheel is half a vehicle's track from the axle centre, so
/// |H| is at most 1.5 m (within it the correction 1 / (1 - tan(psi) H / L) stays finite for the
/// default wheelbase and every accepted steering angle).
inline constexpr app::Bounds kEncoderOffset{-1.5, 1.5};

struct ImportOptions {
  std::string odometry_csv;           ///< vp_odometry.csv: time_ms, speed_mps, steering_rad
  std::string gps_csv;                ///< vp_gps.csv: time_ms, Lo_m (east), La_m (north)
  std::string output;                 ///< LCM log to write ("" = import and count only)
  double wheelbase = 2.83;            ///< L [m] (README / info_original.txt)
  double encoder_offset = 0.76;       ///< H: encoder to the left of the rear axle centre [m]
  int holdout_every = 5;              ///< every k-th fix goes to heldout_channel (0 = none)
  int holdout_phase = 0;              ///< fix index i is held out when i % k == phase
  double gps_std = 0.0;               ///< position_std written into the fixes [m] (0 = filter default)
  double max_speed = 30.0;            ///< |speed| above this: refused [m/s]
  double max_steering = 1.0;          ///< |steering| above this: refused [rad]
  /// A slice: the first N odometry rows and the GPS rows up to the last of them (0 = all).
  int64_t max_rows = 0;
  bus::Datum datum;                ///< local Lo/La metres -> lat/lon about this datum
  std::string odometry_channel = "ODOMETRY";
  std::string gps_channel = "GPS";
  std::string heldout_channel = "GPS_HELDOUT";
  std::function<bool()> stop;         ///< polled while reading: true ends the import early
};

struct Refusal {
  std::string file;
  int64_t line = 0;                   ///< 1-based line number in the file
  std::string reason;
};

/// One fix as imported, in the local frame (x east, y north).
struct Fix {
  int64_t utime = 0;
  double x = 0, y = 0;
  bool heldout = false;
};

struct ImportResult {
  int64_t odometry_rows = 0, odometry_refused = 0, odometry_written = 0;
  int64_t gps_rows = 0, gps_refused = 0, gps_written = 0, heldout_written = 0;
  int64_t first_utime = 0, last_utime = 0;  ///< time span of the messages [us]
  int64_t odometry_gaps = 0;          ///< odometry intervals longer than 0.5 s (speed held over them)
  double distance_m = 0;              ///< sum of |delta_s|
  std::vector<Refusal> refusals;      ///< every refused row, in file order
  std::vector<Fix> fixes;             ///< every accepted fix (heldout marked)
  bool interrupted = false;
};

/// Throws app::ConfigError naming the flag for an option that would make a wrong log:
/// --wheelbase not > 0, --encoder-offset outside kEncoderOffset, --holdout-every < 0,
/// --holdout-phase outside [0, every) (>= 0 when every is 0), and a --heldout-channel that is
/// empty, holds a blank or is a channel the import writes (odometry or GPS: the held-out fixes
/// would reach the filters or be read as odometry).
void checkImportOptions(const ImportOptions& opt);

/// Reads both files, converts and (when output is set) writes the log in time order. Refused
/// rows are listed with file, line and reason. Throws app::ConfigError for the options
/// (checkImportOptions) or an output that is an input file, std::runtime_error when a file is
/// missing, a directory or cannot be opened, its header is not the expected one (a leading UTF-8
/// byte-order mark is skipped), or the output cannot be written.
ImportResult importVictoriaPark(const ImportOptions& opt);

/// Human report of an import (counts, time span, the first refusals).
std::string importSummary(const ImportOptions& opt, const ImportResult& r, int max_refusals = 20);

/// lcmloc-import-vp's work after its command line: the CSV files from dir unless given, the
/// datum and channels from cfg, the import and its summary (importSummary) on stdout. Throws
/// app::UsageError (exit 2) without both inputs, for a missing input and for an existing
/// output without overwrite. Returns app::kExitOk.
int importCommand(const app::SystemConfig& cfg, ImportOptions io, const std::string& dir, int max_refusals,
                  bool overwrite);

// ---------------------------------------------------------------------------------------------
struct ExperimentOptions {
  std::vector<std::string> filters{"tvekf", "ukf_gps", "dead_reckoning"};
  std::string out_dir = "out/vp";
  /// Start each filter at the first fix (x, y) with the heading of the first fixes' course
  /// (chord from the first fix to the first fix at least init_course_m away); otherwise the
  /// configured fusion.filter.initial_pose.
  bool init_from_gps = true;
  double init_course_m = 10.0;
  /// Fit each filter's noise to the innovations of the fixes it is given (fit::fitByInnovations:
  /// gnss.position_rw to the fixes' prediction error, the sigmas to the NIS) before its replay;
  /// the held-out fixes are never seen by the fit.
  bool fit_noise = true;
};

struct Score {
  std::string filter;
  int64_t poses = 0;
  int64_t scored = 0;                 ///< held-out fixes inside the estimate's time span
  double rmse_m = 0, median_m = 0, p95_m = 0, max_m = 0;
  int64_t gps_accepted = 0, gps_rejected = 0, lockouts = 0, relocalized = 0;
  double longest_rejection_s = 0;     ///< longest run of refused fixes: first refused to the next accepted [s]
  double position_rw = 0, gps_std = 0;  ///< the filter's, as replayed (fitted or configured)
  std::vector<double> t, err;         ///< per scored held-out fix: time since start [s], error [m]
  std::vector<std::array<double, 3>> track;  ///< t [s], x, y (every pose)
};

struct ExperimentResult {
  ImportResult import;
  std::vector<Score> scores;
  std::string log_path;
  double seconds = 0;
};

/// Throws app::ConfigError naming the flag for options that make no experiment, before
/// anything is written: an empty --filters, a filter type cfg does not know or one listed
/// twice, --holdout-every below 2 (0 holds no fix out: nothing to score; 1 holds every fix out:
/// the filters get no GPS) and the import options (checkImportOptions, with cfg's channels).
void checkExperimentOptions(const app::SystemConfig& cfg, const ImportOptions& imp, const ExperimentOptions& opt);

/// Checks the options (checkExperimentOptions), imports (into out_dir/vp.lcmlog), replays the log
/// through the fusion daemon's code once per filter (lcmloc-replay's replayLog: the active filter
/// subscribes to ODOMETRY and GPS only, never to GPS_HELDOUT) and scores each estimate at the
/// held-out fixes (linear interpolation of the pose stream at the fix time). Writes report.json, data files, plot.gp, drive.png
/// and error.png into out_dir.
ExperimentResult runExperiment(const app::SystemConfig& cfg, ImportOptions imp, const ExperimentOptions& opt);

/// Interpolated position of a time-sorted track (t, x, y) at t; false outside its span.
bool interpolate(const std::vector<std::array<double, 3>>& track, double t, double& x, double& y);

}  // namespace lcmloc::vp
