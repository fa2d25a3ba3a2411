#include "lcmloc/core/control_pose.hpp"

#include <algorithm>

namespace lcmloc::core {
namespace {

bool same(const OrderKey& a, const OrderKey& b) { return a.utime == b.utime && a.rank == b.rank && a.seq == b.seq; }

}  // namespace

const FilterState& ControlPredictor::pose(const Filter& active, const FilterConfig& cfg, int64_t version,
                                          const std::vector<Waiting>& waiting) {
  const bool imu = active.uses(Measurement::Imu);
  motion_.clear();
  for (const Waiting& w : waiting) {
    const auto* odo = std::get_if<OdometryInput>(&w.input->payload);
    const auto* sample = std::get_if<ImuInput>(&w.input->payload);
    if (odo ? odo->finite() : (imu && sample && sample->finite())) motion_.push_back(&w);
  }
  if (motion_.empty()) {
    applied_.clear();
    active.stateInto(out_);
    return out_;
  }
  // Go on from what was composed before while the canonical state and the motion before are the
  // same; compose afresh otherwise.
  bool goes_on = !applied_.empty() && version == version_ && scratch_ && scratch_->name() == active.name() &&
                 applied_.size() <= motion_.size();
  for (std::size_t k = 0; goes_on && k < applied_.size(); ++k) goes_on = same(applied_[k], motion_[k]->key);
  if (!goes_on) {
    if (!scratch_ || scratch_->name() != active.name()) scratch_ = makeFilterOver(cfg, map_);
    active.stateInto(base_);
    scratch_->initialize(base_);
    applied_.clear();
    version_ = version;
    utime_ = base_.utime;
  }
  for (std::size_t k = applied_.size(); k < motion_.size(); ++k) {
    const EngineInput& in = *motion_[k]->input;
    if (const auto* odo = std::get_if<OdometryInput>(&in.payload))
      scratch_->predict(*odo);
    else
      scratch_->update(std::get<ImuInput>(in.payload));
    applied_.push_back(motion_[k]->key);
    utime_ = std::max(utime_, in.utime);
  }
  scratch_->stateInto(out_);
  out_.utime = utime_;
  out_.status = base_.status;
  return out_;
}

}  // namespace lcmloc::core
