// Simulated IMU (noise, constant + drifting biases, declination, magnetic disturbance,
// saturation) and GPS receiver (uniform or Gaussian error, outages, jumps).
#include "lcmloc/sim/gnss_sensors.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "lcmloc/core/gnss_model.hpp"
#include "lcmloc/sim/world.hpp"
#include "lcmloc/sim/schedule.hpp"

namespace lcmloc::sim {
namespace {

core::Vec3 normal3(std::mt19937_64& rng, double sd) {
  std::normal_distribution<double> n(0.0, 1.0);
  const double a = n(rng), b = n(rng), c = n(rng);
  return core::Vec3(a, b, c) * sd;
}

core::Vec3 clip(const core::Vec3& v, double range) {
  return range > 0 ? core::Vec3(v.cwiseMax(-range).cwiseMin(range)) : v;
}

int64_t periodUs(double rate_hz) { return static_cast<int64_t>(std::llround(1e6 / rate_hz)); }

}  // namespace

ImuSensor::ImuSensor(const ImuSensorConfig& cfg, double wheelbase, uint64_t seed)
    : cfg_(cfg), wheelbase_(wheelbase), rng_(seed) {
  if (!(cfg_.rate_hz > 0.0)) throw std::invalid_argument("imu.rate_hz: must be > 0");
  if (!(wheelbase_ > 0.0)) throw std::invalid_argument("vehicle.wheelbase: must be > 0");
  accel_bias_ = normal3(rng_, cfg_.accel_bias);
  gyro_bias_ = normal3(rng_, cfg_.gyro_bias);
  mag_dist_ = normal3(rng_, cfg_.mag_disturbance_std);
}

ImuSample ImuSensor::ideal(const ImuSensorConfig& cfg, double wheelbase, double a, double v,
                           double psi, double theta) {
  ImuSample s;
  const double w = core::gnss::headingRate(v, psi, wheelbase);
  s.accel = core::Vec3(a, v * w, cfg.gravity);
  s.gyro = core::Vec3(0.0, 0.0, w);
  s.mag = core::gnss::earthFieldBody(theta, cfg.declination, cfg.mag_horizontal, cfg.mag_vertical);
  return s;
}

std::optional<ImuSample> ImuSensor::sample(const TruthState& truth) {
  const int64_t period = periodUs(cfg_.rate_hz);
  // A speed that is not finite (corrupt ground truth that got this far; drivers refuse it in
  // TruthDriver) would stay in last_speed_ and make every later sample NaN: skipped.
  if (!std::isfinite(truth.speed)) return std::nullopt;
  if (!started_) {
    started_ = true;
    next_utime_ = saturatingAdd(truth.utime, period);
    last_utime_ = truth.utime;
    last_speed_ = truth.speed;
    return std::nullopt;
  }
  const double dt = secondsBetween(truth.utime, last_utime_);
  if (!(dt > 0)) return std::nullopt;
  const double a = (truth.speed - last_speed_) / dt;
  last_utime_ = truth.utime;
  last_speed_ = truth.speed;
  // Biases drift and the disturbance evolves with every truth sample (first-order Markov).
  accel_bias_ += normal3(rng_, cfg_.accel_bias_rw * std::sqrt(dt));
  gyro_bias_ += normal3(rng_, cfg_.gyro_bias_rw * std::sqrt(dt));
  if (cfg_.mag_disturbance_std > 0) {
    const double phi = std::exp(-dt / cfg_.mag_disturbance_tau);
    mag_dist_ = phi * mag_dist_ +
                normal3(rng_, cfg_.mag_disturbance_std * std::sqrt(1.0 - phi * phi));
  }
  if (!scheduleDue(next_utime_, truth.utime, period)) return std::nullopt;
  ImuSample s = ideal(cfg_, wheelbase_, a, truth.speed, truth.steering, truth.heading);
  s.utime = truth.utime;
  s.accel = clip(s.accel + accel_bias_ + normal3(rng_, cfg_.accel_std), cfg_.accel_range);
  s.gyro = clip(s.gyro + gyro_bias_ + normal3(rng_, cfg_.gyro_std), cfg_.gyro_range);
  s.mag += mag_dist_ + normal3(rng_, cfg_.mag_std);
  return s;
}

GpsSensor::GpsSensor(const GpsSensorConfig& cfg, uint64_t seed) : cfg_(cfg), rng_(seed) {
  if (!(cfg_.rate_hz > 0.0)) throw std::invalid_argument("gps.rate_hz: must be > 0");
  if (cfg_.error_model != "uniform" && cfg_.error_model != "gaussian")
    throw std::invalid_argument("gps.error_model: must be uniform or gaussian");
  if (!(cfg_.error >= 0.0)) throw std::invalid_argument("gps.error: must be >= 0");
}

double GpsSensor::modelStd() const {
  return cfg_.error_model == "uniform" ? cfg_.error / std::sqrt(3.0) : cfg_.error;
}

std::optional<GpsFixSample> GpsSensor::sample(const TruthState& truth) {
  const int64_t period = periodUs(cfg_.rate_hz);
  if (!started_) {
    started_ = true;
    t0_ = truth.utime;
    next_utime_ = truth.utime;
  }
  if (!scheduleDue(next_utime_, truth.utime, period)) return std::nullopt;
  const double t = secondsBetween(truth.utime, t0_);
  GpsFixSample f;
  f.utime = truth.utime;
  f.hdop = cfg_.hdop;
  f.position_std = cfg_.reported_std > 0 ? cfg_.reported_std : modelStd();
  for (const auto& o : cfg_.outages)
    if (t >= o.start && t < o.start + o.duration) {
      f.has_fix = false;
      f.satellites = 0;
      f.position_std = 0.0;
      return f;
    }
  double ex, ey;
  if (cfg_.error_model == "uniform") {
    std::uniform_real_distribution<double> u(-cfg_.error, cfg_.error);
    ex = u(rng_);
    ey = u(rng_);
  } else {
    std::normal_distribution<double> n(0.0, cfg_.error);
    ex = n(rng_);
    ey = n(rng_);
  }
  f.x = truth.x + ex;
  f.y = truth.y + ey;
  for (const auto& j : cfg_.jumps)
    if (t >= j.at && t <= j.at + j.duration) {
      f.x += j.dx;
      f.y += j.dy;
    }
  f.satellites = cfg_.satellites;
  return f;
}

}  // namespace lcmloc::sim
