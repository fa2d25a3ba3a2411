#include "lcmloc/core/control_pose.hpp"

#include <algorithm>

namespace lcmloc::core {

const FilterState& ControlPredictor::pose(const Filter& active, const FilterConfig& cfg,
                                          const std::vector<const EngineInput*>& waiting) {
  active.stateInto(out_);
  bool started = false;
  int64_t utime = out_.utime;
  const FilterStatus status = out_.status;
  for (const EngineInput* in : waiting) {
    const auto* odo = std::get_if<OdometryInput>(&in->payload);
    const auto* imu = std::get_if<ImuInput>(&in->payload);
    if (odo ? !odo->finite() : !(imu && imu->finite() && active.uses(Measurement::Imu))) continue;
    if (!started) {
      if (!scratch_ || scratch_->name() != active.name()) scratch_ = makeFilterOver(cfg, map_);
      scratch_->initialize(out_);
      started = true;
    }
    if (odo)
      scratch_->predict(*odo);
    else
      scratch_->update(*imu);
    utime = std::max(utime, in->utime);
  }
  if (!started) return out_;
  scratch_->stateInto(out_);
  out_.utime = utime;
  out_.status = status;
  return out_;
}

}  // namespace lcmloc::core
