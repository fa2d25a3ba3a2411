#include "config_ins.hpp"

#include <cmath>

#include "lcmloc/app/imu_error_keys.hpp"

namespace lcmloc::app::ins_config {

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

void parseLandmarkList(KeyReader& parent, const std::string& key, std::vector<MapLandmark>& out) {
  YAML::Node n = parent.child(key);
  if (!n) return;
  out.clear();
  if (n.IsNull()) return;
  const std::string kp = parent.keyPath(key);
  if (!n.IsSequence()) throw ConfigError(parent.file(), kp, "expected a list of {id, x, y}, got " + yaml_detail::nodeText(n));
  for (std::size_t i = 0; i < n.size(); ++i) {
    const std::string ip = kp + "[" + std::to_string(i) + "]";
    MapLandmark l;
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
  std::vector<MapLandmark> list;
  if (!fusion.child("landmarks")) return;  // absent: unchanged
  parseLandmarkList(fusion, "landmarks", list);
  landmarks.clear();
  for (const auto& l : list) landmarks.emplace(l.id, core::Vec2(l.x, l.y));
}

}  // namespace lcmloc::app::ins_config
