#include "lcmloc/drivers/sim_convert.hpp"

namespace lcmloc::drivers {

sim::TruthState toCore(const lcmloc::ground_truth_t& m) {
  sim::TruthState s;
  s.utime = m.utime;
  s.x = m.x;
  s.y = m.y;
  s.heading = m.heading;
  s.speed = m.speed;
  s.steering = m.steering;
  s.distance = m.distance;
  return s;
}

lcmloc::ground_truth_t toLcm(const sim::TruthState& s, int64_t seq) {
  lcmloc::ground_truth_t m;
  m.utime = s.utime;
  m.seq = seq;
  m.x = s.x;
  m.y = s.y;
  m.heading = s.heading;
  m.speed = s.speed;
  m.steering = s.steering;
  m.distance = s.distance;
  return m;
}

lcmloc::odometry_t toLcm(const sim::OdometrySample& s, int64_t seq) {
  lcmloc::odometry_t m;
  m.utime = s.input.utime;
  m.seq = seq;
  m.delta_s = s.input.delta_s;
  m.ticks = s.ticks;
  m.steering = s.input.steering;
  m.has_steering = s.input.has_steering;
  m.delta_theta = s.input.delta_theta;
  return m;
}

lcmloc::magruler_t toLcm(const sim::RulerReading& r, int64_t seq) {
  lcmloc::magruler_t m;
  m.utime = r.utime;
  m.seq = seq;
  m.num_sensors = static_cast<int32_t>(r.readings.size());
  m.readings = r.readings;
  m.detected = r.detected;
  m.lateral_offset = r.lateral_offset;
  m.quality = r.quality;
  return m;
}

lcmloc::imu_t toLcm(const sim::ImuSample& s, int64_t seq) {
  lcmloc::imu_t m;
  m.utime = s.utime;
  m.seq = seq;
  for (int i = 0; i < 3; ++i) {
    m.accel[i] = s.accel[i];
    m.gyro[i] = s.gyro[i];
    m.mag[i] = s.mag[i];
  }
  return m;
}

lcmloc::gps_fix_t toLcm(const sim::GpsFixSample& f, const bus::LocalFrame& frame, int64_t seq) {
  lcmloc::gps_fix_t m{};
  m.utime = f.utime;
  m.seq = seq;
  m.fix_type = f.has_fix ? 2 : 1;
  m.satellites = static_cast<int16_t>(f.satellites);
  m.hdop = f.hdop;
  m.position_std = f.position_std;
  if (f.has_fix) {
    frame.toGeodetic(f.x, f.y, 0.0, m.latitude, m.longitude, m.altitude);
  } else {
    m.latitude = m.longitude = m.altitude = 0.0;
  }
  return m;
}

lcmloc::landmark_bearings_t toLcm(const sim::VisionSample& s, int64_t seq) {
  lcmloc::landmark_bearings_t m;
  m.utime = s.utime;
  m.seq = seq;
  m.count = static_cast<int32_t>(s.ids.size());
  m.landmark_ids.assign(s.ids.begin(), s.ids.end());
  m.bearings = s.bearings;
  m.bearing_std = s.bearing_std;
  return m;
}

}  // namespace lcmloc::drivers
