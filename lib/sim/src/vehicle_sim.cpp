// Car-like vehicle (eq. 1-2) following the reference path with pure pursuit and a lateral weave.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/vehicle_model.hpp"
#include "lcmloc/sim/world.hpp"

namespace lcmloc::sim {
namespace {
constexpr double kTwoPi = 6.283185307179586;
constexpr double kCreepSpeed = 0.02;  // [m/s] keeps the final approach finite
}  // namespace

VehicleSim::VehicleSim(const VehicleConfig& cfg, const Path& path, double stop_at_arc,
                       uint64_t seed)
    : cfg_(cfg), path_(&path), stop_at_arc_(stop_at_arc), rng_(seed) {
  if (!(cfg_.rate_hz > 0.0)) throw std::invalid_argument("vehicle.rate_hz: must be > 0");
  if (cfg_.substeps < 1) throw std::invalid_argument("vehicle.substeps: must be >= 1");
  if (!(cfg_.wheelbase > 0.0)) throw std::invalid_argument("vehicle.wheelbase: must be > 0");
  if (!(cfg_.accel > 0.0)) throw std::invalid_argument("vehicle.accel: must be > 0");
  const core::Pose p0 = path.poseAt(0.0);
  st_.utime = cfg_.start_utime;
  st_.x = p0.x();
  st_.y = p0.y();
  st_.heading = p0.z();
}

const TruthState& VehicleSim::state() const { return st_; }
bool VehicleSim::finished() const { return finished_; }

const TruthState& VehicleSim::step() {
  const double period = 1.0 / cfg_.rate_hz;
  const double dt = period / cfg_.substeps;
  st_.utime += static_cast<int64_t>(std::llround(1e6 / cfg_.rate_hz));
  for (int k = 0; k < cfg_.substeps && !finished_; ++k) {
    arc_hint_ = path_->project(st_.x, st_.y, arc_hint_);

    // Speed profile: accelerate, cruise, brake to stop at stop_at_arc.
    const double remaining = stop_at_arc_ - arc_hint_;
    if (remaining <= 0.0) {
      st_.speed = 0.0;
      finished_ = true;
      break;
    }
    const double v_brake = std::sqrt(2.0 * cfg_.accel * remaining);
    st_.speed = std::max(kCreepSpeed,
                         std::min({st_.speed + cfg_.accel * dt, cfg_.speed, v_brake}));

    // Pure pursuit toward the weaving look-ahead point.
    const double s_t = arc_hint_ + cfg_.lookahead;
    const core::Pose target = path_->poseAt(s_t);
    const double w = cfg_.weave_wavelength > 0.0
                         ? cfg_.weave_amplitude * std::sin(kTwoPi * s_t / cfg_.weave_wavelength)
                         : 0.0;
    const double tx = target.x() - w * std::sin(target.z()) - st_.x;
    const double ty = target.y() + w * std::cos(target.z()) - st_.y;
    const double ld = std::max(std::hypot(tx, ty), 1e-6);
    const double alpha = core::wrapAngle(std::atan2(ty, tx) - st_.heading);
    const double psi = std::atan(2.0 * cfg_.wheelbase * std::sin(alpha) / ld);
    st_.steering = std::clamp(psi, -cfg_.max_steering, cfg_.max_steering);

    const double ds = st_.speed * dt;
    const core::Pose next = core::propagatePose(core::Pose(st_.x, st_.y, st_.heading), ds,
                                                core::headingIncrement(ds, st_.steering, cfg_.wheelbase));
    st_.x = next.x();
    st_.y = next.y();
    st_.heading = next.z();
    st_.distance += ds;
  }
  return st_;
}

}  // namespace lcmloc::sim
