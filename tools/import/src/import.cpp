#include "lcmloc/import/import.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>

#include <fmt/format.h>

#include "lcmloc/beacon_range_t.hpp"
#include "lcmloc/app/csv.hpp"
#include "lcmloc/bus/geodesy.hpp"
#include "lcmloc/core/angles.hpp"
#include "lcmloc/gps_fix_t.hpp"
#include "lcmloc/ground_truth_t.hpp"
#include "lcmloc/import/checks.hpp"
#include "lcmloc/import/event_log.hpp"
#include "lcmloc/landmark_obs_t.hpp"
#include "lcmloc/odometry_t.hpp"

namespace lcmloc::import {
namespace fs = std::filesystem;
namespace {

constexpr double kPi = 3.14159265358979323846;

/// The data formats, told apart by their header (the time column may be time, time_s, time_us).
enum class Format { OdoDelta, OdoYawRate, OdoSteering, Landmarks, Beacons, GpsLocal, GpsGeo, Truth, Map };

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
  std::vector<Row> rows;            ///< rows that split into the right number of columns with a numeric time
  std::optional<int64_t> first_kept, last_kept;  ///< time span of the rows the time-order rule keeps
};

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

template <typename M>
void addMsg(EventLog& log, FileReport& rep, int order, const std::string& ch, const M& m) {
  log.add(m.utime, order, ch, m);
  if (rep.written == 0) rep.first_utime = m.utime;
  rep.first_utime = std::min(rep.first_utime, static_cast<int64_t>(m.utime));
  rep.last_utime = std::max(rep.last_utime, static_cast<int64_t>(m.utime));
  ++rep.written;
}

bool parseId(const std::string& s, int& id, bool allow_unknown, std::string& why) {
  std::string low = s;
  std::transform(low.begin(), low.end(), low.begin(), [](unsigned char c) { return std::tolower(c); });
  if (allow_unknown && low == "unknown") {
    id = -1;
    return true;
  }
  double v = 0;
  if (!common::csv::parseNumber(s, 2, v, why)) {
    if (allow_unknown) why += " (an integer id >= 0 or \"unknown\")";
    return false;
  }
  if (v < 0 || v != std::floor(v) || v > 2e9) {
    why = fmt::format("column 2: id must be an integer >= 0, got '{}'", s);
    return false;
  }
  id = static_cast<int>(v);
  return true;
}

/// The options that go into config.yaml, refused with the flag's name when config.yaml would
/// not accept them (the replay would refuse the generated file).
void checkOptions(const ImportOptions& opt) {
  if (opt.wheelbase != 0.0) checkFilterValue("--wheelbase", "wheelbase", fmt::format("{}", opt.wheelbase));
  if (opt.initial_pose)
    checkFilterValue("--initial-pose", "initial_pose",
                     fmt::format("[{}, {}, {}]", (*opt.initial_pose)[0], (*opt.initial_pose)[1], (*opt.initial_pose)[2]));
  if (!opt.filter.empty()) checkFilterValue("--filter", "type", opt.filter);
}

}  // namespace

std::string toString(TimeUnit u) {
  switch (u) {
    case TimeUnit::Seconds: return "seconds";
    case TimeUnit::Microseconds: return "microseconds";
    default: return "auto";
  }
}
std::string toString(TimeBase b) {
  switch (b) {
    case TimeBase::Absolute: return "absolute";
    case TimeBase::Relative: return "relative";
    default: return "auto";
  }
}

TimeUnit detectTimeUnit(const std::vector<double>& t) {
  if (t.empty()) return TimeUnit::Seconds;
  std::vector<double> mag;  // the median, not the largest: one wrong time does not decide
  for (double v : t) mag.push_back(std::abs(v));
  std::nth_element(mag.begin(), mag.begin() + mag.size() / 2, mag.end());
  if (mag[mag.size() / 2] >= 1e11) return TimeUnit::Microseconds;
  std::vector<double> steps;
  for (std::size_t i = 1; i < t.size(); ++i)
    if (t[i] > t[i - 1]) steps.push_back(t[i] - t[i - 1]);
  if (steps.empty()) return TimeUnit::Seconds;
  std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
  return steps[steps.size() / 2] >= 1000.0 ? TimeUnit::Microseconds : TimeUnit::Seconds;
}

