#pragma once
// The control pose: the canonical estimate (the active filter's state, fused on the delayed
// horizon of the reorder window) with the motion not yet released composed on top, so that a
// controller gets a pose of the newest odometry or IMU message the moment it arrives. The motion
// goes through the filters' own time update (Filter::predict for odometry, Filter::update for
// IMU samples of a filter that uses them) on a scratch filter of the active filter's type started
// from the canonical state: the same vehicle and INS models, their covariance grown the same way.
// The canonical estimate is not touched.
#include <memory>
#include <vector>

#include "lcmloc/core/engine_input.hpp"
#include "lcmloc/core/filter.hpp"
#include "lcmloc/core/map_index.hpp"

namespace lcmloc::core {

class ControlPredictor {
 public:
  explicit ControlPredictor(SharedMapIndex map) : map_(std::move(map)) {}
  /// The control pose over `active` (of configuration cfg) and the inputs waiting in the reorder
  /// window, in canonical order: each odometry input through predict, each IMU sample through
  /// update when the filter uses IMU; other inputs (measurements, commands) wait for the
  /// canonical estimate. Its utime is that of the last motion input applied, its status the
  /// canonical one. No motion waiting: the active filter's state, as it is. The result is valid
  /// until the next call.
  const FilterState& pose(const Filter& active, const FilterConfig& cfg, const std::vector<const EngineInput*>& waiting);
  /// The scratch filter is made afresh from the configuration at the next pose() (a switch of
  /// filter or of its parameters, a reset).
  void invalidate() { scratch_.reset(); }

 private:
  SharedMapIndex map_;
  std::unique_ptr<Filter> scratch_;
  FilterState out_;
};

}  // namespace lcmloc::core
