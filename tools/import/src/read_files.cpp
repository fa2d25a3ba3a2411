// Pass 1 of lcmloc-import (import_files.hpp): which format each CSV file is, the map, the rows
// and their time column (unit, base, time-order rule), and one clock for all files.
#include <algorithm>
#include <fstream>
#include <limits>
#include <map>
#include <stdexcept>

#include <fmt/format.h>

#include "import_files.hpp"
#include "lcmloc/app/csv.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/import/checks.hpp"

namespace lcmloc::import::detail {
namespace fs = std::filesystem;
namespace {

struct FormatInfo {
  Format format;
  const char* kind;
  std::vector<std::string> required;  ///< after the time column, in any order
  std::vector<std::string> optional;  ///< may be there too
};

const std::vector<FormatInfo>& formats() {
  static const std::vector<FormatInfo> f{
      {Format::OdoDelta, "odometry", {"delta_s", "delta_theta"}, {}},
      {Format::OdoYawRate, "odometry", {"speed", "yaw_rate"}, {}},
      {Format::OdoSteering, "odometry", {"speed", "steering"}, {}},
      {Format::Landmarks, "landmarks", {"landmark_id", "range", "bearing"}, {"range_std", "bearing_std"}},
      {Format::Beacons, "beacons", {"beacon_id", "range"}, {"range_std"}},
      {Format::GpsLocal, "gps", {"x", "y"}, {"position_std"}},
      {Format::GpsGeo, "gps", {"latitude", "longitude"}, {"position_std"}},
      {Format::Truth, "ground_truth", {"x", "y", "heading"}, {}},
      {Format::Truth, "ground_truth", {"truth_x", "truth_y"}, {"truth_heading"}},
      {Format::Imu, "imu", {"accel_x", "accel_y", "accel_z", "gyro_x", "gyro_y", "gyro_z"}, {"mag_x", "mag_y", "mag_z"}},
  };
  return f;
}

bool has(const std::vector<std::string>& v, const std::string& x) { return std::find(v.begin(), v.end(), x) != v.end(); }

/// "time,landmark_id,range,bearing[,range_std][,bearing_std]"
std::string signature(const FormatInfo& fi) {
  std::string s = "time";
  for (const auto& c : fi.required) s += "," + c;
  if (fi.format == Format::Imu) {  // the magnetometer: its three columns or none
    std::string mag;
    for (const auto& c : fi.optional) mag += "," + c;
    return s + "[" + mag + "]";
  }
  for (const auto& c : fi.optional) s += "[," + c + "]";
  return s;
}

std::string quoted(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "'" : ", '") + n + "'";
  return s;
}

/// What a header is: a format, or why it is none.
struct Classified {
  std::optional<Format> format;
  TimeUnit forced = TimeUnit::Auto;  ///< from time_s / time_us
  std::string problem;               ///< why it is none of the formats
};

Classified classify(const std::vector<std::string>& h) {
  Classified c;
  if (h.size() == 3 && h[0] == "id" && h[1] == "x" && h[2] == "y") {
    c.format = Format::Map;
    return c;
  }
  if (h.empty()) {
    c.problem = "no header row (an empty file)";
    return c;
  }
  if (h[0] == "time") c.forced = TimeUnit::Auto;
  else if (h[0] == "time_s") c.forced = TimeUnit::Seconds;
  else if (h[0] == "time_us") c.forced = TimeUnit::Microseconds;
  else {
    c.problem = "the first column is '" + h[0] + "', not time, time_s or time_us (nor a map: id,x,y)";
    return c;
  }
  const std::vector<std::string> cols(h.begin() + 1, h.end());
  for (std::size_t i = 0; i < cols.size(); ++i) {
    if (cols[i] == "time" || cols[i] == "time_s" || cols[i] == "time_us")
      c.problem = "a second time column '" + cols[i] + "'";
    else if (has(std::vector<std::string>(cols.begin(), cols.begin() + static_cast<std::ptrdiff_t>(i)), cols[i]))
      c.problem = "column '" + cols[i] + "' twice";
    if (!c.problem.empty()) return c;
  }
  // A format whose required columns are all there: the one with the fewest other columns.
  const FormatInfo* best = nullptr;
  std::vector<std::string> best_unknown;
  for (const auto& fi : formats()) {
    bool all = true;
    for (const auto& r : fi.required) all = all && has(cols, r);
    if (!all) continue;
    std::vector<std::string> unknown;
    for (const auto& col : cols)
      if (!has(fi.required, col) && !has(fi.optional, col)) unknown.push_back(col);
    if (!best || unknown.size() < best_unknown.size()) {
      best = &fi;
      best_unknown = unknown;
    }
  }
  if (best && best_unknown.empty()) {
    if (best->format == Format::Imu) {
      const int mags = has(cols, "mag_x") + has(cols, "mag_y") + has(cols, "mag_z");
      if (mags != 0 && mags != 3) {
        c.problem = "imu: mag_x, mag_y, mag_z are all three there or none";
        return c;
      }
    }
    c.format = best->format;
    return c;
  }
  if (best) {
    c.problem = fmt::format("unknown column{} {} for {} ({})", best_unknown.size() > 1 ? "s" : "", quoted(best_unknown),
                            best->kind, signature(*best));
  } else if (has(cols, "range") && !has(cols, "bearing") && !has(cols, "landmark_id")) {
    c.problem = "ranges without a beacon_id column: give the column (time,beacon_id,range[,range_std]), with each "
                "row's beacon map id, or `unknown` where the row does not say which beacon it is (the filter then "
                "associates the range with the map itself)";
  } else {
    // the format that has most of its required columns: what is missing from it
    std::size_t most = 0;
    for (const auto& fi : formats()) {
      std::size_t n = 0;
      for (const auto& r : fi.required) n += has(cols, r);
      if (n > most) {
        most = n;
        best = &fi;
      }
    }
    c.problem = "none of the formats";
    if (best) {
      std::vector<std::string> missing;
      for (const auto& r : best->required)
        if (!has(cols, r)) missing.push_back(r);
      c.problem += fmt::format(" (closest: {} {}, without {})", best->kind, signature(*best), quoted(missing));
    }
  }
  return c;
}

std::string formatList() {
  std::string s;
  for (const auto& fi : formats()) s += fmt::format("  {:<13} {}\n", fi.kind, signature(fi));
  s += fmt::format("  {:<13} {}\n", "map", "id,x,y");
  return s;
}

}  // namespace

