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

/// What an input carries: a command or a sensor's message (each alternative has an InputKind).
using InputPayload = std::variant<OdometryInput, RulerDetection, ControlCommand, ImuInput, GpsInput,
                                  LandmarkObservation, BeaconRange, BearingsInput>;

/// One input message, already converted and validated.
struct EngineInput {
  std::string channel;
  int64_t seq = 0;
  int64_t utime = 0;
  InputPayload payload;
};

/// The input an event is about.
inline InputRef refOf(const EngineInput& in) { return InputRef{in.channel, in.seq, in.utime}; }

/// The engine's descriptor of each kind of input (one specialization per alternative of
/// EngineInput::payload; adding a sensor adds its line here, its core type, its converter in the
/// bus and the filters that use it: docs/architecture.md, "Adding an input kind"):
/// - rank: the canonical tie-break at equal utime. A command first (it applies to what comes at
///   its time), then the odometry (a measurement sees the motion up to its time), then the
///   measurements. Inputs of one kind on different channels are ordered by a stable hash of the
///   channel name, then by seq (canonicalKey).
/// - measurement (a measurement a filter takes or not, Filter::uses): the kind the engine asks
///   each filter about; `what` names it in events (a NaN field: "beacon range").
/// A measurement kind with no special handling in the engine reaches every filter that uses it
/// through Filter::update(const T&) (FusionEngine's generic measurement path).
template <typename T>
struct InputKind;  // undefined: the static_assert below names a kind without a descriptor
template <> struct InputKind<ControlCommand> { static constexpr int rank = 0; };
template <> struct InputKind<OdometryInput> { static constexpr int rank = 1; };
template <> struct InputKind<RulerDetection> {
  static constexpr int rank = 2;
  static constexpr Measurement measurement = Measurement::Ruler;
  static constexpr const char* what = "ruler detection";
};
template <> struct InputKind<ImuInput> {
  static constexpr int rank = 3;
  static constexpr Measurement measurement = Measurement::Imu;
  static constexpr const char* what = "IMU sample";
};
template <> struct InputKind<GpsInput> {
  static constexpr int rank = 4;
  static constexpr Measurement measurement = Measurement::Gps;
  static constexpr const char* what = "GPS fix";
};
template <> struct InputKind<LandmarkObservation> {
  static constexpr int rank = 5;
  static constexpr Measurement measurement = Measurement::Landmark;
  static constexpr const char* what = "landmark observation";
};
template <> struct InputKind<BeaconRange> {
  static constexpr int rank = 6;
  static constexpr Measurement measurement = Measurement::Beacon;
  static constexpr const char* what = "beacon range";
};
template <> struct InputKind<BearingsInput> { static constexpr int rank = 7; };

/// The canonical rank of a kind of input (InputKind<T>::rank).
template <typename T>
inline constexpr int kCanonicalRank = InputKind<T>::rank;

namespace detail {
template <typename Variant>
struct EveryInputRanked;
template <typename... T>
struct EveryInputRanked<std::variant<T...>> {
  static constexpr bool value = ((kCanonicalRank<T> >= 0) && ...);
};
/// Whether T is a measurement kind (its InputKind names a Measurement).
template <typename T, typename = void>
struct IsMeasurement : std::false_type {};
template <typename T>
struct IsMeasurement<T, std::void_t<decltype(InputKind<T>::measurement)>> : std::true_type {};
}  // namespace detail
static_assert(detail::IsMeasurement<GpsInput>::value && !detail::IsMeasurement<OdometryInput>::value);
static_assert(detail::EveryInputRanked<InputPayload>::value,
              "every kind of EngineInput needs an InputKind with a rank");

/// The canonical rank of in's kind (InputKind<T>::rank).
inline int canonicalRank(const EngineInput& in) {
  return std::visit([](const auto& p) { return kCanonicalRank<std::decay_t<decltype(p)>>; }, in.payload);
}

}  // namespace lcmloc::core
