// YAML -> config structs. Every map is read through a KeyReader that remembers which keys were
// asked for, so a key nobody asked for is reported as unknown (with the list of valid keys).
// Here: the file as a whole, `datum`, `channels`, `fusion` (with its filter), `logger` and the
// top-level `landmarks`; the INS filter's section and the landmark lists are in config_ins.cpp.
// The simulation's sections are accepted unread (lcmloc_simconfig reads them).
#include "lcmloc/app/config.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include <fmt/format.h>

#include "lcmloc/app/files.hpp"
#include "lcmloc/app/yaml_reader.hpp"
#include "config_ins.hpp"
#include "lcmloc/core/filter.hpp"

namespace lcmloc::app {

namespace {

using yaml_detail::join;

std::string describe(const std::string& file, const std::string& key, const std::string& reason) {
  std::string s = file;
  if (!key.empty()) s += ": " + key;
  return s + ": " + reason;
}

constexpr double kPi = 3.14159265358979323846;

/// Every single-channel key of `channels` (magruler, a list, is read apart).
constexpr std::pair<const char*, std::string ChannelConfig::*> kChannelKeys[] = {
    {"ground_truth", &ChannelConfig::ground_truth}, {"odometry", &ChannelConfig::odometry},
    {"magruler_fault", &ChannelConfig::magruler_fault}, {"fault_events", &ChannelConfig::fault_events},
    {"pose", &ChannelConfig::pose}, {"pose_control", &ChannelConfig::pose_control}, {"gate", &ChannelConfig::gate}, {"control", &ChannelConfig::control},
    {"status", &ChannelConfig::status}, {"timing", &ChannelConfig::timing}, {"heartbeat", &ChannelConfig::heartbeat}, {"imu", &ChannelConfig::imu},
    {"gps", &ChannelConfig::gps}, {"landmarks", &ChannelConfig::landmarks}, {"beacons", &ChannelConfig::beacons},
    {"vision", &ChannelConfig::vision}};

void parseChannels(KeyReader& root, ChannelConfig& c) {
  KeyReader r(root.child("channels"), root.file(), "channels");
  for (const auto& [key, member] : kChannelKeys) r.get(key, c.*member);
  r.getStrings("magruler", c.magruler);
  r.finish();
  // Every name non-empty and without blanks; the daemon's outputs and its control channel apart
  // from every input (a POSE published on ODOMETRY would be read back as odometry).
  std::vector<std::pair<std::string, std::string>> named;
  for (const auto& [key, member] : kChannelKeys) named.push_back({key, c.*member});
  for (std::size_t i = 0; i < c.magruler.size(); ++i) named.push_back({"magruler[" + std::to_string(i) + "]", c.magruler[i]});
  for (const auto& [key, name] : named)
    if (name.empty() || name.find_first_of(" \t\n") != std::string::npos)
      throw ConfigError(root.file(), "channels." + key, "a channel name must be non-empty and without blanks");
  const std::vector<std::string> outputs{"pose", "pose_control", "gate", "status", "timing", "control", "heartbeat"};
  for (const auto& [out_key, out_name] : named) {
    if (std::find(outputs.begin(), outputs.end(), out_key) == outputs.end()) continue;
    for (const auto& [key, name] : named)
      if (key != out_key && name == out_name)
        throw ConfigError(root.file(), "channels." + out_key,
                          "'" + out_name + "' is also channels." + key + ": each of pose, pose_control, gate, status, "
                          "timing, control and heartbeat needs a channel of its own");
  }
}

void checkFilterType(const std::string& type, const std::string& file, const std::string& key) {
  const auto types = core::filterTypes();
  if (std::find(types.begin(), types.end(), type) == types.end())
    throw ConfigError(file, key, "unknown filter type '" + type + "' (valid: " + join(types) + ")");
}

}  // namespace

const std::vector<std::string>& sensorKeys() {
  static const std::vector<std::string> keys{"odometry", "magruler", "imu", "gps", "landmarks", "beacons", "vision"};
  return keys;
}

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

/// The sensor keys of `fusion.sensors` (the daemon's input kinds, fusion/daemon/inputs.hpp) and
/// the channels of each.
std::vector<std::string> sensorChannels(const ChannelConfig& c, const std::string& key) {
  if (key == "odometry") return {c.odometry};
  if (key == "magruler") return c.magruler;
  if (key == "imu") return {c.imu};
  if (key == "gps") return {c.gps};
  if (key == "landmarks") return {c.landmarks};
  if (key == "beacons") return {c.beacons};
  if (key == "vision") return {c.vision};
  return {};
}

/// fusion.sensors, max_horizon, max_queued, and the horizon within its bounds and the guard.
void parseHorizon(KeyReader& r, const std::string& file, FusionConfig& f) {
  r.get("max_horizon", f.max_horizon, 0.0, 10.0);
  r.get("max_queued", f.max_queued, 1, 10000000);
  if (f.reorder_window > f.max_horizon)
    throw ConfigError(file, "fusion.reorder_window",
                      fmt::format("{} s is more than fusion.max_horizon ({} s), the horizon's memory bound",
                                  f.reorder_window, f.max_horizon));
  KeyReader sensors(r.child("sensors"), file, "fusion.sensors");
  for (const std::string& key : sensorKeys()) {
    KeyReader x(sensors.child(key), file, "fusion.sensors." + key);
    FusionConfig::Sensor s = f.sensors.count(key) ? f.sensors[key] : FusionConfig::Sensor{};
    const char* bound = "0 to fusion.max_horizon: the horizon's memory bound";
    x.get("delay", s.delay, 0.0, f.max_horizon, bound);
    x.get("period", s.period, 0.0, 3600.0, "0 = not watched");
    x.finish();
    if (s.delay > 0.0 || s.period > 0.0) f.sensors[key] = s;
    // An input later than max_time_jump is taken for a source whose time started over: a horizon
    // as wide would hold late inputs only to refuse them.
    if (f.max_time_jump > 0.0 && s.delay >= f.max_time_jump)
      throw ConfigError(file, "fusion.sensors." + key + ".delay",
                        fmt::format("{} s is not less than fusion.max_time_jump ({} s): an input that late is taken "
                                    "for a new time base (widen max_time_jump with it, or 0 = off)",
                                    s.delay, f.max_time_jump));
  }
  sensors.finish();
}

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
  parseHorizon(r, root.file(), f);
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
    KeyReader x(r.child("limits"), root.file(), "fusion.limits");
    x.get("max_speed", f.limits.max_speed, 0.0, 1e4, "0 = off");
    x.get("max_yaw_rate", f.limits.max_yaw_rate, 0.0, 1e4, "0 = off");
    x.get("max_steering", f.limits.max_steering, 0.0, 1.6, "0 = off");
    x.get("max_fix_jump_sigma", f.limits.max_fix_jump_sigma, 0.0, 1e6, "0 = off");
    x.finish();
    // The ruler's span (its half width, with half of it again for the detection's noise) and a
    // fix's sigma when it carries none come from the filter's settings.
    f.limits.max_lateral_offset = 1.5 * f.filter.ruler_half_width;
    f.limits.gps_std = f.filter.gnss.gps_std;
  }
  {
    KeyReader x(r.child("landmark_fix"), root.file(), "fusion.landmark_fix");
    x.get("gate_probability", f.fix_gate.probability, 0.0, 1.0 - 1e-12, "0 = no gate");
    x.get("lockout_rejections", f.fix_gate.lockout_rejections, 0, 1000000);
    x.get("max_condition", f.fix.max_condition, 1.0, 1e12);
    x.finish();
  }
  r.finish();
}

