// Drive encoder (scale error, slip noise, tick quantization) and steering encoder (bias, noise,
// quantization), emitting increments at rate_hz.
#include <cmath>
#include <stdexcept>

#include "lcmloc/core/vehicle_model.hpp"
#include "lcmloc/sim/world.hpp"
#include "lcmloc/sim/schedule.hpp"

namespace lcmloc::sim {

OdometrySensor::OdometrySensor(const OdometrySensorConfig& cfg, double wheelbase, uint64_t seed)
    : cfg_(cfg), wheelbase_(wheelbase), rng_(seed) {
  if (!(cfg_.rate_hz > 0.0)) throw std::invalid_argument("odometry.rate_hz: must be > 0");
  if (!(cfg_.tick_length > 0.0)) throw std::invalid_argument("odometry.tick_length: must be > 0");
}

std::optional<OdometrySample> OdometrySensor::sample(const TruthState& truth) {
  // A count of ticks an encoder can hold, exactly, as a double as well (2^53).
  constexpr double kMaxTicks = 9007199254740992.0;
  const auto period_us = static_cast<int64_t>(std::llround(1e6 / cfg_.rate_hz));
  if (!started_) {
    if (!std::isfinite(truth.distance)) return std::nullopt;
    started_ = true;
    next_utime_ = saturatingAdd(truth.utime, period_us);
    last_true_distance_ = truth.distance;
    return std::nullopt;
  }
  std::normal_distribution<double> normal(0.0, 1.0);
  const double ds_true = truth.distance - last_true_distance_;
  const double measured = measured_distance_ + ((1.0 + cfg_.scale_error) * ds_true +
                                                cfg_.slip_std * std::sqrt(std::abs(ds_true)) * normal(rng_));
  // Quantize the accumulated distance, not the increment: the error never accumulates.
  const double ticks_now = std::floor(measured / cfg_.tick_length);
  // A distance the encoder cannot count (not finite, or beyond 2^53 ticks: corrupt ground truth
  // that got this far) is no step of this encoder: the sample is skipped and the state kept, so
  // the next valid sample gives the right increment (converting it to int64 would be undefined
  // behaviour, and a NaN kept in the state would freeze the odometer for good).
  if (!(std::abs(ticks_now) <= kMaxTicks)) return std::nullopt;
  last_true_distance_ = truth.distance;
  measured_distance_ = measured;
  if (!scheduleDue(next_utime_, truth.utime, period_us)) return std::nullopt;

  const auto ticks = static_cast<int64_t>(ticks_now);
  OdometrySample out;
  out.ticks = ticks - ticks_total_;
  ticks_total_ = ticks;

  double steering = truth.steering + cfg_.steering_bias + cfg_.steering_std * normal(rng_);
  if (cfg_.steering_resolution > 0.0)
    steering = std::round(steering / cfg_.steering_resolution) * cfg_.steering_resolution;

  out.input.utime = truth.utime;
  out.input.delta_s = static_cast<double>(out.ticks) * cfg_.tick_length;
  out.input.steering = steering;
  out.input.has_steering = true;
  out.input.delta_theta = core::headingIncrement(out.input.delta_s, steering, wheelbase_);
  return out;
}

}  // namespace lcmloc::sim
