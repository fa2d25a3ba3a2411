// Pass 2 of lcmloc-import (import_files.hpp): the rows of each file converted into our messages
// (odometry, landmark and beacon observations, GPS fixes, ground truth, IMU samples), with the range checks
// that refuse a row.
#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "import_files.hpp"
#include "lcmloc/app/csv.hpp"
#include "lcmloc/beacon_range_t.hpp"
#include "lcmloc/bus/convert.hpp"
#include "lcmloc/bus/geodesy.hpp"
#include "lcmloc/core/angles.hpp"
#include "lcmloc/gps_fix_t.hpp"
#include "lcmloc/ground_truth_t.hpp"
#include "lcmloc/imu_t.hpp"
#include "lcmloc/landmark_obs_t.hpp"
#include "lcmloc/odometry_t.hpp"

namespace lcmloc::import::detail {
namespace {

constexpr double kPi = 3.14159265358979323846;

template <typename M>
void addMsg(EventLog& log, FileReport& rep, int order, const std::string& ch, const M& m) {
  log.add(m.utime, order, ch, m);
  if (rep.written == 0) rep.first_utime = m.utime;
  rep.first_utime = std::min(rep.first_utime, static_cast<int64_t>(m.utime));
  rep.last_utime = std::max(rep.last_utime, static_cast<int64_t>(m.utime));
  ++rep.written;
}

/// The id column (landmark_id, beacon_id; column number c): an integer >= 0, or "unknown" = -1
/// (the filter associates the observation with the map itself).
bool parseId(const std::string& s, std::size_t c, int& id, std::string& why) {
  std::string low = s;
  std::transform(low.begin(), low.end(), low.begin(), [](unsigned char ch) { return std::tolower(ch); });
  if (low == "unknown") {
    id = -1;
    return true;
  }
  double v = 0;
  if (!app::csv::parseNumber(s, c, v, why)) {
    why += " (an integer id >= 0 or \"unknown\")";
    return false;
  }
  if (v < 0 || v != std::floor(v) || v > 2e9) {
    why = fmt::format("column {}: id must be an integer >= 0, got '{}'", c, s);
    return false;
  }
  id = static_cast<int>(v);
  return true;
}

/// A per-row 1-sigma column (its name ends in _std): finite (parseNumber) and > 0.
bool checkStd(const std::string& name, std::size_t c, double v, std::string& why) {
  if (v > 0) return true;
  why = fmt::format("column {}: {} must be > 0, got {} (a column of sigmas holds one for every row; leave the column "
                    "out for the config's default)", c, name, v);
  return false;
}

/// Ground truth, position only: the initial heading is the direction of travel from the first
/// row to the first row at least this far from it [m]: far enough for a motion-capture or RTK
/// truth's noise (millimetres to a centimetre), near enough that the vehicle has not turned yet
/// (a chord of a metre in a labyrinth or a parking manoeuvre bends).
constexpr double kTravelForHeading = 0.1;
/// A ground-truth position further from the origin than this is refused [m] (the bound of
/// fusion.filter.initial_pose, where the first one goes).
constexpr double kMaxPosition = 1e7;

}  // namespace

Converted convertRows(std::vector<DataFile>& files, const std::vector<const DataFile*>& in_time,
                      const core::MarkerMap& map, const ImportOptions& opt, ImportResult& r) {
  auto refuse = [&r](FileReport& f, int64_t line, const std::string& why) { detail::refuse(r, f, line, why); };
  int64_t shift = 0;  // --start-at-zero: the earliest kept time
  if (opt.start_at_zero && !in_time.empty() && in_time.front()->first_kept) shift = *in_time.front()->first_kept;

  std::map<int, core::Marker> by_id;
  for (const auto& m : map) by_id[m.id] = m;
  const bus::LocalFrame frame(opt.datum);
  Converted out;
  EventLog& log = out.log;
  bool& have_landmarks = out.have_landmarks;
  bool& have_beacons = out.have_beacons;
  bool& have_gps = out.have_gps;
  std::optional<core::Vec3>& first_truth = out.first_truth;
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
    // a named column's value in v (all but the id column), or `otherwise` when the file has none
    auto at = [&](const char* name, double otherwise = 0.0) {
      const std::size_t i = df.col(name);
      return i == std::string::npos ? otherwise : v[i];
    };
    for (auto& row : df.rows) {
      row.utime -= shift;
      const int64_t ln = row.line;
      v.assign(row.fields.size(), 0.0);
      v[0] = row.t_raw;
      bool ok = true;
      int id = -1;
      for (std::size_t i = 1; i < row.fields.size() && ok; ++i) {
        const std::string& name = df.names[i];
        if (name == "landmark_id" || name == "beacon_id")
          ok = parseId(row.fields[i], i + 1, id, why);
        else
          ok = app::csv::parseNumber(row.fields[i], i + 1, v[i], why) &&
               (name.size() < 4 || name.compare(name.size() - 4, 4, "_std") != 0 || checkStd(name, i + 1, v[i], why));
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
            const double ds = at("delta_s"), dth = at("delta_theta");
            if (std::abs(ds) > 100.0) { refuse(rep, ln, fmt::format("|delta_s| {} m above 100 m", ds)); continue; }
            if (std::abs(dth) > kPi) { refuse(rep, ln, fmt::format("|delta_theta| {} rad above pi", dth)); continue; }
            m.delta_s = ds;
            m.delta_theta = dth;
            m.has_steering = false;
          } else {
            const double speed = at("speed");
            const double turn = df.format == Format::OdoYawRate ? at("yaw_rate") : at("steering");
            if (std::abs(speed) > 100.0) { refuse(rep, ln, fmt::format("|speed| {} m/s above 100 m/s", speed)); continue; }
            if (df.format == Format::OdoSteering && std::abs(turn) >= kPi / 2) {
              refuse(rep, ln, fmt::format("|steering| {} rad not below pi/2", turn));
              continue;
            }
            if (df.format == Format::OdoYawRate && std::abs(turn) > 100.0) {
              refuse(rep, ln, fmt::format("|yaw_rate| {} rad/s above 100 rad/s", turn));
              continue;
            }
            // the speed and rate of a row hold until the next row (the first row starts the interval)
            m.delta_s = a_prev * dt;
            if (df.format == Format::OdoYawRate) {
              m.delta_theta = b_prev * dt;
              m.has_steering = false;
            } else {
              m.has_steering = true;
              m.steering = have_prev ? b_prev : turn;
              m.delta_theta = m.delta_s * std::tan(m.steering) / opt.wheelbase;
            }
            if (std::abs(m.delta_theta) > kPi) {
              refuse(rep, ln, fmt::format("heading increment {} rad over {} s above pi", m.delta_theta, dt));
              continue;
            }
            a_prev = speed;
            b_prev = turn;
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
          const double range = at("range"), bearing = at("bearing");
          if (range < 0) { refuse(rep, ln, fmt::format("negative range {}", range)); continue; }
          if (std::abs(bearing) > kPi) { refuse(rep, ln, fmt::format("bearing {} outside [-pi, pi] (radians expected)", bearing)); continue; }
          lcmloc::landmark_obs_t m{};
          m.utime = row.utime;
          m.landmark_id = id;
          m.range = range;
          m.bearing = core::wrapAngle(bearing);
          m.range_std = at("range_std");      // 0: the filter's default
          m.bearing_std = at("bearing_std");
          landmark_msgs.emplace_back(m, &rep);
          have_landmarks = true;
          break;
        }
        case Format::Beacons: {
          if (map.empty()) {
            refuse(rep, ln, "a beacon range: no map file (id,x,y) in the directory");
            continue;
          }
          if (id >= 0 && !by_id.count(id)) {  // (-1: unknown, associated by the filter)
            refuse(rep, ln, fmt::format("beacon id {} not in the map", id));
            continue;
          }
          const double range = at("range");
          if (range < 0) { refuse(rep, ln, fmt::format("negative range {}", range)); continue; }
          lcmloc::beacon_range_t m{};
          m.utime = row.utime;
          m.beacon_id = id;
          m.range = range;
          m.range_std = at("range_std");      // 0: the filter's default
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
          m.position_std = at("position_std");  // 0: the filter's default
          if (df.format == Format::GpsLocal) {
            const double x = at("x"), y = at("y");
            if (std::abs(x) > 1e5 || std::abs(y) > 1e5) {
              refuse(rep, ln, fmt::format("position ({}, {}) m more than 100 km from the origin", x, y));
              continue;
            }
            frame.toGeodetic(x, y, 0.0, m.latitude, m.longitude, m.altitude);
          } else {
            const double lat = at("latitude"), lon = at("longitude");
            if (std::abs(lat) > 90 || std::abs(lon) > 180) {
              refuse(rep, ln, fmt::format("latitude/longitude ({}, {}) out of range", lat, lon));
              continue;
            }
            m.latitude = lat;
            m.longitude = lon;
            m.altitude = opt.datum.altitude;
          }
          gps_msgs.emplace_back(m, &rep);
          have_gps = true;
          break;
        }
        case Format::Truth: {
          const bool pose = df.col("heading") != std::string::npos || df.col("truth_heading") != std::string::npos;
          const double x = df.col("x") != std::string::npos ? at("x") : at("truth_x");
          const double y = df.col("y") != std::string::npos ? at("y") : at("truth_y");
          if (std::abs(x) > kMaxPosition || std::abs(y) > kMaxPosition) {
            refuse(rep, ln, fmt::format("position ({}, {}) m more than {} km from the origin", x, y, kMaxPosition / 1e3));
            continue;
          }
          lcmloc::ground_truth_t m{};
          m.utime = row.utime;
          m.x = x;
          m.y = y;
          // position only: NaN (lcmloc-evaluate then scores the position alone)
          m.heading = pose ? core::wrapAngle(df.col("heading") != std::string::npos ? at("heading") : at("truth_heading"))
                           : NAN;
          const double step = have_prev ? std::hypot(x - x_prev, y - y_prev) : 0.0;
          dist += step;
          m.speed = dt > 0 ? step / dt : 0.0;
          m.steering = 0;
          m.distance = dist;
          x_prev = x;
          y_prev = y;
          if (!first_truth) {  // truth files are one stream in time order: the first row is the earliest
            first_truth = core::Vec3(x, y, pose ? m.heading : 0.0);
            out.truth_heading = pose ? "row" : "none";
          } else if (out.truth_heading == "none" &&
                     std::hypot(x - (*first_truth)[0], y - (*first_truth)[1]) >= kTravelForHeading) {
            (*first_truth)[2] = std::atan2(y - (*first_truth)[1], x - (*first_truth)[0]);
            out.truth_heading = "travel";
          }
          m.seq = seq[opt.channels.ground_truth]++;
          addMsg(log, rep, 0, opt.channels.ground_truth, m);
          break;
        }
        case Format::Imu: {
          static const char* const kAccel[] = {"accel_x", "accel_y", "accel_z"};
          static const char* const kGyro[] = {"gyro_x", "gyro_y", "gyro_z"};
          static const char* const kMag[] = {"mag_x", "mag_y", "mag_z"};
          const bool with_mag = df.col("mag_x") != std::string::npos;
          lcmloc::imu_t m{};
          m.utime = row.utime;
          for (int k = 0; k < 3; ++k) {
            m.accel[k] = at(kAccel[k]);
            m.gyro[k] = at(kGyro[k]);
            m.mag[k] = at(kMag[k]);  // 0 without a magnetometer (config.yaml then turns it off)
          }
          std::string bad;  // what the fusion would refuse (lcmloc/bus/convert.hpp), refused here
          if (!bus::toCore(m, opt.channels.imu, &bad)) { refuse(rep, ln, bad); continue; }
          out.imu_without_mag = out.imu_without_mag || !with_mag;
          out.have_imu = true;
          m.seq = seq[opt.channels.imu]++;
          addMsg(log, rep, 1, opt.channels.imu, m);
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
  out.landmarks_written = static_cast<int64_t>(landmark_msgs.size());
  for (const auto& lm : landmark_msgs) out.landmarks_without_identity += lm.first.landmark_id < 0;
  addInTimeOrder(landmark_msgs, 2, opt.channels.landmarks);
  addInTimeOrder(beacon_msgs, 3, opt.channels.beacons);
  addInTimeOrder(gps_msgs, 4, opt.channels.gps);
  return out;
}

}  // namespace lcmloc::import::detail