std::vector<DataFile> readDataFiles(const std::vector<fs::path>& paths, const ImportOptions& opt, ImportResult& r,
                                    core::MarkerMap& map) {
  auto refuse = [&r](FileReport& f, int64_t line, const std::string& why) { detail::refuse(r, f, line, why); };
  std::string map_source;
  std::vector<DataFile> files;
  // Every file's header first: a file that is none of the formats is an error before any is read.
  struct Header {
    fs::path path;
    std::string text;
    std::vector<std::string> columns;
    Classified what;
  };
  std::vector<Header> headers;
  std::vector<std::string> unknown;  // "'path': header ...: why"
  for (const auto& p : paths) {
    std::error_code ec;
    if (fs::is_directory(p, ec)) {  // not a file: listed, not read
      r.skipped.push_back("'" + p.string() + "': is a directory");
      continue;
    }
    Header hd{p, {}, {}, {}};
    app::csv::openCsv(p.string(), hd.text);  // throws for a file that cannot be read
    hd.columns = app::csv::split(hd.text);
    hd.what = classify(hd.columns);
    if (!hd.what.format)
      unknown.push_back(fmt::format("'{}': {}: {}", p.string(),
                                    hd.columns.empty() ? std::string("no columns")
                                                       : fmt::format("header '{}' ({} column{}: {})", hd.text,
                                                                     hd.columns.size(), hd.columns.size() > 1 ? "s" : "",
                                                                     quoted(hd.columns)),
                                    hd.what.problem));
    headers.push_back(std::move(hd));
  }
  if (!unknown.empty()) {
    std::string what = fmt::format("{} of the *.csv files {} none of the import formats (docs/import_formats.md):\n",
                                   unknown.size(), unknown.size() > 1 ? "are" : "is");
    for (const auto& u : unknown) what += "  " + u + "\n";
    what += "The formats (the first column time, time_s or time_us; the others named, in any order; [optional]):\n" +
            formatList() +
            "Every *.csv file in the directory is read (no other file is): fix the header, or move the file out or "
            "rename it (e.g. to .txt).";
    throw app::UsageError(what);
  }
  for (const auto& hd : headers) {
    const fs::path& p = hd.path;
    const auto& h = hd.columns;
    const std::string& header = hd.text;
    std::string again;
    std::ifstream in = app::csv::openCsv(p.string(), again);
    const Format f = *hd.what.format;
    if (f == Format::Map) {
      if (!map_source.empty())
        throw std::runtime_error("two map files: '" + map_source + "' and '" + p.string() + "'");
      map = app::csv::loadMap(p.string());  // a map is configuration: any bad row is an error
      map_source = p.string();
      continue;
    }
    const std::size_t ncol = h.size();
    const TimeUnit forced = hd.what.forced;
    DataFile df;
    df.format = f;
    df.columns = ncol;
    df.names = h;
    df.report.path = p.string();
    df.report.header = header;
    for (const auto& fi : formats())
      if (fi.format == f) df.report.kind = fi.kind;
    df.report.unit = opt.unit != TimeUnit::Auto ? opt.unit : forced;
    std::string line, why;
    int64_t lineno = 1;
    std::vector<double> raw;
    while (std::getline(in, line)) {
      ++lineno;
      if (line.empty() || line == "\r") continue;
      ++df.report.rows;
      Row row;
      row.line = lineno;
      row.fields = app::csv::split(line);
      if (row.fields.size() != ncol) {
        refuse(df.report, lineno, fmt::format("expected {} columns, got {}", ncol, row.fields.size()));
        continue;
      }
      if (!app::csv::parseNumber(row.fields[0], 1, row.t_raw, why)) {
        refuse(df.report, lineno, why);
        continue;
      }
      if (row.t_raw < 0) {
        refuse(df.report, lineno, fmt::format("negative time {}", row.fields[0]));
        continue;
      }
      raw.push_back(row.t_raw);
      df.rows.push_back(std::move(row));
    }
    if (df.report.unit == TimeUnit::Auto) df.report.unit = detectTimeUnit(raw);
    // Times in microseconds (out of range: refused), then the time-order rule (an outlier is
    // refused alone); the base is the first kept row's.
    std::vector<std::optional<int64_t>> utimes;
    for (const auto& row : df.rows) {
      utimes.push_back(toMicros(row.t_raw, df.report.unit == TimeUnit::Seconds ? 1e6 : 1.0));
      if (!utimes.back())
        refuse(df.report, row.line, fmt::format("time {} {} out of range", row.fields[0], toString(df.report.unit)));
    }
    const bool strict = f != Format::Landmarks && f != Format::Beacons;
    const auto order = checkTimeOrder(utimes, strict);
    for (std::size_t i = 0; i < df.rows.size(); ++i) {
      if (!utimes[i]) continue;
      df.rows[i].utime = *utimes[i];
      if (order[i].kind != TimeVerdict::Kept) {
        df.rows[i].time_refusal =
            timeOrderReason(utimes, i, order[i], strict, [&](std::size_t k) { return df.rows[k].fields[0]; });
        continue;
      }
      if (!df.first_kept) df.first_kept = df.rows[i].utime;
      df.last_kept = df.rows[i].utime;  // the kept rows are in time order
    }
    std::vector<Row> timed;  // the rows with a time in range
    for (std::size_t i = 0; i < df.rows.size(); ++i)
      if (utimes[i]) timed.push_back(std::move(df.rows[i]));
    df.rows = std::move(timed);
    df.report.base = opt.base != TimeBase::Auto || !df.first_kept ? opt.base : detectTimeBase(*df.first_kept);
    files.push_back(std::move(df));
  }
  return files;
}

