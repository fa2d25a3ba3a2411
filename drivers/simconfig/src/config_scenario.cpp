// The scenario and sensor sections of the system config: `scenario`, `path`, `markers`,
// `vehicle`, `odometry`, `magruler`, `faults`, `imu`, `gps` and `vision` (what the simulator and
// the drivers read). Called from sim_config.cpp.
#include "config_scenario.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace lcmloc::simconfig::scenario_config {

// Built on the application layer (configuration, process helpers).
using namespace lcmloc::app;

using yaml_detail::nodeText;

void parseScenarioSection(KeyReader& root, sim::ScenarioConfig& s) {
  KeyReader r(root.child("scenario"), root.file(), "scenario");
  r.get("name", s.name);
  r.get<uint64_t>("seed", s.seed);
  r.get("realtime_factor", s.realtime_factor, kRealtimeFactor.lo, kRealtimeFactor.hi, "0 = as fast as possible");
  r.finish();
}

void parsePath(KeyReader& root, sim::PathConfig& p) {
  KeyReader r(root.child("path"), root.file(), "path");
  r.get("x0", p.x0);
  r.get("y0", p.y0);
  r.get("theta0", p.theta0, -M_PI, M_PI);
  YAML::Node segs = r.child("segments");
  if (segs) {
    const std::string kp = r.keyPath("segments");
    if (!segs.IsSequence() || segs.size() == 0)
      throw ConfigError(root.file(), kp, "expected a non-empty list of {length, curvature}");
    p.segments.clear();
    for (std::size_t i = 0; i < segs.size(); ++i) {
      sim::PathSegment seg;
      KeyReader sr(segs[i], root.file(), kp + "[" + std::to_string(i) + "]");
      sr.get("length", seg.length, 1e-3, 1e6);
      sr.get("curvature", seg.curvature, -10.0, 10.0);
      sr.finish();
      p.segments.push_back(seg);
    }
  }
  r.finish();
}

void parseMarkers(KeyReader& root, sim::MarkerLayout& m) {
  KeyReader r(root.child("markers"), root.file(), "markers");
  r.get("count", m.count, static_cast<int>(kMarkerCount.lo), static_cast<int>(kMarkerCount.hi));
  r.get("spacing", m.spacing, 1e-3, 1e6);
  r.get("first_at", m.first_at, 0.0, 1e6);
  r.finish();
}

void parseVehicle(KeyReader& root, sim::VehicleConfig& v) {
  KeyReader r(root.child("vehicle"), root.file(), "vehicle");
  r.get("wheelbase", v.wheelbase, 0.1, 20.0);
  r.get("speed", v.speed, 0.01, 100.0);
  r.get("accel", v.accel, 0.01, 100.0);
  r.get("max_steering", v.max_steering, 0.01, 1.5);
  r.get("lookahead", v.lookahead, 0.1, 100.0);
  r.get("weave_amplitude", v.weave_amplitude, 0.0, 10.0);
  r.get("weave_wavelength", v.weave_wavelength, 0.1, 1e4);
  r.get("rate_hz", v.rate_hz, 1.0, 10000.0);
  r.get("substeps", v.substeps, 1, 1000);
  r.get("end_margin", v.end_margin, 0.0, 1e4);
  r.get<int64_t>("start_utime", v.start_utime, 0, std::numeric_limits<int64_t>::max() / 2);
  r.finish();
}

void parseOdometry(KeyReader& root, sim::OdometrySensorConfig& o) {
  KeyReader r(root.child("odometry"), root.file(), "odometry");
  r.get("rate_hz", o.rate_hz, 0.1, 10000.0);
  r.get("tick_length", o.tick_length, 1e-6, 1.0);
  r.get("scale_error", o.scale_error, kOdometryScaleError.lo, kOdometryScaleError.hi);
  r.get("slip_std", o.slip_std, 0.0, 1.0);
  r.get("steering_bias", o.steering_bias, kOdometrySteeringBias.lo, kOdometrySteeringBias.hi);
  r.get("steering_std", o.steering_std, 0.0, 0.5);
  r.get("steering_resolution", o.steering_resolution, 0.0, 0.5);
  r.finish();
}

void parseMagRuler(KeyReader& root, sim::MagRulerConfig& m) {
  KeyReader r(root.child("magruler"), root.file(), "magruler");
  r.get("num_sensors", m.num_sensors, 2, 1000);
  r.get("length", m.length, 0.01, 10.0);
  r.get("height", m.height, 0.001, 10.0);
  r.get("marker_depth", m.marker_depth, 0.0, 10.0);
  r.get("ruler_offset", m.ruler_offset, -20.0, 20.0);
  r.get("dipole_moment", m.dipole_moment, 0.0, 1e6);
  r.get("earth_field_z", m.earth_field_z, -10.0, 10.0);
  r.get("noise_std", m.noise_std, 0.0, 10.0);
  r.get("disturbance_std", m.disturbance_std, 0.0, 10.0);
  r.get("disturbance_tau", m.disturbance_tau, 1e-3, 1e6);
  r.get("gain_std", m.gain_std, 0.0, 0.5);
  r.get("detection_threshold", m.detection_threshold, 0.0, 100.0);
  r.get("publish_rate_hz", m.publish_rate_hz, 0.0, 10000.0);
  r.finish();
}

