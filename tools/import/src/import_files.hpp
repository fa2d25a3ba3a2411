#pragma once
// The two passes of importDirectory (import.cpp), internal to tools/import/src: reading the CSV
// files (read_files.cpp: formats told apart by their header, the map, the time column and its
// time-order rule, one clock for all files) and converting their rows into messages
// (convert_rows.cpp). Refused rows go into ImportResult::refusals in the order they are found.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "lcmloc/core/types.hpp"
#include "lcmloc/import/event_log.hpp"
#include "lcmloc/import/import.hpp"

namespace lcmloc::import::detail {

/// The data formats, told apart by their header (the time column may be time, time_s, time_us;
/// the other columns are named, in any order, docs/import_formats.md).
enum class Format { OdoDelta, OdoYawRate, OdoSteering, Landmarks, Beacons, GpsLocal, GpsGeo, Truth, Imu, Map };

struct Row {
  int64_t line = 0;
  int64_t utime = 0;
  double t_raw = 0;
  std::vector<std::string> fields;  ///< as read (time first)
  std::string time_refusal;         ///< why the time-order rule refuses the row ("" = kept)
};

struct DataFile {
  FileReport report;
  Format format = Format::Map;
  std::size_t columns = 0;          ///< columns in this file (with time)
  std::vector<std::string> names;   ///< the header's column names (time first)
  /// The index of column `name` in a row (time: 0), or npos when the file has no such column.
  std::size_t col(const std::string& name) const {
    for (std::size_t i = 0; i < names.size(); ++i)
      if (names[i] == name) return i;
    return std::string::npos;
  }
  std::vector<Row> rows;            ///< rows that split into the right number of columns with a numeric time
  std::optional<int64_t> first_kept, last_kept;  ///< time span of the rows the time-order rule keeps
};

/// Refuses line `line` of file f: listed in r.refusals, counted in f.refused.
inline void refuse(ImportResult& r, FileReport& f, int64_t line, const std::string& why) {
  r.refusals.push_back({f.path, line, why});
  ++f.refused;
}

/// Pass 1: recognises the files, reads the map into `map`, splits the rows and reads the time
/// column (unit, base, time-order rule). A directory named *.csv goes to r.skipped. Throws
/// app::UsageError naming every *.csv file that is none of the formats (with the formats it
/// could have been and the columns it had), std::runtime_error for an unreadable file, two map
/// files or a bad map.
std::vector<DataFile> readDataFiles(const std::vector<std::filesystem::path>& paths, const ImportOptions& opt,
                                    ImportResult& r, core::MarkerMap& map);

/// The files in the order of their first kept time (files without one last). Throws
/// std::runtime_error when the files do not share one clock (absolute and relative times) or
/// when two odometry, two IMU or two ground-truth files overlap in time.
std::vector<const DataFile*> inTimeOrder(const std::vector<DataFile>& files);

/// What pass 2 made of the rows.
struct Converted {
  EventLog log;
  bool have_landmarks = false, have_beacons = false, have_gps = false, have_imu = false;
  bool imu_without_mag = false;           ///< an IMU file without magnetometer columns (mag written as 0)
  int64_t landmarks_written = 0, landmarks_without_identity = 0;  ///< landmark messages, and those with id -1
  std::optional<core::Vec3> first_truth;  ///< the earliest ground-truth pose (heading: see truth_heading)
  /// How first_truth's heading was found: "row" (the truth has a heading), "travel" (position-only
  /// truth: the direction of travel), "none" (position-only truth that never moves: 0).
  std::string truth_heading;
};

/// Pass 2: converts the rows of `files`, file after file in `in_time` order (sequence numbers
/// in time order), each file's rows in line order; refuses the rows it cannot convert. Throws
/// std::runtime_error for speed,steering odometry without --wheelbase.
Converted convertRows(std::vector<DataFile>& files, const std::vector<const DataFile*>& in_time,
                      const core::MarkerMap& map, const ImportOptions& opt, ImportResult& r);

}  // namespace lcmloc::import::detail
