#include "config_ins.hpp"

#include <cmath>
#include <limits>

namespace lcmloc::common::ins_config {
namespace {

/// The IMU error model's keys, the same in the simulator's and in the filter's section: the
/// filter models the sensor the simulator draws (first-order Markov + white noise per axis).
template <class Config>
void readImuErrorModel(KeyReader& r, Config& c) {
  r.get("gyro_markov", c.gyro_markov, 0.0, 1e6, "deg/h");
  r.get("gyro_tau", c.gyro_tau, 1e-3, 1e9);
  r.get("gyro_white", c.gyro_white, 0.0, 1e6, "deg/h");
  r.get("accel_markov", c.accel_markov, 0.0, 1.0, "g");
  r.get("accel_tau", c.accel_tau, 1e-3, 1e9);
  r.get("accel_white", c.accel_white, 0.0, 1.0, "g");
}

}  // namespace

void parseInsSim(KeyReader& root, models::InsSimConfig& c) {
  KeyReader r(root.child("ins_sim"), root.file(), "ins_sim");
  r.get<uint64_t>("seed", c.seed);
  r.get("rate_hz", c.rate_hz, 1.0, 10000.0);
  r.get("odometry_divider", c.odometry_divider, 1, 10000);
  r.get("duration", c.duration, kInsSimDuration.lo, kInsSimDuration.hi);
  r.get("profile", c.profile);
  if (c.profile != "paper" && c.profile != "custom")
    throw ConfigError(root.file(), "ins_sim.profile", "unknown profile '" + c.profile + "' (valid: paper, custom)");
  r.get("start", c.start);
  if (!models::insStartValid(c.start))
    throw ConfigError(root.file(), "ins_sim.start",
                      "unknown start '" + c.start + "' (valid: hard, gentle, gentle_turn, gentle_stopgo, steady)");
  r.getList("segments", c.segments, "{duration, accel, yaw_rate}", [](KeyReader& s, models::InsMotionSegment& v) {
    s.get("duration", v.duration, 1e-3, 1e6);
    s.get("accel", v.accel, -20.0, 20.0);
    s.get("yaw_rate", v.yaw_rate, -180.0, 180.0, "deg/s");
  });
  if (c.profile == "custom" && c.segments.empty())
    throw ConfigError(root.file(), "ins_sim.segments", "the custom profile needs a non-empty list of segments");
  r.get("latitude", c.latitude, -89.0, 89.0);
  r.get("longitude", c.longitude, -180.0, 180.0);
  r.get("height", c.height, -1e4, 1e5);
  r.get("heading", c.heading, -M_PI, M_PI);
  readImuErrorModel(r, c);
  r.get("scale_error", c.scale_error, -0.5, 0.5);
  r.get("scale_markov", c.scale_markov, 0.0, 0.5);
  r.get("scale_tau", c.scale_tau, 1e-3, 1e9);
  r.get("scale_white", c.scale_white, 0.0, 0.5);
  r.getList("imu_dropouts", c.imu_dropouts, "{start, duration}", [](KeyReader& d, auto& v) {
    d.get("start", v.first, 0.0, 1e7);
    d.get("duration", v.second, 0.0, 1e7);
  });
  r.finish();
}

void parseInsFilter(KeyReader& filter, core::InsFilterConfig& c) {
  KeyReader r(filter.child("ins"), filter.file(), filter.keyPath("ins"));
  r.get("latitude", c.latitude, -89.0, 89.0);
  r.get("longitude", c.longitude, -180.0, 180.0);
  r.get("height", c.height, -1e4, 1e5);
  r.getVector("init_att_std", c.init_att_std, 1e-9, 1e4);
  r.get("init_vel_std", c.init_vel_std, 1e-9, 1e3);
  r.get("init_pos_std", c.init_pos_std, 1e-9, 1e6);
  r.get("meas_vel_std", c.meas_vel_std, 1e-9, 1e3);
  readImuErrorModel(r, c);
  r.get("odo_scale", c.odo_scale, 0.0, 0.5);
  r.get("odo_markov", c.odo_markov, 0.0, 0.5);
  r.get("odo_tau", c.odo_tau, 1e-3, 1e9);
  r.get("odo_white", c.odo_white, 0.0, 0.5);
  r.get("attitude_term", c.attitude_term);
  r.get("paper_exact_h", c.paper_exact_h);
  r.get("max_imu_gap", c.max_imu_gap, 1e-4, 1e3);
  r.get("max_coast", c.max_coast, 0.0, 1e5);
  r.finish();
}

void parseLandmarkList(KeyReader& parent, const std::string& key, std::vector<models::Landmark>& out) {
  YAML::Node n = parent.child(key);
  if (!n) return;
  out.clear();
  if (n.IsNull()) return;
  const std::string kp = parent.keyPath(key);
  if (!n.IsSequence()) throw ConfigError(parent.file(), kp, "expected a list of {id, x, y}, got " + yaml_detail::nodeText(n));
  for (std::size_t i = 0; i < n.size(); ++i) {
    const std::string ip = kp + "[" + std::to_string(i) + "]";
    models::Landmark l;
    KeyReader r(n[i], parent.file(), ip);
    if (!r.child("id")) throw ConfigError(parent.file(), ip + ".id", "missing (every landmark needs an id)");
    r.get("id", l.id);
    if (!r.child("x") || !r.child("y")) throw ConfigError(parent.file(), ip, "missing x or y");
    r.get("x", l.x, -1e7, 1e7);
    r.get("y", l.y, -1e7, 1e7);
    r.finish();
    for (std::size_t j = 0; j < out.size(); ++j) {
      if (out[j].id == l.id)
        throw ConfigError(parent.file(), ip + ".id",
                          "duplicate landmark id " + std::to_string(l.id) + " (also " + kp + "[" + std::to_string(j) + "])");
      // Two ids at one place: a bearing to either is the same, and a fix from both is singular.
      if (std::hypot(out[j].x - l.x, out[j].y - l.y) < 1e-3)
        throw ConfigError(parent.file(), ip,
                          "landmark " + std::to_string(l.id) + " is at the place of landmark " + std::to_string(out[j].id) +
                              " (" + kp + "[" + std::to_string(j) + "]), less than 1 mm apart");
    }
    out.push_back(l);
  }
}

void parseLandmarks(KeyReader& fusion, std::map<int, core::Vec2>& landmarks) {
  std::vector<models::Landmark> list;
  if (!fusion.child("landmarks")) return;  // absent: unchanged
  parseLandmarkList(fusion, "landmarks", list);
  landmarks.clear();
  for (const auto& l : list) landmarks.emplace(l.id, core::Vec2(l.x, l.y));
}

}  // namespace lcmloc::common::ins_config
