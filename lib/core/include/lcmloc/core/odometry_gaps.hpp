#pragma once
// Odometry gaps (EngineConfig::odometry_gap, docs/odometry_gap.md): per odometry channel, the last
// input and its recent increments; a gap found between two inputs of a channel (or between the
// state initialize() gave and the first odometry after it) is bridged by every filter before the
// increment after it, and said (event "odometry_gap").
#include <array>
#include <climits>
#include <cstdint>
#include <map>
#include <optional>
#include <string>

#include "lcmloc/core/engine_config.hpp"
#include "lcmloc/core/engine_events.hpp"
#include "lcmloc/core/engine_input.hpp"
#include "lcmloc/core/filter_bank.hpp"
#include "lcmloc/core/output_decimation.hpp"

namespace lcmloc::core {

class OdometryGaps {
 public:
  /// Throws std::invalid_argument on a negative or non-finite setting.
  OdometryGaps(const OdometryGapConfig& cfg, FilterBank& bank, OutputDecimation& decimation,
               const EngineOutputs& out);

  /// An odometry input (in, its increment odo), before the filters take it: a gap before it is
  /// found (detect()) and bridged by every filter.
  void odometry(const EngineInput& in, const OdometryInput& odo);
  /// The gap before (in, odo), if any, with what the tracks learnt from it: detection without the
  /// bridge. GapBridged::bridged is empty.
  std::optional<events::GapBridged> detect(const EngineInput& in, const OdometryInput& odo);

  /// A measurement at utime has no odometry to place it: the newest odometry input is older by
  /// more than max_odometry_gap and twice its channel's period (a slow sender is not missing).
  bool odometryMissing(int64_t utime) const;
  /// The newest odometry input's utime (INT64_MIN: none since the start or the last reset).
  int64_t lastOdometryUtime() const { return last_odometry_utime_; }
  /// A gap was bridged and no measurement was accepted since (accepted() ends it).
  bool afterGap() const { return after_gap_; }
  /// [m] 3 sigma of the active filter's position after the last bridged gap (the larger axis).
  double spread() const { return spread_; }
  /// The active filter accepted a measurement.
  void accepted() { after_gap_ = false; }

  /// The filters started from a state at utime (FusionEngine::initialize): every channel starts
  /// over, and the first odometry input more than max_odometry_gap after utime is a resume gap.
  void resumeFrom(int64_t utime);
  /// Every channel and gap forgotten (a new time base).
  void reset();

 private:
  struct Track {
    int64_t utime = 0, seq = 0;
    static constexpr int kRecent = 10;
    std::array<double, kRecent> dt{}, ds{}, dth{}, steer{};
    int n = 0, next = 0;
    /// [us] The recent period (0: not known).
    int64_t period() const;
  };
  events::GapBridged gapAfter(const EngineInput& in, const OdometryInput& odo, Track& t, int64_t prev_utime,
                              int64_t prev_seq) const;
  std::optional<events::GapBridged> resumeGap(const EngineInput& in, const OdometryInput& odo);
  void bridge(events::GapBridged&& gap);

  OdometryGapConfig cfg_;
  FilterBank& bank_;
  OutputDecimation& decimation_;
  const EngineOutputs& out_;
  std::map<std::string, Track> tracks_;  ///< (nodes stay put: newest_track_)
  int64_t last_odometry_utime_ = INT64_MIN;  ///< newest odometry input on any channel
  const Track* newest_track_ = nullptr;      ///< the channel of that input
  int64_t resume_from_ = INT64_MIN;  ///< the state's time after initialize(), until the first odometry
  bool after_gap_ = false;
  double spread_ = 0.0;
};

}  // namespace lcmloc::core