TimeBase detectTimeBase(int64_t first_utime) {
  return first_utime >= 1'000'000'000'000'000LL ? TimeBase::Absolute : TimeBase::Relative;
}

ImportResult importDirectory(const ImportOptions& opt) {
  ImportResult r;
  std::error_code ec;
  if (!fs::is_directory(opt.dir, ec)) throw std::runtime_error("'" + opt.dir + "' is not a directory");
  std::vector<fs::path> paths;
  for (const auto& e : fs::directory_iterator(opt.dir, ec))  // (a directory named *.csv: skipped, saying so)
    if (e.path().extension() == ".csv") paths.push_back(e.path());
  if (ec) throw std::runtime_error("cannot list '" + opt.dir + "': " + ec.message());
  std::sort(paths.begin(), paths.end());
  checkOptions(opt);
  if (!opt.out_dir.empty()) {
    const std::vector<std::string> inputs(paths.begin(), paths.end());
    for (const char* name : {"run.lcmlog", "map.csv", "config.yaml"})
      common::refuseOutputOverInputs("--output", (fs::path(opt.out_dir) / name).string(), inputs);
  }

  auto refuse = [&](FileReport& f, int64_t line, const std::string& why) {
    r.refusals.push_back({f.path, line, why});
    ++f.refused;
  };

  // Pass 1: recognise the files, read the map, split rows and read the time column.
  core::MarkerMap map;
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
  r.map_size = static_cast<int64_t>(map.size());

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
  int64_t shift = 0;  // --start-at-zero: the earliest kept time
  if (opt.start_at_zero && !in_time.empty() && in_time.front()->first_kept) shift = *in_time.front()->first_kept;

  std::map<int, core::Marker> by_id;
  for (const auto& m : map) by_id[m.id] = m;
  const common::LocalFrame frame(opt.datum);
  EventLog log;
  bool have_landmarks = false, have_beacons = false, have_gps = false;
  std::optional<core::Vec3> first_truth;
  int64_t first_truth_utime = 0;
  std::map<std::string, int64_t> seq;
  // Landmarks, beacons and gps may come from several files at once: numbered per channel in
  // time order once all are read (the daemon counts a jump in seq as lost messages).
  std::vector<std::pair<lcmloc::landmark_obs_t, FileReport*>> landmark_msgs;
  std::vector<std::pair<lcmloc::beacon_range_t, FileReport*>> beacon_msgs;
  std::vector<std::pair<lcmloc::gps_fix_t, FileReport*>> gps_msgs;

  // Pass 2: convert, file after file in time order (sequence numbers in time order), each
  // file's rows in line order.
  for (const DataFile* in_order : in_time) {
    DataFile& df = files[static_cast<std::size_t>(in_order - files.data())];
    FileReport& rep = df.report;
    if (df.format == Format::OdoSteering && !(opt.wheelbase > 0))
      throw std::runtime_error("'" + rep.path + "': speed,steering odometry needs --wheelbase (L [m], eq. 2)");
    bool have_prev = false;
    int64_t t_prev = 0;
    double a_prev = 0, b_prev = 0, dist = 0, x_prev = 0, y_prev = 0;
    std::string why;
    std::vector<double> v;
    for (auto& row : df.rows) {
      row.utime -= shift;
      const int64_t ln = row.line;
      v.assign(row.fields.size(), 0.0);
      v[0] = row.t_raw;
      bool ok = true;
      int id = -1;
      for (std::size_t i = 1; i < row.fields.size() && ok; ++i) {
        if ((df.format == Format::Landmarks || df.format == Format::Beacons) && i == 1)
          ok = parseId(row.fields[1], id, df.format == Format::Landmarks, why);
        else
          ok = common::csv::parseNumber(row.fields[i], i + 1, v[i], why);
      }
      if (!row.time_refusal.empty()) { refuse(rep, ln, row.time_refusal); continue; }
      if (!ok) { refuse(rep, ln, why); continue; }
      const double dt = have_prev ? (row.utime - t_prev) * 1e-6 : 0.0;
      switch (df.format) {
        case Format::OdoDelta:
        case Format::OdoYawRate:
        case Format::OdoSteering: {
          lcmloc::odometry_t m{};
          m.utime = row.utime;
          m.ticks = 0;
          if (df.format == Format::OdoDelta) {
            if (std::abs(v[1]) > 100.0) { refuse(rep, ln, fmt::format("|delta_s| {} m above 100 m", v[1])); continue; }
            if (std::abs(v[2]) > kPi) { refuse(rep, ln, fmt::format("|delta_theta| {} rad above pi", v[2])); continue; }
            m.delta_s = v[1];
            m.delta_theta = v[2];
            m.has_steering = false;
          } else {
            if (std::abs(v[1]) > 100.0) { refuse(rep, ln, fmt::format("|speed| {} m/s above 100 m/s", v[1])); continue; }
            if (df.format == Format::OdoSteering && std::abs(v[2]) >= kPi / 2) {
              refuse(rep, ln, fmt::format("|steering| {} rad not below pi/2", v[2]));
              continue;
            }
            if (df.format == Format::OdoYawRate && std::abs(v[2]) > 100.0) {
              refuse(rep, ln, fmt::format("|yaw_rate| {} rad/s above 100 rad/s", v[2]));
              continue;
            }
            // the speed and rate of a row hold until the next row (the first row starts the interval)
            m.delta_s = a_prev * dt;
            if (df.format == Format::OdoYawRate) {
              m.delta_theta = b_prev * dt;
              m.has_steering = false;
            } else {
              m.has_steering = true;
              m.steering = have_prev ? b_prev : v[2];
              m.delta_theta = m.delta_s * std::tan(m.steering) / opt.wheelbase;
            }
            if (std::abs(m.delta_theta) > kPi) {
              refuse(rep, ln, fmt::format("heading increment {} rad over {} s above pi", m.delta_theta, dt));
              continue;
            }
            a_prev = v[1];
            b_prev = v[2];
          }
          m.seq = seq[opt.channels.odometry]++;
          addMsg(log, rep, 1, opt.channels.odometry, m);
          break;
        }
        case Format::Landmarks: {
          if (id >= 0 && !by_id.count(id)) {
            refuse(rep, ln, map.empty() ? fmt::format("landmark id {}: no map file (id,x,y) in the directory", id)
                                        : fmt::format("landmark id {} not in the map", id));
            continue;
          }
          if (v[2] < 0) { refuse(rep, ln, fmt::format("negative range {}", v[2])); continue; }
          if (std::abs(v[3]) > kPi) { refuse(rep, ln, fmt::format("bearing {} outside [-pi, pi] (radians expected)", v[3])); continue; }
          lcmloc::landmark_obs_t m{};
          m.utime = row.utime;
          m.landmark_id = id;
          m.range = v[2];
          m.bearing = core::wrapAngle(v[3]);
          landmark_msgs.emplace_back(m, &rep);
          have_landmarks = true;
          break;
        }
        case Format::Beacons: {
          if (!by_id.count(id)) {
            refuse(rep, ln, map.empty() ? fmt::format("beacon id {}: no map file (id,x,y) in the directory", id)
                                        : fmt::format("beacon id {} not in the map", id));
            continue;
          }
          if (v[2] < 0) { refuse(rep, ln, fmt::format("negative range {}", v[2])); continue; }
          lcmloc::beacon_range_t m{};
          m.utime = row.utime;
          m.beacon_id = id;
          m.range = v[2];
          beacon_msgs.emplace_back(m, &rep);
          have_beacons = true;
          break;
        }
        case Format::GpsLocal:
        case Format::GpsGeo: {
          lcmloc::gps_fix_t m{};
          m.utime = row.utime;
          m.fix_type = 2;
          m.hdop = NAN;
          m.position_std = v.size() > 3 ? v[3] : 0.0;
          if (m.position_std < 0) { refuse(rep, ln, "negative position_std"); continue; }
          if (df.format == Format::GpsLocal) {
            if (std::abs(v[1]) > 1e5 || std::abs(v[2]) > 1e5) {
              refuse(rep, ln, fmt::format("position ({}, {}) m more than 100 km from the origin", v[1], v[2]));
              continue;
            }
            frame.toGeodetic(v[1], v[2], 0.0, m.latitude, m.longitude, m.altitude);
          } else {
            if (std::abs(v[1]) > 90 || std::abs(v[2]) > 180) {
              refuse(rep, ln, fmt::format("latitude/longitude ({}, {}) out of range", v[1], v[2]));
              continue;
            }
            m.latitude = v[1];
            m.longitude = v[2];
            m.altitude = opt.datum.altitude;
          }
          gps_msgs.emplace_back(m, &rep);
          have_gps = true;
          break;
        }
        case Format::Truth: {
          lcmloc::ground_truth_t m{};
          m.utime = row.utime;
          m.x = v[1];
          m.y = v[2];
          m.heading = core::wrapAngle(v[3]);
          const double step = have_prev ? std::hypot(v[1] - x_prev, v[2] - y_prev) : 0.0;
          dist += step;
          m.speed = dt > 0 ? step / dt : 0.0;
          m.steering = 0;
          m.distance = dist;
          x_prev = v[1];
          y_prev = v[2];
          if (!first_truth || m.utime < first_truth_utime) {
            first_truth = core::Vec3(m.x, m.y, m.heading);
            first_truth_utime = m.utime;
          }
          m.seq = seq[opt.channels.ground_truth]++;
          addMsg(log, rep, 0, opt.channels.ground_truth, m);
          break;
        }
        case Format::Map: break;
      }
      have_prev = true;
      t_prev = row.utime;
    }
  }
  auto addInTimeOrder = [&](auto& msgs, int order, const std::string& channel) {
    std::stable_sort(msgs.begin(), msgs.end(),
                     [](const auto& a, const auto& b) { return a.first.utime < b.first.utime; });
    for (auto& [m, rep] : msgs) {
      m.seq = seq[channel]++;
      addMsg(log, *rep, order, channel, m);
    }
  };
  addInTimeOrder(landmark_msgs, 2, opt.channels.landmarks);
  addInTimeOrder(beacon_msgs, 3, opt.channels.beacons);
  addInTimeOrder(gps_msgs, 4, opt.channels.gps);

  log.sort();
  r.messages = static_cast<int64_t>(log.size());
  r.first_utime = log.firstUtime();
  r.last_utime = log.lastUtime();
  r.files.clear();
  for (const auto& f : files) r.files.push_back(f.report);
  if (!opt.filter.empty()) r.filter = opt.filter;
  else if (have_landmarks || have_beacons) r.filter = "ukf_landmarks";
  else if (have_gps) r.filter = "ukf_gps";
  else r.filter = "dead_reckoning";

  if (!opt.out_dir.empty() && r.usable()) {
    fs::create_directories(opt.out_dir, ec);
    if (ec) throw std::runtime_error("cannot create '" + opt.out_dir + "': " + ec.message());
    r.log_path = (fs::path(opt.out_dir) / "run.lcmlog").string();
    log.write(r.log_path);
    if (!map.empty()) {
      r.map_path = (fs::path(opt.out_dir) / "map.csv").string();
      common::csv::writeMap(r.map_path, map);
    }
    r.config_path = (fs::path(opt.out_dir) / "config.yaml").string();
    const core::Vec3 pose = opt.initial_pose ? *opt.initial_pose : first_truth ? *first_truth : core::Vec3::Zero();
    const core::FilterConfig d;
    std::ofstream c(r.config_path);
    c << "# Written by lcmloc-import from " << opt.dir << " (docs/import_formats.md).\n"
      << "# Replay: lcmloc-replay run.lcmlog --config config.yaml --with-inputs -o estimates.lcmlog\n"
      << "scenario: {name: import, seed: 1, realtime_factor: 0.0}\n"
      << "markers: {count: 0}            # the map is fusion.map_file\n"
      << fmt::format("datum: {{latitude: {:.9f}, longitude: {:.9f}, altitude: {:.3f}}}\n", opt.datum.latitude,
                     opt.datum.longitude, opt.datum.altitude)
      << "fusion:\n"
      << "  shadow: []\n";
    if (!map.empty()) c << "  map_file: map.csv              # id,x,y [m]\n";
    c << "  filter:\n"
      << "    type: " << r.filter << "\n"
      << fmt::format("    initial_pose: [{:.6f}, {:.6f}, {:.6f}]   # x [m], y [m], theta [rad]{}\n", pose[0], pose[1],
                     pose[2], opt.initial_pose ? "" : first_truth ? " (first ground-truth row)" : " (no ground truth)")
      << fmt::format("    p0_diag: [{}, {}, {}]        # initial variances [m^2, m^2, rad^2]\n", d.p0_diag[0],
                     d.p0_diag[1], d.p0_diag[2]);
    if (opt.wheelbase > 0) c << fmt::format("    wheelbase: {}\n", opt.wheelbase);
    c << fmt::format("    pw_diag: [{}, {}, {}]     # process noise accumulated over pw_distance of travel\n",
                     d.pw_diag[0], d.pw_diag[1], d.pw_diag[2])
      << fmt::format("    pw_distance: {}                # [m]\n", d.pw_distance)
      << fmt::format("    pw_turn: {}                   # heading variance per radian turned [rad^2/rad]\n", d.pw_turn)
      << fmt::format("    landmarks: {{range_std: {}, bearing_std: {}, beacon_std: {}}}  # [m], [rad], [m]\n",
                     d.landmarks.range_std, d.landmarks.bearing_std, d.landmarks.beacon_std)
      << "    gate: {enabled: true, probability: 0.99}\n";
    if (!c) throw std::runtime_error("cannot write '" + r.config_path + "'");
  }
  return r;
}