std::vector<const DataFile*> inTimeOrder(const std::vector<DataFile>& files) {
  // All files must share one clock.
  const DataFile* abs_file = nullptr;
  const DataFile* rel_file = nullptr;
  for (const auto& f : files) {
    if (f.rows.empty()) continue;
    if (f.report.base == TimeBase::Absolute && !abs_file) abs_file = &f;
    if (f.report.base == TimeBase::Relative && !rel_file) rel_file = &f;
  }
  if (abs_file && rel_file)
    throw std::runtime_error(fmt::format(
        "'{}' has absolute (epoch) times, '{}' relative ones: they do not share a clock (force one with "
        "--time-base, and check --time-unit)",
        abs_file->report.path, rel_file->report.path));
  // One motion source, one IMU, one truth: files of odometry, IMU or ground truth are pieces of
  // one stream, one after the other; two that overlap in time would be merged into one channel
  // (the motion counted twice, two truths interleaved). Measurements (landmarks, beacons, gps) may come
  // from several files at once (several sensors).
  std::vector<const DataFile*> in_time;  // files in the order of their first kept time
  for (const auto& f : files) in_time.push_back(&f);
  std::stable_sort(in_time.begin(), in_time.end(), [](const DataFile* a, const DataFile* b) {
    constexpr int64_t kNever = std::numeric_limits<int64_t>::max();  // no kept row: last
    return a->first_kept.value_or(kNever) < b->first_kept.value_or(kNever);
  });
  std::map<std::string, const DataFile*> last_of_kind;
  for (const DataFile* f : in_time) {
    const bool stream = f->report.kind == "odometry" || f->report.kind == "ground_truth" || f->report.kind == "imu";
    if (!f->first_kept || !stream) continue;
    const DataFile*& before = last_of_kind[f->report.kind];
    if (before && *f->first_kept <= *before->last_kept)
      throw std::runtime_error(fmt::format(
          "two {} files overlap in time: '{}' ({:.6f} .. {:.6f} s) and '{}' ({:.6f} .. {:.6f} s); one {} stream per "
          "directory (files of one kind are joined one after the other): remove or merge one",
          f->report.kind, before->report.path, *before->first_kept * 1e-6, *before->last_kept * 1e-6, f->report.path,
          *f->first_kept * 1e-6, *f->last_kept * 1e-6, f->report.kind));
    before = f;
  }
  return in_time;
}

}  // namespace lcmloc::import::detail