void parseImu(KeyReader& root, sim::ImuSensorConfig& m) {
  KeyReader r(root.child("imu"), root.file(), "imu");
  r.get("enabled", m.enabled);
  r.get("rate_hz", m.rate_hz, kImuRateHz.lo, kImuRateHz.hi);
  r.get("gravity", m.gravity, 0.0, 100.0);
  r.get("accel_std", m.accel_std, 0.0, 100.0);
  r.get("accel_bias", m.accel_bias, 0.0, 100.0);
  r.get("accel_bias_rw", m.accel_bias_rw, 0.0, 100.0);
  r.get("accel_range", m.accel_range, 0.0, 1e4, "0 = no saturation");
  r.get("gyro_std", m.gyro_std, 0.0, 100.0);
  r.get("gyro_bias", m.gyro_bias, 0.0, 100.0);
  r.get("gyro_bias_rw", m.gyro_bias_rw, 0.0, 100.0);
  r.get("gyro_range", m.gyro_range, 0.0, 1e4, "0 = no saturation");
  r.get("mag_horizontal", m.mag_horizontal, 1e-6, 10.0);
  r.get("mag_vertical", m.mag_vertical, -10.0, 10.0);
  r.get("declination", m.declination, -M_PI, M_PI);
  r.get("mag_std", m.mag_std, 0.0, 10.0);
  r.get("mag_disturbance_std", m.mag_disturbance_std, 0.0, 10.0);
  r.get("mag_disturbance_tau", m.mag_disturbance_tau, 1e-3, 1e6);
  r.finish();
}

void parseGps(KeyReader& root, sim::GpsSensorConfig& g, GpsDriverConfig& d) {
  KeyReader r(root.child("gps"), root.file(), "gps");
  r.get("enabled", g.enabled);
  r.get("source", d.source);
  if (d.source != "sim" && d.source != "gpsd")
    throw ConfigError(root.file(), "gps.source", "unknown source '" + d.source + "' (valid: sim, gpsd)");
  r.get("gpsd_host", d.gpsd_host);
  r.get("gpsd_port", d.gpsd_port);
  {
    const std::string& p = d.gpsd_port;
    const bool digits = !p.empty() && p.size() <= 5 && std::all_of(p.begin(), p.end(), [](char c) { return c >= '0' && c <= '9'; });
    if (!digits || std::stoi(p) < 1 || std::stoi(p) > 65535)
      throw ConfigError(root.file(), "gps.gpsd_port", "'" + p + "' is not a TCP port number (1-65535; gpsd's is 2947)");
  }
  r.get("time_source", d.time_source);
  if (d.time_source != "fix" && d.time_source != "receive")
    throw ConfigError(root.file(), "gps.time_source",
                      "unknown time source '" + d.time_source + "' (valid: fix, receive)");
  r.get("rate_hz", g.rate_hz, 0.01, 1000.0);
  r.get("error_model", g.error_model);
  if (g.error_model != "uniform" && g.error_model != "gaussian")
    throw ConfigError(root.file(), "gps.error_model",
                      "unknown error model '" + g.error_model + "' (valid: uniform, gaussian)");
  r.get("error", g.error, 0.0, 1e4);
  r.get("reported_std", g.reported_std, 0.0, 1e4, "0 = the model's own 1 sigma");
  r.get("satellites", g.satellites, 0, 100);
  r.get("hdop", g.hdop, 0.0, 100.0);
  r.getList("outages", g.outages, "{start, duration}", [](KeyReader& o, sim::GpsOutage& v) {
    o.get("start", v.start, 0.0, 1e7);
    o.get("duration", v.duration, 0.0, 1e7);
  });
  r.getList("jumps", g.jumps, "{at, duration, dx, dy}", [](KeyReader& j, sim::GpsJump& v) {
    j.get("at", v.at, 0.0, 1e7);
    j.get("duration", v.duration, 0.0, 1e7);
    j.get("dx", v.dx, -1e6, 1e6);
    j.get("dy", v.dy, -1e6, 1e6);
  });
  r.finish();
}

void parseFaults(KeyReader& root, std::vector<sim::FaultConfig>& faults) {
  YAML::Node n = root.child("faults");
  if (!n) return;
  if (n.IsNull()) { faults.clear(); return; }
  if (!n.IsSequence()) throw ConfigError(root.file(), "faults", "expected a list of faults, got " + nodeText(n));
  faults.clear();
  for (std::size_t i = 0; i < n.size(); ++i) {
    const std::string kp = "faults[" + std::to_string(i) + "]";
    sim::FaultConfig f;
    KeyReader r(n[i], root.file(), kp);
    r.get("kind", f.kind);
    if (f.kind != "phantom_marker" && f.kind != "wrong_offset")
      throw ConfigError(root.file(), kp + ".kind",
                        "unknown fault kind '" + f.kind + "' (valid: phantom_marker, wrong_offset)");
    r.get("at_distance", f.at_distance, 0.0, 1e6);
    r.get("lateral_offset", f.lateral_offset, -5.0, 5.0);
    r.finish();
    faults.push_back(f);
  }
}

// `vision` section: the simulated bearing sensor (seeds/004 §III). Angles in radians.
void parseVision(KeyReader& root, sim::VisionSensorConfig& v) {
  KeyReader r(root.child("vision"), root.file(), "vision");
  r.get("rate_hz", v.rate_hz, kVisionRateHz.lo, kVisionRateHz.hi);
  r.get("bearing_std", v.bearing_std, 0.0, 1.0, "1 sigma [rad]");
  r.get("resolution", v.resolution, 0.0, 0.1, "quantization step [rad], 0 = none");
  r.get<uint64_t>("seed", v.seed);
  r.get("max_range", v.max_range, 0.0, 1e7, "[m], 0 = no limit");
  r.finish();
}

}  // namespace lcmloc::simconfig::scenario_config
