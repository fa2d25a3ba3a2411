#pragma once
// The filters the engine runs: the active one (its state is the output) and the shadows (same
// inputs, their states published beside it), the switch between types, and starting a filter
// afresh from its configuration.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "lcmloc/core/engine_events.hpp"
#include "lcmloc/core/filter.hpp"
#include "lcmloc/core/map_index.hpp"

namespace lcmloc::core {

class FilterBank {
 public:
  /// base: the initial active filter; shadow_types: shadow filters of base's parameters; every
  /// filter shares map. Throws std::invalid_argument when a config is invalid.
  FilterBank(FilterConfig base, std::vector<std::string> shadow_types, SharedMapIndex map,
             const EngineOutputs& out);
  /// The same over map, indexed here.
  FilterBank(FilterConfig base, std::vector<std::string> shadow_types, const MarkerMap& map,
             const EngineOutputs& out)
      : FilterBank(std::move(base), std::move(shadow_types), std::make_shared<const MapIndex>(map), out) {}

  Filter& active() { return *active_; }
  const Filter& active() const { return *active_; }
  const FilterConfig& activeConfig() const { return active_cfg_; }
  std::size_t shadowCount() const { return shadows_.size(); }

  /// f(filter, is_active) for the active filter, then each shadow in configuration order.
  template <typename F>
  void forEach(F&& f) {
    f(*active_, true);
    for (auto& s : shadows_) f(*s, false);
  }
  template <typename F>
  void forEach(F&& f) const {
    f(static_cast<const Filter&>(*active_), true);
    for (const auto& s : shadows_) f(static_cast<const Filter&>(*s), false);
  }

  /// Publishes f's state (EngineOutputs::on_state). A state that is not finite never leaves: the
  /// filter starts afresh from its configuration and says so (event "restarted").
  void emitState(Filter& f, bool is_active);
  /// Active states published so far (a state after odometry that was batched is out once this
  /// moved on).
  uint64_t activeStatesEmitted() const { return active_emitted_; }

  /// The configuration a running filter was made from.
  FilterConfig configOf(const Filter& f, bool is_active) const;
  /// Starts f again from its configured initial state (fc) at utime.
  void startFresh(Filter& f, const FilterConfig& fc, int64_t utime) const;
  /// Every filter from its configured initial state at utime (command "reset").
  void startAllFresh(int64_t utime);
  /// Applies a pose fix to f; a filter whose other states cannot be carried over (not finite)
  /// starts from its configured initial state first (event "restarted"), so a fix also repairs a
  /// broken filter. Returns whether f took the fix.
  bool applyFix(Filter& f, bool is_active, const PoseFix& fix);

  /// What switchTo() did: error set when the config is invalid (nothing changed); note set when
  /// the active state could not be carried over and the new filter started afresh.
  struct Switched { std::string error, previous, note; };
  /// A filter of config c becomes the active one, started from the active state at utime (or
  /// later, the active state's time).
  Switched switchTo(const FilterConfig& c, int64_t utime);

  /// Every filter from state (mapped where the states differ).
  void initialize(const FilterState& state);
  /// Every filter made afresh from its configuration, the active type kept (a new time base).
  void reset();

  /// "active NAME" or "shadow NAME": one key per running filter.
  static std::string key(const Filter& f, bool is_active) { return (is_active ? "active " : "shadow ") + f.name(); }

 private:
  FilterConfig base_;
  SharedMapIndex map_;
  const EngineOutputs& out_;
  FilterConfig active_cfg_;
  std::unique_ptr<Filter> active_;
  std::vector<std::unique_ptr<Filter>> shadows_;
  FilterState scratch_;  ///< reused for every published state
  uint64_t active_emitted_ = 0;
};

}  // namespace lcmloc::core
