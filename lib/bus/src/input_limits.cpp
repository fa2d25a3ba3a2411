#include "lcmloc/bus/input_limits.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

namespace lcmloc::bus {

std::string LimitCheck::checkFix(const std::string& channel, const core::GpsInput& g) {
  if (!g.has_fix || l_.max_speed <= 0 || l_.max_fix_jump_sigma <= 0) return "";
  const double sd = g.position_std > 0 ? g.position_std : l_.gps_std;
  const auto it = last_fix_.find(channel);
  if (it != last_fix_.end() && g.utime > it->second.utime) {
    const Fix& p = it->second;
    const double dt = static_cast<double>(g.utime - p.utime) * 1e-6;
    const double jump = std::hypot(g.x - p.x, g.y - p.y);
    const double bound = l_.max_speed * dt + l_.max_fix_jump_sigma * std::hypot(sd, p.std);
    if (jump > bound)
      return fmt::format("fix {:.4g} m from the previous one {:.4g} s before, beyond fusion.limits.max_speed {:.4g} "
                         "m/s and {:.4g} sigma of the two fixes ({:.4g} m)",
                         jump, dt, l_.max_speed, l_.max_fix_jump_sigma, bound);
  }
  if (it == last_fix_.end() || g.utime > it->second.utime) last_fix_[channel] = Fix{g.utime, g.x, g.y, sd};
  return "";
}

std::string LimitCheck::check(const core::EngineInput& in) {
  if (const auto* d = std::get_if<core::RulerDetection>(&in.payload)) {
    if (l_.max_lateral_offset > 0 && std::abs(d->lateral_offset) > l_.max_lateral_offset)
      return fmt::format("lateral offset {:.4g} m beyond the ruler's span ({:.4g} m)", d->lateral_offset,
                         l_.max_lateral_offset);
    return "";
  }
  if (const auto* g = std::get_if<core::GpsInput>(&in.payload)) return checkFix(in.channel, *g);
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
