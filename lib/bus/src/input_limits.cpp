#include "lcmloc/bus/input_limits.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

namespace lcmloc::bus {

std::string LimitCheck::check(const core::EngineInput& in) {
  const auto* o = std::get_if<core::OdometryInput>(&in.payload);
  if (!o) return "";
  if (l_.max_steering > 0 && o->has_steering && std::abs(o->steering) > l_.max_steering)
    return fmt::format("steering angle {:.4g} rad beyond fusion.limits.max_steering {:.4g}", o->steering, l_.max_steering);
  auto [it, first] = last_utime_.try_emplace(in.channel, in.utime);
  if (!first) {
    // The interval since the previous increment taken (at least min_interval; an input out of
    // order has none of its own: min_interval too).
    const double dt = std::max(static_cast<double>(in.utime - it->second) * 1e-6, l_.min_interval);
    const double speed = std::abs(o->delta_s) / dt;
    if (l_.max_speed > 0 && speed > l_.max_speed)
      return fmt::format("increment {:.4g} m over {:.4g} s is {:.4g} m/s, beyond fusion.limits.max_speed {:.4g}",
                         o->delta_s, dt, speed, l_.max_speed);
    const double yaw = std::abs(o->delta_theta) / dt;
    if (l_.max_yaw_rate > 0 && !o->has_steering && yaw > l_.max_yaw_rate)
      return fmt::format("heading increment {:.4g} rad over {:.4g} s is {:.4g} rad/s, beyond fusion.limits.max_yaw_rate {:.4g}",
                         o->delta_theta, dt, yaw, l_.max_yaw_rate);
  }
  it->second = std::max(it->second, in.utime);
  return "";
}

}  // namespace lcmloc::bus
