// Pass 2 of lcmloc-import (import_files.hpp): the rows of each file converted into our messages
// (odometry, landmark and beacon observations, GPS fixes, ground truth), with the range checks
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
#include "lcmloc/bus/geodesy.hpp"
#include "lcmloc/core/angles.hpp"
#include "lcmloc/gps_fix_t.hpp"
#include "lcmloc/ground_truth_t.hpp"
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

}  // namespace

Converted convertRows(std::vector<DataFile>& files, const std::vector<const DataFile*>& in_time,
                      const core::MarkerMap& map, const ImportOptions& opt, ImportResult& r) {
  auto refuse = [&r](FileReport& f, int64_t line, const std::string& why) { detail::refuse(r, f, line, why); };
  int64_t shift = 0;  // --start-at-zero: the earliest kept time
  if (opt.start_at_zero && !in_time.empty() && in_time.front()->first_kept) shift = *in_time.front()->first_kept;

  std::map<int, core::Marker> by_id;
  for (const auto& m : map) by_id[m.id] = m;
  const common::LocalFrame frame(opt.datum);
  Converted out;
  EventLog& log = out.log;
  bool& have_landmarks = out.have_landmarks;
  bool& have_beacons = out.have_beacons;
  bool& have_gps = out.have_gps;
  std::optional<core::Vec3>& first_truth = out.first_truth;
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
  return out;
}

}  // namespace lcmloc::import::detail
