#include "landmark_calibration.hpp"

#include <cmath>
#include <stdexcept>

#include <cstdio>

namespace lcmloc::core {

detail::CalibrationLayout detail::CalibrationLayout::of(const FilterConfig& c, const MarkerMap& map) {
  using BB = FilterConfig::Calibration::BeaconBias;
  const auto& k = c.calibration;
  CalibrationLayout l;
  l.names = {"x", "y", "theta"};
  std::vector<double> x0, p0;
  auto add = [&l, &x0, &p0](const std::string& name, double mean, double std0) {
    l.names.push_back(name);
    x0.push_back(mean);
    p0.push_back(std0 * std0);
    return l.size() - 1;
  };
  if (k.odo_scale) l.odo_scale = add("cal_odo_scale", k.odo_scale_mean, k.odo_scale_std);
  if (k.yaw_rate_scale) l.yaw_rate_scale = add("cal_yaw_rate_scale", k.yaw_rate_scale_mean, k.yaw_rate_scale_std);
  if (k.yaw_rate_bias) l.yaw_rate_bias = add("cal_yaw_rate_bias", k.yaw_rate_bias_mean, k.yaw_rate_bias_std);
  if (k.beacon_bias == BB::Shared) {
    l.bias0 = add("cal_beacon_bias", k.beacon_bias_mean, k.beacon_bias_std);
  } else if (k.beacon_bias == BB::PerBeacon) {
    if (map.size() > static_cast<std::size_t>(kMaxBeaconBiasStates))
      throw std::invalid_argument("filter config: calibration.beacon_bias per_beacon takes at most " +
                                  std::to_string(kMaxBeaconBiasStates) + " map entries (the map has " +
                                  std::to_string(map.size()) + "): use shared");
    for (const Marker& m : map) {
      const int i = add("cal_beacon_bias_" + std::to_string(m.id), k.beacon_bias_mean, k.beacon_bias_std);
      if (l.bias0 < 0) l.bias0 = i;
      l.bias_ids.push_back(m.id);
    }
  }
  l.x0 = Eigen::Map<const Eigen::VectorXd>(x0.data(), static_cast<Eigen::Index>(x0.size()));
  l.p0 = Eigen::Map<const Eigen::VectorXd>(p0.data(), static_cast<Eigen::Index>(p0.size()));
  return l;
}

int detail::CalibrationLayout::biasIndex(int beacon_id) const {
  if (bias0 < 0) return -1;
  if (bias_ids.empty()) return bias0;
  for (std::size_t i = 0; i < bias_ids.size(); ++i)
    if (bias_ids[i] == beacon_id) return bias0 + static_cast<int>(i);
  return -1;
}

void detail::CalibrationLayout::addProcessNoise(const FilterConfig::Calibration& c, double ds, double dtheta,
                                                double dt, Eigen::Ref<Eigen::VectorXd> q) const {
  if (odo_scale >= 0) q[odo_scale] += c.odo_scale_rw * c.odo_scale_rw * std::abs(ds);
  if (yaw_rate_scale >= 0) q[yaw_rate_scale] += c.yaw_rate_scale_rw * c.yaw_rate_scale_rw * std::abs(dtheta);
  if (yaw_rate_bias >= 0) q[yaw_rate_bias] += c.yaw_rate_bias_rw * c.yaw_rate_bias_rw * dt;
  for (int i = bias0; i >= 0 && i < size(); ++i) q[i] += c.beacon_bias_rw * c.beacon_bias_rw * dt;
}

std::vector<CalibrationValue> calibrationValues(const FilterState& s) {
  std::vector<CalibrationValue> v;
  const auto n = std::min<Eigen::Index>(s.x.size(), static_cast<Eigen::Index>(s.names.size()));
  for (Eigen::Index i = 3; i < n; ++i) {
    if (s.names[i].rfind("cal_", 0) != 0 || s.P.rows() <= i) continue;
    v.push_back({s.names[i].substr(4), s.x[i], std::sqrt(std::max(s.P(i, i), 0.0))});
  }
  return v;
}

std::string calibrationSummary(const FilterState& s) {
  std::string out;
  for (const auto& c : calibrationValues(s)) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "%s%s %.4g +- %.2g", out.empty() ? "calibration: " : ", ", c.name.c_str(), c.value,
                  c.sigma);
    out += buf;
  }
  return out;
}

}  // namespace lcmloc::core
