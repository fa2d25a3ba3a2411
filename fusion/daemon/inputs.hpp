#pragma once
// The sensor inputs the fusion daemon takes: one descriptor per kind. Adding a sensor adds its
// line here; with its lcm type (lcmtypes/, lib/logio's type registry), its core type and
// InputKind (lib/core: canonical rank, the measurement kind filters are asked about), its
// converter (bus::toInput, lib/bus), its channel key (app::ChannelConfig) and the filters
// that use it, that is all (docs/architecture.md, "Adding an input kind").
#include <string>
#include <tuple>
#include <type_traits>
#include <variant>
#include <vector>

#include "lcmloc/app/config.hpp"
#include "lcmloc/beacon_range_t.hpp"
#include "lcmloc/core/engine_input.hpp"
#include "lcmloc/gps_fix_t.hpp"
#include "lcmloc/imu_t.hpp"
#include "lcmloc/landmark_bearings_t.hpp"
#include "lcmloc/landmark_obs_t.hpp"
#include "lcmloc/magruler_t.hpp"
#include "lcmloc/odometry_t.hpp"

namespace lcmloc::fusion {

/// A sensor input kind: messages of type Lcm on the channels `channels` gives, each converted by
/// bus::toInput(const Lcm&, ...) into a Core for the engine, its seq tracked per channel.
template <typename Lcm, typename Core>
struct SensorInput {
  using lcm_type = Lcm;
  using core_type = Core;
  const char* name;  ///< the channels key (channels.<name> in the system file)
  std::vector<std::string> (*channels)(const app::ChannelConfig&);
};

namespace detail {
template <typename Lcm, typename Core, std::string app::ChannelConfig::*channel>
SensorInput<Lcm, Core> one(const char* name) {
  return {name, [](const app::ChannelConfig& c) { return std::vector<std::string>{c.*channel}; }};
}
}  // namespace detail

/// Every sensor input kind, in the order the daemon subscribes to them (FUSION_CONTROL, a
/// command rather than a sensor, is the daemon's own).
inline const auto kSensorInputs = std::make_tuple(
    detail::one<lcmloc::odometry_t, core::OdometryInput, &app::ChannelConfig::odometry>("odometry"),
    SensorInput<lcmloc::magruler_t, core::RulerDetection>{
        "magruler", [](const app::ChannelConfig& c) { return c.magruler; }},
    detail::one<lcmloc::imu_t, core::ImuInput, &app::ChannelConfig::imu>("imu"),
    detail::one<lcmloc::gps_fix_t, core::GpsInput, &app::ChannelConfig::gps>("gps"),
    detail::one<lcmloc::landmark_obs_t, core::LandmarkObservation, &app::ChannelConfig::landmarks>("landmarks"),
    detail::one<lcmloc::beacon_range_t, core::BeaconRange, &app::ChannelConfig::beacons>("beacons"),
    detail::one<lcmloc::landmark_bearings_t, core::BearingsInput, &app::ChannelConfig::vision>("vision"));

/// Calls f(descriptor) for each sensor input kind.
template <typename F>
void forEachSensorInput(F&& f) {
  std::apply([&](const auto&... d) { (f(d), ...); }, kSensorInputs);
}

namespace detail {
template <typename T, typename Tuple>
struct HasCore;
template <typename T, typename... D>
struct HasCore<T, std::tuple<D...>> {
  static constexpr bool value = (std::is_same_v<T, typename D::core_type> || ...);
};
template <typename Payload>
struct EverySensorDescribed;
template <typename... T>
struct EverySensorDescribed<std::variant<T...>> {
  static constexpr bool value =
      ((std::is_same_v<T, core::ControlCommand> ||
        HasCore<T, std::remove_const_t<decltype(kSensorInputs)>>::value) && ...);
};
}  // namespace detail
static_assert(detail::EverySensorDescribed<core::InputPayload>::value,
              "every kind of engine input but the command needs a SensorInput in kSensorInputs");

}  // namespace lcmloc::fusion
