// Simulated electro-optical bearings to known landmarks (seeds/004 §III).
#include "lcmloc/sim/vision_sensor.hpp"

#include <cmath>
#include <set>
#include <stdexcept>
#include <string>

#include "lcmloc/core/angles.hpp"
#include "lcmloc/sim/world.hpp"
#include "lcmloc/sim/schedule.hpp"

namespace lcmloc::sim {

void validateLandmarks(const std::vector<Landmark>& landmarks) {
  std::set<int> seen;
  for (std::size_t i = 0; i < landmarks.size(); ++i) {
    const auto& l = landmarks[i];
    const std::string where = "landmarks[" + std::to_string(i) + "]";
    if (!std::isfinite(l.x) || !std::isfinite(l.y))
      throw std::invalid_argument(where + ": position of landmark " + std::to_string(l.id) + " is not finite");
    if (!seen.insert(l.id).second)
      throw std::invalid_argument(where + ": duplicate landmark id " + std::to_string(l.id));
  }
}

std::map<int, Eigen::Vector2d> landmarkMap(const std::vector<Landmark>& landmarks) {
  validateLandmarks(landmarks);
  std::map<int, Eigen::Vector2d> m;
  for (const auto& l : landmarks) m[l.id] = Eigen::Vector2d(l.x, l.y);
  return m;
}

std::vector<core::landmark::Bearing> toFixBearings(const VisionSample& s) {
  std::vector<core::landmark::Bearing> b;
  for (std::size_t i = 0; i < s.ids.size() && i < s.bearings.size(); ++i)
    b.push_back({s.ids[i], core::wrapAngle(-s.bearings[i])});
  return b;
}

double toFixHeading(double heading) { return core::wrapAngle(0.5 * M_PI - heading); }

VisionSensor::VisionSensor(const VisionSensorConfig& cfg, std::vector<Landmark> landmarks, uint64_t seed)
    : cfg_(cfg), landmarks_(std::move(landmarks)), rng_(seed) {
  if (!(cfg_.rate_hz > 0.0) || !std::isfinite(cfg_.rate_hz)) throw std::invalid_argument("vision.rate_hz: must be > 0");
  if (!(cfg_.bearing_std >= 0.0) || !std::isfinite(cfg_.bearing_std))
    throw std::invalid_argument("vision.bearing_std: must be >= 0");
  if (!(cfg_.resolution >= 0.0) || !(cfg_.resolution < 1.0))
    throw std::invalid_argument("vision.resolution: must be in [0, 1) rad");
  if (!(cfg_.max_range >= 0.0) || !std::isfinite(cfg_.max_range))
    throw std::invalid_argument("vision.max_range: must be >= 0");
  validateLandmarks(landmarks_);
}

double VisionSensor::trueBearing(double x, double y, double heading, double lx, double ly) {
  return core::wrapAngle(std::atan2(ly - y, lx - x) - heading);
}

double VisionSensor::quantize(double a, double step) {
  if (!(step > 0.0)) return core::wrapAngle(a);
  return core::wrapAngle(step * std::round(a / step));
}

double VisionSensor::effectiveStd(const VisionSensorConfig& cfg) {
  return std::sqrt(cfg.bearing_std * cfg.bearing_std + cfg.resolution * cfg.resolution / 12.0);
}

VisionSample VisionSensor::observe(double x, double y, double heading, int64_t utime) {
  VisionSample s;
  s.utime = utime;
  s.bearing_std = effectiveStd(cfg_);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (const auto& l : landmarks_) {
    if (cfg_.max_range > 0.0 && std::hypot(l.x - x, l.y - y) > cfg_.max_range) continue;
    // One draw per landmark in view, in map order: the sequence depends only on the seed and
    // on which landmarks are seen.
    const double n = noise(rng_) * cfg_.bearing_std;
    s.ids.push_back(l.id);
    s.bearings.push_back(quantize(trueBearing(x, y, heading, l.x, l.y) + n, cfg_.resolution));
  }
  return s;
}

std::optional<VisionSample> VisionSensor::sample(const TruthState& truth) {
  if (!std::isfinite(truth.x) || !std::isfinite(truth.y) || !std::isfinite(truth.heading)) return std::nullopt;
  const int64_t period = static_cast<int64_t>(std::llround(1e6 / cfg_.rate_hz));
  if (!started_) {
    started_ = true;
    next_utime_ = truth.utime;
  }
  if (!scheduleDue(next_utime_, truth.utime, period)) return std::nullopt;
  return observe(truth.x, truth.y, truth.heading, truth.utime);
}

}  // namespace lcmloc::sim
