// YAML -> config structs. Every map is read through a KeyReader that remembers which keys were
// asked for, so a key nobody asked for is reported as unknown (with the list of valid keys).
#include "lcmloc/app/config.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

#include <fmt/format.h>

#include "lcmloc/app/process.hpp"
#include "lcmloc/app/yaml_reader.hpp"
#include "config_ins.hpp"
#include "lcmloc/core/filter.hpp"

namespace lcmloc::common {

namespace {

using yaml_detail::join;
using yaml_detail::nodeText;

std::string describe(const std::string& file, const std::string& key, const std::string& reason) {
  std::string s = file;
  if (!key.empty()) s += ": " + key;
  return s + ": " + reason;
}


constexpr double kPi = 3.14159265358979323846;

void parseScenarioSection(KeyReader& root, models::ScenarioConfig& s) {
  KeyReader r(root.child("scenario"), root.file(), "scenario");
  r.get("name", s.name);
  r.get<uint64_t>("seed", s.seed);
  r.get("realtime_factor", s.realtime_factor, kRealtimeFactor.lo, kRealtimeFactor.hi, "0 = as fast as possible");
  r.finish();
}

void parsePath(KeyReader& root, models::PathConfig& p) {
  KeyReader r(root.child("path"), root.file(), "path");
  r.get("x0", p.x0);
  r.get("y0", p.y0);
  r.get("theta0", p.theta0, -kPi, kPi);
  YAML::Node segs = r.child("segments");
  if (segs) {
    const std::string kp = r.keyPath("segments");
    if (!segs.IsSequence() || segs.size() == 0)
      throw ConfigError(root.file(), kp, "expected a non-empty list of {length, curvature}");
    p.segments.clear();
    for (std::size_t i = 0; i < segs.size(); ++i) {
      models::PathSegment seg;
      KeyReader sr(segs[i], root.file(), kp + "[" + std::to_string(i) + "]");
      sr.get("length", seg.length, 1e-3, 1e6);
      sr.get("curvature", seg.curvature, -10.0, 10.0);
      sr.finish();
      p.segments.push_back(seg);
    }
  }
  r.finish();
}

void parseMarkers(KeyReader& root, models::MarkerLayout& m) {
  KeyReader r(root.child("markers"), root.file(), "markers");
  r.get("count", m.count, static_cast<int>(kMarkerCount.lo), static_cast<int>(kMarkerCount.hi));
  r.get("spacing", m.spacing, 1e-3, 1e6);
  r.get("first_at", m.first_at, 0.0, 1e6);
  r.finish();
}

void parseVehicle(KeyReader& root, models::VehicleConfig& v) {
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

void parseOdometry(KeyReader& root, models::OdometrySensorConfig& o) {
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

void parseMagRuler(KeyReader& root, models::MagRulerConfig& m) {
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

void parseImu(KeyReader& root, models::ImuSensorConfig& m) {
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
  r.get("declination", m.declination, -kPi, kPi);
  r.get("mag_std", m.mag_std, 0.0, 10.0);
  r.get("mag_disturbance_std", m.mag_disturbance_std, 0.0, 10.0);
  r.get("mag_disturbance_tau", m.mag_disturbance_tau, 1e-3, 1e6);
  r.finish();
}

void parseGps(KeyReader& root, models::GpsSensorConfig& g, GpsDriverConfig& d) {
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
  r.getList("outages", g.outages, "{start, duration}", [](KeyReader& o, models::GpsOutage& v) {
    o.get("start", v.start, 0.0, 1e7);
    o.get("duration", v.duration, 0.0, 1e7);
  });
  r.getList("jumps", g.jumps, "{at, duration, dx, dy}", [](KeyReader& j, models::GpsJump& v) {
    j.get("at", v.at, 0.0, 1e7);
    j.get("duration", v.duration, 0.0, 1e7);
    j.get("dx", v.dx, -1e6, 1e6);
    j.get("dy", v.dy, -1e6, 1e6);
  });
  r.finish();
}

void parseDatum(KeyReader& root, Datum& d) {
  KeyReader r(root.child("datum"), root.file(), "datum");
  r.get("latitude", d.latitude, -90.0, 90.0);
  r.get("longitude", d.longitude, -180.0, 180.0);
  r.get("altitude", d.altitude, -1e4, 1e5);
  r.finish();
}

void parseFaults(KeyReader& root, std::vector<models::FaultConfig>& faults) {
  YAML::Node n = root.child("faults");
  if (!n) return;
  if (n.IsNull()) { faults.clear(); return; }
  if (!n.IsSequence()) throw ConfigError(root.file(), "faults", "expected a list of faults, got " + nodeText(n));
  faults.clear();
  for (std::size_t i = 0; i < n.size(); ++i) {
    const std::string kp = "faults[" + std::to_string(i) + "]";
    models::FaultConfig f;
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

void parseChannels(KeyReader& root, ChannelConfig& c) {
  KeyReader r(root.child("channels"), root.file(), "channels");
  r.get("ground_truth", c.ground_truth);
  r.get("odometry", c.odometry);
  r.getStrings("magruler", c.magruler);
  r.get("magruler_fault", c.magruler_fault);
  r.get("fault_events", c.fault_events);
  r.get("pose", c.pose);
  r.get("gate", c.gate);
  r.get("control", c.control);
  r.get("status", c.status);
  r.get("heartbeat", c.heartbeat);
  r.get("imu", c.imu);
  r.get("gps", c.gps);
  r.get("landmarks", c.landmarks);
  r.get("beacons", c.beacons);
  r.get("vision", c.vision);
  r.finish();
  // Every name non-empty and without blanks; the daemon's outputs and its control channel apart
  // from every input (a POSE published on ODOMETRY would be read back as odometry).
  std::vector<std::pair<std::string, std::string>> named{
      {"ground_truth", c.ground_truth}, {"odometry", c.odometry}, {"magruler_fault", c.magruler_fault},
      {"fault_events", c.fault_events}, {"pose", c.pose}, {"gate", c.gate}, {"control", c.control},
      {"status", c.status}, {"heartbeat", c.heartbeat}, {"imu", c.imu}, {"gps", c.gps},
      {"landmarks", c.landmarks}, {"beacons", c.beacons}, {"vision", c.vision}};
  for (std::size_t i = 0; i < c.magruler.size(); ++i) named.push_back({"magruler[" + std::to_string(i) + "]", c.magruler[i]});
  for (const auto& [key, name] : named)
    if (name.empty() || name.find_first_of(" \t\n") != std::string::npos)
      throw ConfigError(root.file(), "channels." + key, "a channel name must be non-empty and without blanks");
  const std::vector<std::string> outputs{"pose", "gate", "status", "control", "heartbeat"};
  for (const auto& [out_key, out_name] : named) {
    if (std::find(outputs.begin(), outputs.end(), out_key) == outputs.end()) continue;
    for (const auto& [key, name] : named)
      if (key != out_key && name == out_name)
        throw ConfigError(root.file(), "channels." + out_key,
                          "'" + out_name + "' is also channels." + key + ": each of pose, gate, status, control "
                          "and heartbeat needs a channel of its own");
  }
}

void checkFilterType(const std::string& type, const std::string& file, const std::string& key) {
  const auto types = core::filterTypes();
  if (std::find(types.begin(), types.end(), type) == types.end())
    throw ConfigError(file, key, "unknown filter type '" + type + "' (valid: " + join(types) + ")");
}

}  // namespace

void checkFilterList(const std::vector<std::string>& types, const std::string& file, const std::string& key) {
  for (std::size_t i = 0; i < types.size(); ++i) {
    const std::string k = key + "[" + std::to_string(i) + "]";
    checkFilterType(types[i], file, k);
    if (std::find(types.begin(), types.begin() + static_cast<std::ptrdiff_t>(i), types[i]) !=
        types.begin() + static_cast<std::ptrdiff_t>(i))
      throw ConfigError(file, k, "'" + types[i] + "' is listed twice");
  }
}

namespace {

void parseFusion(KeyReader& root, FusionConfig& f) {
  KeyReader r(root.child("fusion"), root.file(), "fusion");
  YAML::Node filter = r.child("filter");
  if (filter) f.filter = parseFilterConfig(filter, f.filter, root.file(), "fusion.filter");
  r.getStrings("shadow", f.shadow);
  checkFilterList(f.shadow, root.file(), "fusion.shadow");  // a shadow publishes on POSE_<TYPE>
  r.get("reorder_window", f.reorder_window, 0.0, 10.0);
  r.get("status_period", f.status_period, 0.01, 3600.0);
  r.get("max_time_jump", f.max_time_jump, 0.0, 1e9);
  // An input later than max_time_jump is taken for a source whose time started over, however wide
  // the reorder window: a window as wide would hold late inputs only to refuse them.
  if (f.max_time_jump > 0.0 && f.reorder_window >= f.max_time_jump)
    throw ConfigError(root.file(), "fusion.reorder_window",
                      fmt::format("{} s is not less than fusion.max_time_jump ({} s): an input that late is taken "
                                  "for a new time base, not reordered (widen max_time_jump with it, or 0 = off)",
                                  f.reorder_window, f.max_time_jump));
  r.get("map_file", f.map_file);
  if (!f.map_file.empty() && f.map_file[0] != '/') {
    const auto slash = root.file().rfind('/');
    if (slash != std::string::npos) f.map_file = root.file().substr(0, slash + 1) + f.map_file;
  }
  r.get("output_every", f.output_every, 1, 1000000);
  r.get("max_odometry_gap", f.max_odometry_gap, 0.0, 3600.0, "0 = off");
  r.get("odometry_gap_accel", f.odometry_gap_accel, 0.0, 100.0);
  r.get("odometry_gap_yaw_rate", f.odometry_gap_yaw_rate, 0.0, 10.0);
  r.get("odometry_period", f.odometry_period, 0.0, 10.0, "0 = not known");
  ins_config::parseLandmarks(r, f.landmarks);
  {
    KeyReader x(r.child("landmark_fix"), root.file(), "fusion.landmark_fix");
    x.get("gate_probability", f.fix_gate.probability, 0.0, 1.0 - 1e-12, "0 = no gate");
    x.get("lockout_rejections", f.fix_gate.lockout_rejections, 0, 1000000);
    x.get("max_condition", f.fix.max_condition, 1.0, 1e12);
    x.finish();
  }
  r.finish();
}

void parseLogger(KeyReader& root, LoggerConfig& l) {
  KeyReader r(root.child("logger"), root.file(), "logger");
  r.get("output", l.output);
  if (l.output.empty()) throw ConfigError(root.file(), "logger.output", "must not be empty");
  r.getStrings("channels", l.channels);
  r.get("queue_capacity", l.queue_capacity, 1, 100000000);
  r.get("queue_bytes", l.queue_bytes, int64_t{1} << 20, int64_t{1} << 40);
  r.get("max_file_bytes", l.max_file_bytes, int64_t{0}, int64_t{1} << 50);
  r.get("max_file_seconds", l.max_file_seconds, kMaxFileSeconds.lo, kMaxFileSeconds.hi);
  r.get("flush_period", l.flush_period, kFlushPeriod.lo, kFlushPeriod.hi);
  r.get("status_channel", l.status_channel);
  r.get("status_period", l.status_period, 0.01, 3600.0);
  r.get("recv_buf_size", l.recv_buf_size, 65536, 1 << 30);
  r.finish();
}

// `vision` section: the simulated bearing sensor (seeds/004 §III). Angles in radians.
void parseVision(KeyReader& root, models::VisionSensorConfig& v) {
  KeyReader r(root.child("vision"), root.file(), "vision");
  r.get("rate_hz", v.rate_hz, kVisionRateHz.lo, kVisionRateHz.hi);
  r.get("bearing_std", v.bearing_std, 0.0, 1.0, "1 sigma [rad]");
  r.get("resolution", v.resolution, 0.0, 0.1, "quantization step [rad], 0 = none");
  r.get<uint64_t>("seed", v.seed);
  r.get("max_range", v.max_range, 0.0, 1e7, "[m], 0 = no limit");
  r.finish();
}

}  // namespace

ConfigError::ConfigError(const std::string& file, const std::string& key, const std::string& reason)
    : std::runtime_error(describe(file, key, reason)) {}

core::FilterConfig parseFilterConfig(const YAML::Node& node, const core::FilterConfig& base,
                                     const std::string& file, const std::string& key_prefix) {
  core::FilterConfig c = base;
  KeyReader r(node, file, key_prefix);
  r.get("type", c.type);
  checkFilterType(c.type, file, r.keyPath("type"));
  r.get("wheelbase", c.wheelbase, 0.1, 20.0);
  r.get("ruler_offset", c.ruler_offset, -20.0, 20.0);
  r.get("ruler_half_width", c.ruler_half_width, 0.01, 10.0);
  r.getVector("initial_pose", c.initial_pose, -1e7, 1e7);
  if (std::abs(c.initial_pose[2]) > kPi)
    throw ConfigError(file, r.keyPath("initial_pose[2]"), "heading must be within [-pi, pi]");
  r.getVector("p0_diag", c.p0_diag, 0.0, 1e6);
  r.getVector("pw_diag", c.pw_diag, 0.0, 1e6);
  r.get("pw_distance", c.pw_distance, 0.0, 1e6);
  r.getVector("pv_diag", c.pv_diag, 1e-12, 1e6);
  {
    KeyReader s(r.child("sigma"), file, r.keyPath("sigma"));
    s.get("alpha", c.sigma.alpha, 1e-4, 10.0);
    s.get("beta", c.sigma.beta, 0.0, 10.0);
    s.get("kappa", c.sigma.kappa, -2.9, 100.0);
    s.finish();
  }
  {
    KeyReader g(r.child("gate"), file, r.keyPath("gate"));
    g.get("enabled", c.gate.enabled);
    YAML::Node v = g.child("value");
    if (v) {
      if (v.IsNull()) {
        c.gate.value.reset();
      } else {
        double x = g.convert<double>(v, g.keyPath("value"));
        if (x <= 0) throw ConfigError(file, g.keyPath("value"), "gate value must be > 0");
        c.gate.value = x;
      }
    }
    g.get("probability", c.gate.probability, 1e-6, 1.0 - 1e-12);
    g.get("dof", c.gate.dof, 0, 10);
    g.finish();
  }
  r.get("reach_forward", c.reach_forward, 0.0, 100.0);
  r.get("reach_lateral", c.reach_lateral, 0.0, 100.0);
  r.get("lockout_rejections", c.lockout_rejections, 0, 1000000);
  r.get("lockout_inflation", c.lockout_inflation, 1.0, 1e6);
  r.get("lockout_max_std", c.lockout_max_std, 1e-3, 1e6);
  r.get("scale_std0", c.scale_std0, 0.0, 1.0);
  r.get("steer_bias_std0", c.steer_bias_std0, 0.0, 1.0);
  r.get("scale_rw", c.scale_rw, 0.0, 1.0);
  r.get("steer_bias_rw", c.steer_bias_rw, 0.0, 1.0);
  {
    auto& g = c.gnss;
    KeyReader n(r.child("gnss"), file, r.keyPath("gnss"));
    n.get("accel_std", g.accel_std, 1e-9, 100.0);
    n.get("accel_saturation", g.accel_saturation, 0.0, 1e4, "0 = no check");
    n.get("accel_unknown_std", g.accel_unknown_std, 1e-9, 100.0);
    n.get("encoder_std", g.encoder_std, 1e-9, 100.0);
    n.get("steering_std", g.steering_std, 0.0, 1.0);
    n.get("heading_rw", g.heading_rw, 0.0, 10.0);
    n.get("position_rw", g.position_rw, 0.0, 100.0);
    n.get("mag_std", g.mag_std, 1e-9, 10.0);
    n.get("declination", g.declination, -kPi, kPi);
    n.get("use_magnetometer", g.use_magnetometer);
    n.get("gps_std", g.gps_std, 1e-6, 1e4);
    n.get("speed_std0", g.speed_std0, 1e-9, 100.0);
    n.get("gps_lockout_rejections", g.gps_lockout_rejections, 0, 1000000);
    n.get("mag_lockout_rejections", g.mag_lockout_rejections, 0, 1000000);
    n.get("coast_timeout", g.coast_timeout, 0.0, 1e6);
    n.get("course_distance", g.course_distance, 0.0, 1e5, "0 = off");
    n.get("course_std", g.course_std, 0.0, 10.0);
    n.finish();
  }
  r.get("pw_turn", c.pw_turn, 0.0, 1e3);
  {
    KeyReader l(r.child("landmarks"), file, r.keyPath("landmarks"));
    l.get("range_std", c.landmarks.range_std, 1e-9, 1e6);
    l.get("bearing_std", c.landmarks.bearing_std, 1e-9, 10.0);
    l.get("beacon_std", c.landmarks.beacon_std, 1e-9, 1e6);
    l.finish();
  }
  ins_config::parseInsFilter(r, c.ins);
  r.finish();
  // What only the values together decide (p0_diag > 0 where a range allows 0, the sigma-point
  // parameters, ...): the filter's own checks, so that the file and key are named here rather
  // than when a process builds the filter.
  try {
    core::makeFilter(c, core::MarkerMap{});
  } catch (const std::invalid_argument& e) {
    std::string why = e.what();
    if (why.rfind("filter config: ", 0) == 0) why.erase(0, 15);
    throw ConfigError(file, key_prefix, why);
  }
  return c;
}

SystemConfig parseSystemConfig(const std::string& yaml_text, const std::string& file) {
  YAML::Node doc;
  try {
    doc = YAML::Load(yaml_text);
  } catch (const YAML::ParserException& e) {
    throw ConfigError(file, "", "YAML syntax error at line " + std::to_string(e.mark.line + 1) +
                                    ", column " + std::to_string(e.mark.column + 1) + ": " + e.msg);
  }
  SystemConfig cfg;
  cfg.file = file;
  KeyReader root(doc, file, "");
  parseScenarioSection(root, cfg.scenario);
  parsePath(root, cfg.scenario.path);
  parseMarkers(root, cfg.scenario.markers);
  parseVehicle(root, cfg.scenario.vehicle);
  parseOdometry(root, cfg.scenario.odometry);
  parseMagRuler(root, cfg.scenario.magruler);
  parseFaults(root, cfg.scenario.faults);
  parseImu(root, cfg.scenario.imu);
  parseGps(root, cfg.scenario.gps, cfg.gps_driver);
  parseDatum(root, cfg.datum);
  parseChannels(root, cfg.channels);
  parseFusion(root, cfg.fusion);
  parseLogger(root, cfg.logger);
  ins_config::parseInsSim(root, cfg.ins_sim);
  parseVision(root, cfg.scenario.vision);
  ins_config::parseLandmarkList(root, "landmarks", cfg.scenario.landmarks);
  // One landmark map for the whole system: the fusion takes the top-level `landmarks` (the
  // one lcmloc-vision observes) unless its own `fusion.landmarks` is given.
  if (cfg.fusion.landmarks.empty())
    for (const auto& l : cfg.scenario.landmarks) cfg.fusion.landmarks[l.id] = core::Vec2(l.x, l.y);
  root.finish();
  checkSampledRate(cfg.scenario.odometry.rate_hz, cfg.scenario, file, "odometry.rate_hz");
  checkSampledRate(cfg.scenario.imu.rate_hz, cfg.scenario, file, "imu.rate_hz");
  checkSampledRate(cfg.scenario.magruler.publish_rate_hz, cfg.scenario, file, "magruler.publish_rate_hz");
  return cfg;
}

void checkSampledRate(double rate_hz, const models::ScenarioConfig& sc, const std::string& file,
                      const std::string& key) {
  if (rate_hz > sc.vehicle.rate_hz)
    throw ConfigError(file, key,
                      fmt::format("{} Hz is above the ground-truth rate vehicle.rate_hz ({} Hz) the sensor samples: it "
                                  "would publish at {} Hz",
                                  rate_hz, sc.vehicle.rate_hz, sc.vehicle.rate_hz));
}

std::string readConfigFile(const std::string& path, const std::string& what) {
  if (const std::string problem = fileProblem(path, 64u << 20); !problem.empty())
    throw ConfigError(path, "", problem == kNoSuchFile ? "cannot open " + what + " (does it exist?)"
                                                       : problem + ": not a " + what);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path, "", "cannot open " + what + ": " + std::strerror(errno));
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void refuseOutputOverInputs(const std::string& flag, const std::string& output,
                            const std::vector<std::string>& inputs, const std::string& what) {
  for (const auto& in : inputs) {
    std::error_code ec;  // either missing: not the same file
    if (std::filesystem::equivalent(in, output, ec) && !ec)
      throw ConfigError(flag, "", "'" + output + "' is the " + what + " '" + in +
                                      "': writing it would destroy the input, choose another output");
  }
}

SystemConfig loadSystemConfig(const std::string& path) { return parseSystemConfig(readConfigFile(path), path); }

core::EngineConfig engineConfig(const SystemConfig& cfg) {
  const auto us = [](double s) { return static_cast<int64_t>(std::llround(s * 1e6)); };
  core::EngineConfig ec;
  ec.filter = cfg.fusion.filter;
  ec.shadow = cfg.fusion.shadow;
  ec.reorder_window_us = us(cfg.fusion.reorder_window);
  ec.output_every = cfg.fusion.output_every;
  ec.landmarks = cfg.fusion.landmarks;
  ec.fix = cfg.fusion.fix;
  ec.fix_gate = cfg.fusion.fix_gate;
  ec.max_time_jump_us = us(cfg.fusion.max_time_jump);
  ec.odometry_gap = {us(cfg.fusion.max_odometry_gap), cfg.fusion.odometry_gap_accel, cfg.fusion.odometry_gap_yaw_rate,
                     us(cfg.fusion.odometry_period)};
  return ec;
}

}  // namespace lcmloc::common
