#pragma once
// Conversions between the simulator's samples (lcmloc::models) and lcmtypes: what the simulated
// drivers publish, and the ground truth the evaluation reads back. The core's conversions are in
// lcmloc/bus/convert.hpp.
#include <cstdint>

#include "lcmloc/bus/convert.hpp"
#include "lcmloc/bus/geodesy.hpp"
#include "lcmloc/ground_truth_t.hpp"
#include "lcmloc/sim/gnss_sensors.hpp"
#include "lcmloc/sim/vision_sensor.hpp"
#include "lcmloc/sim/world.hpp"

namespace lcmloc::drivers {

sim::TruthState toCore(const lcmloc::ground_truth_t& m);
lcmloc::ground_truth_t toLcm(const sim::TruthState& s, int64_t seq);
lcmloc::odometry_t toLcm(const sim::OdometrySample& s, int64_t seq);
lcmloc::magruler_t toLcm(const sim::RulerReading& r, int64_t seq);
lcmloc::imu_t toLcm(const sim::ImuSample& s, int64_t seq);
/// Local fix -> gps_fix_t (lat/lon about the frame's datum, altitude = datum altitude).
lcmloc::gps_fix_t toLcm(const sim::GpsFixSample& f, const bus::LocalFrame& frame, int64_t seq);
/// Bearings to landmarks -> landmark_bearings_t (channel VISION).
lcmloc::landmark_bearings_t toLcm(const sim::VisionSample& s, int64_t seq);

}  // namespace lcmloc::drivers
