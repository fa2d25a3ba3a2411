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
#include "lcmloc/import/checks.hpp"

namespace lcmloc::import::detail {
namespace fs = std::filesystem;
namespace {

struct FormatInfo {
  Format format;
  const char* kind;
  std::vector<std::string> columns;  ///< after the time column
  bool optional_last = false;        ///< the last column may be left out
};

const std::vector<FormatInfo>& formats() {
  static const std::vector<FormatInfo> f{
      {Format::OdoDelta, "odometry", {"delta_s", "delta_theta"}},
      {Format::OdoYawRate, "odometry", {"speed", "yaw_rate"}},
      {Format::OdoSteering, "odometry", {"speed", "steering"}},
      {Format::Landmarks, "landmarks", {"landmark_id", "range", "bearing"}},
      {Format::Beacons, "beacons", {"beacon_id", "range"}},
      {Format::Truth, "ground_truth", {"x", "y", "heading"}},
      {Format::GpsLocal, "gps", {"x", "y", "position_std"}, true},
      {Format::GpsGeo, "gps", {"latitude", "longitude", "position_std"}, true},
  };
  return f;
}

/// Header -> format; forced unit from time_s / time_us. False when not recognised.
bool classify(const std::vector<std::string>& h, Format& f, std::size_t& ncol, TimeUnit& forced) {
  if (h.size() == 3 && h[0] == "id" && h[1] == "x" && h[2] == "y") {
    f = Format::Map;
    ncol = 3;
    return true;
  }
  if (h.empty()) return false;
  if (h[0] == "time") forced = TimeUnit::Auto;
  else if (h[0] == "time_s") forced = TimeUnit::Seconds;
  else if (h[0] == "time_us") forced = TimeUnit::Microseconds;
  else return false;
  for (const auto& fi : formats()) {
    const std::size_t full = fi.columns.size() + 1;
    const bool sizes = h.size() == full || (fi.optional_last && h.size() == full - 1);
    if (!sizes) continue;
    bool same = true;
    for (std::size_t i = 1; i < h.size(); ++i) same = same && h[i] == fi.columns[i - 1];
    if (same) {
      f = fi.format;
      ncol = h.size();
      return true;
    }
  }
  return false;
}

}  // namespace

std::vector<DataFile> readDataFiles(const std::vector<fs::path>& paths, const ImportOptions& opt, ImportResult& r,
                                    core::MarkerMap& map) {
  auto refuse = [&r](FileReport& f, int64_t line, const std::string& why) { detail::refuse(r, f, line, why); };
  std::string map_source;
  std::vector<DataFile> files;
  for (const auto& p : paths) {
    std::string header;
    std::ifstream in;
    try {
      in = common::csv::openCsv(p.string(), header);
    } catch (const std::runtime_error& e) {
      r.skipped.push_back(e.what());
      continue;
    }
    if (!in) {
      r.skipped.push_back(p.string() + ": empty");
      continue;
    }
    const auto h = common::csv::split(header);
    Format f{};
    std::size_t ncol = 0;
    TimeUnit forced = TimeUnit::Auto;
    if (!classify(h, f, ncol, forced)) {
      r.skipped.push_back(p.string() + ": header '" + header + "' is none of the formats (docs/import_formats.md)");
      continue;
    }
    if (f == Format::Map) {
      if (!map_source.empty())
        throw std::runtime_error("two map files: '" + map_source + "' and '" + p.string() + "'");
      map = common::csv::loadMap(p.string());  // a map is configuration: any bad row is an error
      map_source = p.string();
      continue;
    }
    DataFile df;
    df.format = f;
    df.columns = ncol;
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
      row.fields = common::csv::split(line);
      if (row.fields.size() != ncol) {
        refuse(df.report, lineno, fmt::format("expected {} columns, got {}", ncol, row.fields.size()));
        continue;
      }
      if (!common::csv::parseNumber(row.fields[0], 1, row.t_raw, why)) {
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
  // One motion source, one truth: files of odometry or ground truth are pieces of one stream,
  // one after the other; two that overlap in time would be merged into one channel (the motion
  // counted twice, two truths interleaved). Measurements (landmarks, beacons, gps) may come
  // from several files at once (several sensors).
  std::vector<const DataFile*> in_time;  // files in the order of their first kept time
  for (const auto& f : files) in_time.push_back(&f);
  std::stable_sort(in_time.begin(), in_time.end(), [](const DataFile* a, const DataFile* b) {
    constexpr int64_t kNever = std::numeric_limits<int64_t>::max();  // no kept row: last
    return a->first_kept.value_or(kNever) < b->first_kept.value_or(kNever);
  });
  std::map<std::string, const DataFile*> last_of_kind;
  for (const DataFile* f : in_time) {
    const bool stream = f->report.kind == "odometry" || f->report.kind == "ground_truth";
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
