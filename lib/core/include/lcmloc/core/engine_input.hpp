#pragma once
// What the fusion engine takes: one input message, already converted and validated, and the
// canonical rank of each kind of input at equal message time.
#include <cstdint>
#include <string>
#include <type_traits>
#include <variant>

#include "lcmloc/core/engine_events.hpp"
#include "lcmloc/core/filter.hpp"

namespace lcmloc::core {

/// Control commands (fusion_control_t).
struct SwitchFilter { FilterConfig config; };           ///< switch active filter (type + params)
struct ResetFilter {};                                   ///< back to the configured initial state
struct SetPose { Pose pose; Vec3 stddev; };              ///< re-initialise x, y, theta
using ControlCommand = std::variant<SwitchFilter, ResetFilter, SetPose>;

/// One input message, already converted and validated.
struct EngineInput {
  std::string channel;
  int64_t seq = 0;
  int64_t utime = 0;
  std::variant<OdometryInput, RulerDetection, ControlCommand, ImuInput, GpsInput, LandmarkObservation, BeaconRange,
               BearingsInput>
      payload;
};

/// The input an event is about.
inline InputRef refOf(const EngineInput& in) { return InputRef{in.channel, in.seq, in.utime}; }

/// The canonical tie-break at equal utime, a property of each kind of input: a command first
/// (it applies to what comes at its time), then the odometry (a measurement sees the motion up
/// to its time), then the measurements. Inputs of one kind on different channels are ordered by
/// a stable hash of the channel name, then by seq (canonicalKey).
template <typename T>
inline constexpr int kCanonicalRank = -1;
template <> inline constexpr int kCanonicalRank<ControlCommand> = 0;
template <> inline constexpr int kCanonicalRank<OdometryInput> = 1;
template <> inline constexpr int kCanonicalRank<RulerDetection> = 2;
template <> inline constexpr int kCanonicalRank<ImuInput> = 3;
template <> inline constexpr int kCanonicalRank<GpsInput> = 4;
template <> inline constexpr int kCanonicalRank<LandmarkObservation> = 5;
template <> inline constexpr int kCanonicalRank<BeaconRange> = 6;
template <> inline constexpr int kCanonicalRank<BearingsInput> = 7;

namespace detail {
template <typename Variant>
struct EveryInputRanked;
template <typename... T>
struct EveryInputRanked<std::variant<T...>> {
  static constexpr bool value = ((kCanonicalRank<T> >= 0) && ...);
};
}  // namespace detail
static_assert(detail::EveryInputRanked<decltype(EngineInput::payload)>::value,
              "every kind of EngineInput needs a kCanonicalRank");

/// The canonical rank of in's kind (kCanonicalRank).
inline int canonicalRank(const EngineInput& in) {
  return std::visit([](const auto& p) { return kCanonicalRank<std::decay_t<decltype(p)>>; }, in.payload);
}

}  // namespace lcmloc::core
