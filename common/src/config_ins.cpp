#include "config_ins.hpp"

#include <cmath>
#include <limits>

namespace lcmloc::common::ins_config {

void parseInsSim(KeyReader& root, models::InsSimConfig& c) {
  KeyReader r(root.child("ins_sim"), root.file(), "ins_sim");
  r.get<uint64_t>("seed", c.seed);
  r.get("rate_hz", c.rate_hz, 1.0, 10000.0);
  r.get("odometry_divider", c.odometry_divider, 1, 10000);
  r.get("duration", c.duration, 0.01, 1e6);
  r.get("profile", c.profile);
  if (c.profile != "paper" && c.profile != "custom")
    throw ConfigError(root.file(), "ins_sim.profile", "unknown profile '" + c.profile + "' (valid: paper, custom)");
  r.get("start", c.start);
  if (!models::insStartValid(c.start))
    throw ConfigError(root.file(), "ins_sim.start",
                      "unknown start '" + c.start + "' (valid: hard, gentle, gentle_turn, gentle_stopgo, steady)");
  YAML::Node segs = r.child("segments");
  if (segs && !segs.IsNull()) {
    const std::string kp = r.keyPath("segments");
    if (!segs.IsSequence()) throw ConfigError(root.file(), kp, "expected a list of {duration, accel, yaw_rate}");
    c.segments.clear();
    for (std::size_t i = 0; i < segs.size(); ++i) {
      models::InsMotionSegment s;
      KeyReader sr(segs[i], root.file(), kp + "[" + std::to_string(i) + "]");
      sr.get("duration", s.duration, 1e-3, 1e6);
      sr.get("accel", s.accel, -20.0, 20.0);
      sr.get("yaw_rate", s.yaw_rate, -180.0, 180.0, "deg/s");
      sr.finish();
      c.segments.push_back(s);
    }
  }
  if (c.profile == "custom" && c.segments.empty())
    throw ConfigError(root.file(), "ins_sim.segments", "the custom profile needs a non-empty list of segments");
  r.get("latitude", c.latitude, -89.0, 89.0);
  r.get("longitude", c.longitude, -180.0, 180.0);
  r.get("height", c.height, -1e4, 1e5);
  r.get("heading", c.heading, -M_PI, M_PI);
  r.get("gyro_markov", c.gyro_markov, 0.0, 1e6, "deg/h");
  r.get("gyro_tau", c.gyro_tau, 1e-3, 1e9);
  r.get("gyro_white", c.gyro_white, 0.0, 1e6, "deg/h");
  r.get("accel_markov", c.accel_markov, 0.0, 1.0, "g");
  r.get("accel_tau", c.accel_tau, 1e-3, 1e9);
  r.get("accel_white", c.accel_white, 0.0, 1.0, "g");
  r.get("scale_error", c.scale_error, -0.5, 0.5);
  r.get("scale_markov", c.scale_markov, 0.0, 0.5);
  r.get("scale_tau", c.scale_tau, 1e-3, 1e9);
  r.get("scale_white", c.scale_white, 0.0, 0.5);
  YAML::Node drops = r.child("imu_dropouts");
  if (drops && !drops.IsNull()) {
    const std::string kp = r.keyPath("imu_dropouts");
    if (!drops.IsSequence()) throw ConfigError(root.file(), kp, "expected a list of {start, duration}");
    c.imu_dropouts.clear();
    for (std::size_t i = 0; i < drops.size(); ++i) {
      double start = 0, duration = 0;
      KeyReader dr(drops[i], root.file(), kp + "[" + std::to_string(i) + "]");
      dr.get("start", start, 0.0, 1e7);
      dr.get("duration", duration, 0.0, 1e7);
      dr.finish();
      c.imu_dropouts.emplace_back(start, duration);
    }
  }
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
  r.get("gyro_markov", c.gyro_markov, 0.0, 1e6, "deg/h");
  r.get("gyro_tau", c.gyro_tau, 1e-3, 1e9);
  r.get("gyro_white", c.gyro_white, 0.0, 1e6, "deg/h");
  r.get("accel_markov", c.accel_markov, 0.0, 1.0, "g");
  r.get("accel_tau", c.accel_tau, 1e-3, 1e9);
  r.get("accel_white", c.accel_white, 0.0, 1.0, "g");
  r.get("odo_scale", c.odo_scale, 0.0, 0.5);
  r.get("odo_markov", c.odo_markov, 0.0, 0.5);
  r.get("odo_tau", c.odo_tau, 1e-3, 1e9);
  r.get("odo_white", c.odo_white, 0.0, 0.5);
  r.get("attitude_term", c.attitude_term);
  r.get("paper_exact_h", c.paper_exact_h);
  r.get("max_imu_gap", c.max_imu_gap, 1e-4, 1e3);
  r.finish();
}

void parseLandmarks(KeyReader& fusion, std::map<int, core::Vec2>& landmarks) {
  YAML::Node n = fusion.child("landmarks");
  if (!n) return;
  const std::string kp = fusion.keyPath("landmarks");
  landmarks.clear();
  if (n.IsNull()) return;
  if (!n.IsSequence()) throw ConfigError(fusion.file(), kp, "expected a list of {id, x, y}");
  for (std::size_t i = 0; i < n.size(); ++i) {
    const std::string ip = kp + "[" + std::to_string(i) + "]";
    KeyReader r(n[i], fusion.file(), ip);
    int id = -1;
    double x = std::numeric_limits<double>::quiet_NaN(), y = x;
    r.get("id", id, 0, std::numeric_limits<int>::max());
    r.get("x", x, -1e8, 1e8);
    r.get("y", y, -1e8, 1e8);
    r.finish();
    if (id < 0 || !std::isfinite(x) || !std::isfinite(y))
      throw ConfigError(fusion.file(), ip, "a landmark needs id, x and y");
    if (!landmarks.emplace(id, core::Vec2(x, y)).second)
      throw ConfigError(fusion.file(), ip + ".id", "landmark id " + std::to_string(id) + " given twice");
  }
}

}  // namespace lcmloc::common::ins_config
