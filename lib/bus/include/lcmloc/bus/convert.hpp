#pragma once
// The one place where lcmtypes and core structs meet.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "lcmloc/bus/geodesy.hpp"
#include "lcmloc/core/engine_input.hpp"
#include "lcmloc/core/types.hpp"
#include "lcmloc/fault_event_t.hpp"
#include "lcmloc/gate_decision_t.hpp"
#include "lcmloc/gps_fix_t.hpp"
#include "lcmloc/imu_t.hpp"
#include "lcmloc/landmark_obs_t.hpp"
#include "lcmloc/beacon_range_t.hpp"
#include "lcmloc/landmark_bearings_t.hpp"
#include "lcmloc/magruler_t.hpp"
#include "lcmloc/odometry_t.hpp"
#include "lcmloc/pose_t.hpp"

namespace lcmloc::bus {

/// Returns nullopt and sets why when a field is NaN/Inf or out of range.
std::optional<core::OdometryInput> toCore(const lcmloc::odometry_t& m, std::string* why = nullptr);
/// The same into `out` (every field set when it returns true; left partly set when false): the
/// daemon's intake converts straight into the item it hands on, with no copy in between.
bool toCore(const lcmloc::odometry_t& m, core::OdometryInput& out, std::string* why = nullptr);
/// Only detections (detected == true) convert; a non-detection returns nullopt with why = "".
std::optional<core::RulerDetection> toCore(const lcmloc::magruler_t& m, const std::string& channel,
                                           std::string* why = nullptr);
/// IMU sample; nullopt (why set) when a field is NaN/Inf or utime is negative.
std::optional<core::ImuInput> toCore(const lcmloc::imu_t& m, const std::string& channel,
                                     std::string* why = nullptr);
/// GPS fix -> local frame. A fix with fix_type < 2 converts with has_fix = false (the filters
/// report it as "no_fix"); a fix with NaN/Inf or out-of-range lat/lon returns nullopt.
std::optional<core::GpsInput> toCore(const lcmloc::gps_fix_t& m, const std::string& channel,
                                     const LocalFrame& frame, std::string* why = nullptr);

lcmloc::pose_t toLcm(const core::FilterState& s, const std::string& filter, int64_t seq);
lcmloc::gate_decision_t toLcm(const core::GateDecision& d, const std::string& filter, int64_t seq);
/// The bytes pose_t::encode gives for toLcm(s, filter, seq) (hash first; the tests compare the
/// two byte for byte), written straight from the state into out, which grows as needed. Returns
/// the encoded size. The daemon's per-state path: building the pose_t (a vector per covariance
/// row, a string per state name) and lcm-gen's field-by-field encode took about 1,300
/// instructions per 3-state pose, this takes under 500 (callgrind, lcmloc-replay --bench).
std::size_t encodePose(const core::FilterState& s, const std::string& filter, int64_t seq,
                       std::vector<uint8_t>& out);
core::FilterState toCore(const lcmloc::pose_t& m);
/// Landmark observation; nullopt (why set) when a field is NaN/Inf, the range or a std is
/// negative, the bearing is outside [-pi, pi] or the id is below -1.
std::optional<core::LandmarkObservation> toCore(const lcmloc::landmark_obs_t& m, const std::string& channel,
                                                std::string* why = nullptr);
/// Beacon range; nullopt (why set) when a field is NaN/Inf or the range or std is negative.
std::optional<core::BeaconRange> toCore(const lcmloc::beacon_range_t& m, const std::string& channel,
                                        std::string* why = nullptr);
/// Landmark bearings (VISION); nullopt (why set) when utime is negative, the count does not
/// match the arrays or a bearing is NaN/Inf. Unknown ids are the engine's to refuse.
std::optional<core::BearingsInput> toCore(const lcmloc::landmark_bearings_t& m, const std::string& channel,
                                          std::string* why = nullptr);

/// What a sensor message is for the fusion (toInput): an input for the engine, nothing (a
/// message that carries nothing for the filters: a ruler reading without a detection), or refused
/// (why says what is wrong with it).
enum class Converted { Input, Nothing, Refused };
/// What a conversion may need besides the message: its channel (the sensor name a gate decision
/// carries) and the local frame GPS fixes are converted into.
struct InputContext {
  const std::string& channel;
  const LocalFrame& frame;
};
/// The converter of each sensor input kind, one overload per lcm type, with one signature: the
/// fusion daemon's intake calls it for every kind alike (fusion/daemon/inputs.hpp). The
/// conversion goes into out (whatever it held: an odometry increment is converted in place when
/// out holds one already, with no copy in between); why is set when refused.
Converted toInput(const lcmloc::odometry_t& m, const InputContext& ctx, core::InputPayload& out, std::string& why);
Converted toInput(const lcmloc::magruler_t& m, const InputContext& ctx, core::InputPayload& out, std::string& why);
Converted toInput(const lcmloc::imu_t& m, const InputContext& ctx, core::InputPayload& out, std::string& why);
Converted toInput(const lcmloc::gps_fix_t& m, const InputContext& ctx, core::InputPayload& out, std::string& why);
Converted toInput(const lcmloc::landmark_obs_t& m, const InputContext& ctx, core::InputPayload& out, std::string& why);
Converted toInput(const lcmloc::beacon_range_t& m, const InputContext& ctx, core::InputPayload& out, std::string& why);
Converted toInput(const lcmloc::landmark_bearings_t& m, const InputContext& ctx, core::InputPayload& out,
                  std::string& why);

}  // namespace lcmloc::bus
