#pragma once
// The control pose: the canonical estimate (the active filter's state, fused on the delayed
// horizon of the reorder window) with the motion not yet released composed on top, so that a
// controller gets a pose of the newest odometry or IMU message the moment it arrives. The motion
// goes through the filters' own time update (Filter::predict for odometry, Filter::update for
// IMU samples of a filter that uses them) on a scratch filter of the active filter's type started
// from the canonical state: the same vehicle and INS models, their covariance grown the same way.
// The canonical estimate is not touched.
#include <cstdint>
#include <memory>
#include <vector>

#include "lcmloc/core/engine_input.hpp"
#include "lcmloc/core/filter.hpp"
#include "lcmloc/core/map_index.hpp"
#include "lcmloc/core/reorder.hpp"

namespace lcmloc::core {

class ControlPredictor {
 public:
  /// An input waiting in the reorder window, with its canonical key.
  struct Waiting {
    OrderKey key;
    const EngineInput* input;
  };
  explicit ControlPredictor(SharedMapIndex map) : map_(std::move(map)) {}
  /// The control pose over `active` (of configuration cfg) and the inputs waiting in the reorder
  /// window, in canonical order: each odometry input through predict, each IMU sample through
  /// update when the filter uses IMU; other inputs (measurements, commands) wait for the
  /// canonical estimate. Its utime is that of the last motion input applied, its status the
  /// canonical one. No motion waiting: the active filter's state, as it is. `version` names the
  /// canonical state: while it is the one of the call before and the motion composed then still
  /// leads the waiting motion, only the motion after it is composed (the same operations, so the
  /// same numbers, as composing all of it again). The result is valid until the next call.
  const FilterState& pose(const Filter& active, const FilterConfig& cfg, int64_t version,
                          const std::vector<Waiting>& waiting);
  /// Everything is composed afresh at the next pose(), the scratch filter made again from the
  /// configuration (a switch of filter or of its parameters, a reset, a new initial state).
  void invalidate() {
    scratch_.reset();
    applied_.clear();
  }

 private:
  SharedMapIndex map_;
  std::unique_ptr<Filter> scratch_;
  FilterState base_, out_;
  int64_t version_ = 0;             ///< the canonical state's the scratch filter started from
  std::vector<OrderKey> applied_;   ///< the motion composed on it, in order (empty: not started)
  std::vector<const Waiting*> motion_;  ///< pose()'s motion inputs (storage reused)
  int64_t utime_ = 0;
};

}  // namespace lcmloc::core
