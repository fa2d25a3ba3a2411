#pragma once
// lcmloc-import: a directory of CSV files (docs/import_formats.md) -> an LCM log of our types,
// the map and a system config ready for lcmloc-replay.
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "lcmloc/app/config.hpp"
#include "lcmloc/core/types.hpp"

namespace lcmloc::import {

/// How the time column is read. Auto: see detectTimeUnit / detectTimeBase.
enum class TimeUnit { Auto, Seconds, Microseconds };
enum class TimeBase { Auto, Absolute, Relative };

struct ImportOptions {
  std::string dir;                       ///< directory of *.csv files
  std::string out_dir;                   ///< writes run.lcmlog, map.csv (if any), config.yaml; "" = check only
  /// With a ground truth, the measurement and process noise of config.yaml are fitted against
  /// it (fit::fitAgainstTruth on the log written); without one, or off, the filter's defaults.
  bool fit_noise = true;
  TimeUnit unit = TimeUnit::Auto;
  TimeBase base = TimeBase::Auto;
  bool start_at_zero = false;            ///< shift every time so that the earliest is 0
  double wheelbase = 0.0;                ///< L [m] for speed,steering odometry (required there)
  std::string filter;                    ///< filter type of config.yaml ("" = chosen from the data)
  std::optional<core::Vec3> initial_pose;  ///< x, y, theta; default: first ground-truth row, else 0
  bus::Datum datum;                   ///< lat/lon <-> local frame (GPS in x,y is converted with it)
  app::ChannelConfig channels;
};

struct Refusal {
  std::string file;
  int64_t line = 0;   ///< 1-based
  std::string reason;
};

/// One recognised file.
struct FileReport {
  std::string path;
  std::string kind;     ///< odometry, landmarks, beacons, gps, ground_truth, imu
  std::string header;   ///< as read
  TimeUnit unit = TimeUnit::Auto;     ///< as detected or forced (not for map)
  TimeBase base = TimeBase::Auto;
  int64_t rows = 0, refused = 0, written = 0;
  int64_t first_utime = 0, last_utime = 0;
};

struct ImportResult {
  std::vector<FileReport> files;
  std::vector<std::string> skipped;   ///< directories named *.csv (not read; "'path': is a directory")
  std::vector<Refusal> refusals;
  int64_t messages = 0;
  int64_t first_utime = 0, last_utime = 0;
  int64_t map_size = 0;
  std::string filter;                 ///< filter type written into config.yaml
  std::string log_path, map_path, config_path;
  /// With a ground truth: the noise fitted against it (lcmloc-fit-noise) that config.yaml got,
  /// one line per value, and what could not be fitted (ImportOptions::fit_noise).
  std::vector<std::string> noise_fit;
  /// What the recording cannot give the filter, said before it is replayed (e.g. no landmark
  /// observation of known identity).
  std::vector<std::string> warnings;
  bool usable() const { return messages > 0; }
};

/// Unit rule for a column of times as read (any order): microseconds when the median |t| is at
/// least 1e11 (epoch seconds are ~1.7e9, epoch microseconds ~1.7e15) or when the median step
/// between consecutive rows is at least 1000 (1000 s between samples is implausible, 1 ms is
/// not); seconds otherwise. Medians, so that a few wrong times do not decide the unit.
TimeUnit detectTimeUnit(const std::vector<double>& times);
/// Absolute (Unix epoch) when the first time is at least 1e9 s (2001-09-09), else relative.
TimeBase detectTimeBase(int64_t first_utime);

/// Imports opt.dir (every *.csv file in it). Throws app::UsageError, before anything is
/// written, naming every *.csv file that is none of the formats (an unknown column, beacons
/// without an id, no time column, ...) with its columns and the formats it could have been;
/// std::runtime_error for an unreadable directory or file, a bad map file, two map files, two
/// odometry, IMU or ground-truth files that overlap in time (files that do not are joined one
/// after the other; gps, landmarks and beacons may come from several), a missing --wheelbase
/// for speed,steering odometry, files whose clocks disagree (absolute and relative) or a
/// config.yaml that the replay's loader (app::parseSystemConfig) would refuse (checked before
/// anything is written); app::ConfigError (naming the flag) for an option config.yaml would
/// not accept or an output file that is one of the input files. Bad rows (a bad sigma among
/// them) are refused and listed, never fatal; the time column follows the time-order rule of
/// checkTimeOrder (import/checks.hpp).
ImportResult importDirectory(const ImportOptions& opt);

/// Human report: per file rows read / refused / written and time span, the first max_refusals
/// refused rows (none when max_refusals <= 0) and how many more there are.
std::string importSummary(const ImportResult& r, int max_refusals = 30);

std::string toString(TimeUnit u);
std::string toString(TimeBase b);

}  // namespace lcmloc::import
