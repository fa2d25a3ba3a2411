#pragma once
// Output decimation (EngineConfig::output_every): a state after every N-th odometry message; the
// odometry in between is composed and applied with one time update by the filters that can
// (Filter::accumulate), always before the next measurement or command.
#include <cstdint>

#include "lcmloc/core/filter_bank.hpp"

namespace lcmloc::core {

class OutputDecimation {
 public:
  OutputDecimation(int every, FilterBank& bank) : every_(every), bank_(bank) {}

  /// output_every > 1: odometry goes through odometry(), and applyAccumulated() comes first
  /// for anything else.
  bool batching() const { return every_ > 1; }
  /// An odometry increment for every filter (composed where the filter can); every N-th, the
  /// state of every filter is published.
  void odometry(const OdometryInput& odo);
  /// Applies what the filters composed (before a measurement, a command, a gap bridge).
  void applyAccumulated();
  /// Odometry was processed whose active state was not published since.
  bool unpublished() const { return unpublished_ && bank_.activeStatesEmitted() == emitted_at_; }
  /// Applies what was composed and publishes every filter's state.
  void publishAll();
  /// publishAll() when unpublished() (the end of input, or of a time base).
  void publishPending() {
    if (unpublished()) publishAll();
  }
  /// Nothing composed, counted or pending (the filters, made afresh, hold nothing either).
  void reset() {
    since_output_ = 0;
    accumulated_ = unpublished_ = false;
  }

 private:
  int every_;
  FilterBank& bank_;
  int since_output_ = 0;     ///< odometry messages since the last regular output
  bool accumulated_ = false;  ///< some filter holds composed odometry not yet applied
  bool unpublished_ = false;  ///< odometry processed since emitted_at_ active states
  uint64_t emitted_at_ = 0;
};

inline void OutputDecimation::odometry(const OdometryInput& odo) {
  bank_.forEach([&](Filter& f, bool) {
    if (f.accumulate(odo))
      accumulated_ = true;
    else
      f.predict(odo);
  });
  unpublished_ = true;
  emitted_at_ = bank_.activeStatesEmitted();
  if (++since_output_ < every_) return;
  since_output_ = 0;
  publishAll();
}

inline void OutputDecimation::applyAccumulated() {
  if (!accumulated_) return;
  bank_.forEach([](Filter& f, bool) { f.applyAccumulated(); });
  accumulated_ = false;
}

inline void OutputDecimation::publishAll() {
  applyAccumulated();
  bank_.forEach([&](Filter& f, bool is_active) { bank_.emitState(f, is_active); });
  unpublished_ = false;
}

}  // namespace lcmloc::core
