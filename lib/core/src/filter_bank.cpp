#include "lcmloc/core/filter_bank.hpp"

#include <algorithm>
#include <stdexcept>

namespace lcmloc::core {

FilterBank::FilterBank(FilterConfig base, std::vector<std::string> shadow_types, SharedMapIndex map,
                       const EngineOutputs& out)
    : base_(std::move(base)), map_(std::move(map)), out_(out), active_cfg_(base_) {
  active_ = makeFilterOver(active_cfg_, map_);
  for (const auto& type : shadow_types) {
    FilterConfig sc = base_;
    sc.type = type;
    shadows_.push_back(makeFilterOver(sc, map_));
  }
}

void FilterBank::emitState(Filter& f, bool is_active) {
  if (is_active) ++active_emitted_;
  if (!out_.on_state) return;
  f.stateInto(scratch_);
  if (!scratch_.x.allFinite() || !scratch_.P.allFinite()) {
    // Never on the bus: a filter whose numbers ran away starts over, and says so.
    startFresh(f, configOf(f, is_active), scratch_.utime);
    out_.event(EventKind::Restarted, scratch_.utime, events::Restarted{f.name(), {}, {}});
    f.stateInto(scratch_);
  }
  out_.on_state(f.name(), is_active, scratch_);
}

FilterConfig FilterBank::configOf(const Filter& f, bool is_active) const {
  if (is_active) return active_cfg_;
  FilterConfig sc = base_;
  sc.type = f.name();
  return sc;
}

void FilterBank::startFresh(Filter& f, const FilterConfig& fc, int64_t utime) const {
  auto n = makeFilterOver(fc, map_);
  FilterState s = n->state();
  s.utime = utime;
  f.initialize(s);
}

void FilterBank::startAllFresh(int64_t utime) {
  forEach([&](Filter& f, bool is_active) { startFresh(f, configOf(f, is_active), utime); });
}

bool FilterBank::applyFix(Filter& f, bool is_active, const PoseFix& fix) {
  try {
    return f.applyFix(fix);
  } catch (const std::exception& e) {
    startFresh(f, configOf(f, is_active), fix.utime);
    out_.event(EventKind::Restarted, fix.utime, events::Restarted{f.name(), e.what(), fix.source});
    return f.applyFix(fix);
  }
}

FilterBank::Switched FilterBank::switchTo(const FilterConfig& c, int64_t utime) {
  Switched r;
  std::unique_ptr<Filter> next;
  try {
    next = makeFilterOver(c, map_);
  } catch (const std::invalid_argument& e) {
    r.error = e.what();
    return r;
  }
  FilterState from = active_->state();
  from.utime = std::max(from.utime, utime);
  try {
    next->initialize(from);
  } catch (const std::exception& e) {  // a state that cannot be carried over (not finite)
    startFresh(*next, c, from.utime);
    r.note = e.what();
  }
  r.previous = active_->name();
  active_ = std::move(next);
  active_cfg_ = c;
  return r;
}

void FilterBank::initialize(const FilterState& state) {
  forEach([&](Filter& f, bool) { f.initialize(state); });
}

void FilterBank::reset() {
  active_ = makeFilterOver(active_cfg_, map_);
  for (auto& s : shadows_) {
    FilterConfig sc = base_;
    sc.type = s->name();
    s = makeFilterOver(sc, map_);
  }
}

}  // namespace lcmloc::core