std::string importSummary(const ImportResult& r, int max_refusals) {
  std::string s;
  for (const auto& f : r.files)
    s += fmt::format("{}: {} ({}), times in {} ({}): {} rows read, {} refused, {} messages, {:.3f} s .. {:.3f} s\n",
                     f.path, f.kind, f.header, toString(f.unit), toString(f.base), f.rows, f.refused, f.written,
                     f.first_utime * 1e-6, f.last_utime * 1e-6);
  for (const auto& k : r.skipped) s += "skipped " + k + "\n";
  if (r.map_size > 0) s += fmt::format("map: {} entries\n", r.map_size);
  s += fmt::format("total: {} messages, time span {:.3f} s .. {:.3f} s ({:.3f} s), {} rows refused\n", r.messages,
                   r.first_utime * 1e-6, r.last_utime * 1e-6, (r.last_utime - r.first_utime) * 1e-6,
                   r.refusals.size());
  const std::size_t shown = std::min(r.refusals.size(), static_cast<std::size_t>(std::max(max_refusals, 0)));
  for (std::size_t i = 0; i < shown; ++i)
    s += fmt::format("refused {}:{}: {}\n", r.refusals[i].file, r.refusals[i].line, r.refusals[i].reason);
  if (shown < r.refusals.size()) s += fmt::format("... and {} more refused rows\n", r.refusals.size() - shown);
  if (!r.log_path.empty())
    s += fmt::format("wrote {}{}, {} (filter {})\n", r.log_path, r.map_path.empty() ? "" : ", " + r.map_path,
                     r.config_path, r.filter);
  return s;
}

}  // namespace lcmloc::import