void parseDatum(KeyReader& root, bus::Datum& d) {
  KeyReader r(root.child("datum"), root.file(), "datum");
  r.get("latitude", d.latitude, -90.0, 90.0);
  r.get("longitude", d.longitude, -180.0, 180.0);
  r.get("altitude", d.altitude, -1e4, 1e5);
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

}  // namespace

ConfigError::ConfigError(const std::string& file, const std::string& key, const std::string& reason)
    : std::runtime_error(describe(file, key, reason)) {}


/// fusion.filter.calibration (the self-calibration states of ukf_landmarks and the GNSS filters; docs/config.md).
static void parseCalibration(KeyReader& r, core::FilterConfig::Calibration& k) {
  using BB = core::FilterConfig::Calibration::BeaconBias;
  KeyReader n(r.child("calibration"), r.file(), r.keyPath("calibration"));
  std::string bias;
  n.get("beacon_bias", bias);
  if (bias == "off") k.beacon_bias = BB::Off;
  else if (bias == "shared") k.beacon_bias = BB::Shared;
  else if (bias == "per_beacon") k.beacon_bias = BB::PerBeacon;
  else if (!bias.empty())
    throw ConfigError(r.file(), n.keyPath("beacon_bias"), "'" + bias + "' is not one of off, shared, per_beacon");
  n.get("beacon_bias_mean", k.beacon_bias_mean, -1e3, 1e3);
  n.get("beacon_bias_std", k.beacon_bias_std, 1e-9, 1e3);
  n.get("beacon_bias_rw", k.beacon_bias_rw, 0.0, 10.0);
  n.get("odo_scale", k.odo_scale);
  n.get("odo_scale_mean", k.odo_scale_mean, -0.9, 10.0);
  n.get("odo_scale_std", k.odo_scale_std, 1e-9, 1.0);
  n.get("odo_scale_rw", k.odo_scale_rw, 0.0, 1.0);
  n.get("yaw_rate_scale", k.yaw_rate_scale);
  n.get("yaw_rate_scale_mean", k.yaw_rate_scale_mean, -10.0, 10.0);
  n.get("yaw_rate_scale_std", k.yaw_rate_scale_std, 1e-9, 10.0);
  n.get("yaw_rate_scale_rw", k.yaw_rate_scale_rw, 0.0, 1.0);
  n.get("yaw_rate_bias", k.yaw_rate_bias);
  n.get("yaw_rate_bias_mean", k.yaw_rate_bias_mean, -1.0, 1.0);
  n.get("yaw_rate_bias_std", k.yaw_rate_bias_std, 1e-9, 1.0);
  n.get("yaw_rate_bias_rw", k.yaw_rate_bias_rw, 0.0, 1.0);
  n.get("steering_bias", k.steering_bias);
  n.get("steering_bias_mean", k.steering_bias_mean, -1.0, 1.0);
  n.get("steering_bias_std", k.steering_bias_std, 1e-9, 1.0);
  n.get("steering_bias_rw", k.steering_bias_rw, 0.0, 1.0);
  n.get("mag_bias", k.mag_bias);
  n.get("mag_bias_std", k.mag_bias_std, 1e-9, 3.2);
  n.get("mag_bias_tau", k.mag_bias_tau, 1e-3, 1e6);
  n.get("accel_bias", k.accel_bias);
  n.get("accel_bias_std", k.accel_bias_std, 1e-9, 100.0);
  n.get("accel_bias_rw", k.accel_bias_rw, 0.0, 10.0);
  n.finish();
}

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
    l.get("correlation_factor", c.landmarks.correlation_factor, 1.0, 1e6);
    l.finish();
  }
  parseCalibration(r, c.calibration);
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
  SystemConfig cfg;
  cfg.file = file;
  KeyReader root(parseYamlText(yaml_text, file), file, "");
  // The top-level sections in the file's order (an unknown key's message lists them so); the
  // simulation's (null here) are accepted unread.
  using Parse = void (*)(KeyReader&, SystemConfig&);
  const std::pair<const char*, Parse> sections[] = {
      {"scenario", nullptr}, {"path", nullptr}, {"markers", nullptr}, {"vehicle", nullptr}, {"odometry", nullptr},
      {"magruler", nullptr}, {"faults", nullptr}, {"imu", nullptr}, {"gps", nullptr},
      {"datum", [](KeyReader& r, SystemConfig& c) { parseDatum(r, c.datum); }},
      {"channels", [](KeyReader& r, SystemConfig& c) { parseChannels(r, c.channels); }},
      {"fusion", [](KeyReader& r, SystemConfig& c) { parseFusion(r, c.fusion); }},
      {"logger", [](KeyReader& r, SystemConfig& c) { parseLogger(r, c.logger); }},
      {"ins_sim", nullptr}, {"vision", nullptr},
      {"landmarks", [](KeyReader& r, SystemConfig& c) { ins_config::parseLandmarkList(r, "landmarks", c.landmarks); }},
  };
  for (const auto& [name, parse] : sections) {
    if (parse)
      parse(root, cfg);
    else
      root.child(name);
  }
  // One landmark map for the whole system: the fusion takes the top-level `landmarks` (the
  // one lcmloc-vision observes) unless its own `fusion.landmarks` is given.
  if (cfg.fusion.landmarks.empty())
    for (const auto& l : cfg.landmarks) cfg.fusion.landmarks[l.id] = core::Vec2(l.x, l.y);
  root.finish();
  return cfg;
}

YAML::Node parseYamlText(const std::string& yaml_text, const std::string& file) {
  try {
    return YAML::Load(yaml_text);
  } catch (const YAML::ParserException& e) {
    throw ConfigError(file, "", "YAML syntax error at line " + std::to_string(e.mark.line + 1) +
                                    ", column " + std::to_string(e.mark.column + 1) + ": " + e.msg);
  }
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
  ec.max_queued = static_cast<std::size_t>(cfg.fusion.max_queued);
  for (const auto& [key, s] : cfg.fusion.sensors)
    for (const std::string& channel : sensorChannels(cfg.channels, key))
      ec.sensors[channel] = core::SensorExpectation{us(s.delay), us(s.period)};
  return ec;
}

}  // namespace lcmloc::app
