#pragma once
// YAML configuration -> plain config structs. One file describes a whole system run
// (config/paper.yaml); each process reads the sections it needs. Unknown keys, wrong types and
// out-of-range values raise ConfigError naming the file, the key path and the reason.
// Here: what every process reads. The simulation's sections (`scenario`, `path`, `markers`,
// `vehicle`, `odometry`, `magruler`, `faults`, `imu`, `gps`, `ins_sim`, `vision`) are accepted
// here unread: the fusion daemon and the logger take nothing from the simulator;
// lcmloc_simconfig (lcmloc/simconfig/sim_config.hpp) reads and checks them.
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "lcmloc/bus/geodesy.hpp"
#include "lcmloc/bus/input_limits.hpp"
#include "lcmloc/core/engine.hpp"
#include "lcmloc/core/filter.hpp"

namespace lcmloc::app {

class ConfigError : public std::runtime_error {
 public:
  ConfigError(const std::string& file, const std::string& key, const std::string& reason);
};

/// The range [lo, hi] of a configuration key that a command-line option overrides too: one
/// definition for the config reader and the option's check.
struct Bounds {
  double lo, hi;
};
inline constexpr Bounds kFlushPeriod{0.001, 3600.0};      ///< logger.flush_period [s], --flush-period
inline constexpr Bounds kMaxFileSeconds{0.0, 1e9};        ///< logger.max_file_seconds, --max-file-seconds

/// Channel names (defaults follow docs/ and the design guide).
struct ChannelConfig {
  std::string ground_truth = "GROUND_TRUTH";
  std::string odometry = "ODOMETRY";
  std::vector<std::string> magruler{"MAGRULER", "MAGRULER_FAULT"};  ///< fusion subscribes to all
  std::string magruler_fault = "MAGRULER_FAULT";  ///< where the injector publishes
  std::string fault_events = "FAULT_EVENTS";
  std::string pose = "POSE";
  /// The control pose (the canonical one with the motion still in the reorder window on top,
  /// published as each odometry or IMU message arrives): lcmloc-fusion; lcmloc-replay --control.
  std::string pose_control = "POSE_CONTROL";
  std::string gate = "GATE";
  std::string control = "FUSION_CONTROL";
  std::string status = "FUSION_STATUS";
  std::string timing = "FUSION_TIMING";  ///< fusion_timing_t: lcmloc-fusion's wall-clock timing
  std::string heartbeat = "HEARTBEAT";
  std::string imu = "IMU";
  std::string gps = "GPS";
  std::string landmarks = "LANDMARKS";  ///< landmark_obs_t
  std::string beacons = "BEACONS";      ///< beacon_range_t
  std::string vision = "VISION";  ///< landmark_bearings_t (three-landmark fix)
};

struct FusionConfig {
  core::FilterConfig filter;          ///< the active filter (type + parameters)
  std::vector<std::string> shadow;    ///< extra filter types run side by side (POSE_<TYPE>)
  double reorder_window = 0.05;       ///< canonical-order window of message time [s]
  /// What is expected of one sensor (`fusion.sensors.<key>`, key: its `channels` key, for every
  /// channel of it; core::SensorExpectation): how late its messages arrive at most, and its
  /// period (0 = not watched for silence) [s].
  struct Sensor {
    double delay = 0.0;
    double period = 0.0;
  };
  std::map<std::string, Sensor> sensors;
  /// The memory bound of the fusion horizon (docs/horizon.md): the horizon (the reorder window
  /// or the largest expected delay) at most max_horizon [s], and at most max_queued inputs held
  /// (core::EngineConfig::max_queued; more: the oldest processed early, event "horizon_full").
  double max_horizon = 2.0;
  int max_queued = 20000;
  /// [s] The fusion horizon: reorder_window, or the largest sensors' delay when larger.
  double horizon() const {
    double h = reorder_window;
    for (const auto& [key, s] : sensors) h = s.delay > h ? s.delay : h;
    return h;
  }
  double status_period = 1.0;         ///< FUSION_STATUS period of message time [s]
  /// Time-jump guard [s] of message time (0 = off): core::EngineConfig::max_time_jump_us.
  double max_time_jump = 1.0;
  /// Map CSV (id,x,y; docs/import_formats.md) of markers, landmarks and beacons; a relative path
  /// is relative to the config file's directory. "" = no map (the daemon reads no other: a
  /// simulated run writes its world's markers with `lcmloc-sim --write-map`).
  std::string map_file;
  /// POSE after every N-th odometry message (and every measurement); the odometry in between is
  /// composed and applied with one time update (core::EngineConfig::output_every). 1 = every one.
  int output_every = 1;
  /// Landmark map for the three-landmark fix (`fusion.landmarks: [{id, x, y}, ...]`, local
  /// metres, x east, y north). Empty in the file: the top-level `landmarks` (lcmloc-vision's).
  std::map<int, core::Vec2> landmarks;
  /// The three-landmark fix (`fusion.landmark_fix`): its gate and its condition limit
  /// (max_condition; the other FixOptions keep their defaults).
  core::LandmarkFixGate fix_gate;
  core::landmark::FixOptions fix;
  /// Odometry gaps (core::EngineConfig::odometry_gap, docs/odometry_gap.md): consecutive
  /// odometry inputs of one channel more than this apart in message time, seq not following,
  /// are bridged by every filter [s]; 0 = off.
  double max_odometry_gap = 0.1;
  double odometry_gap_accel = 0.5;     ///< speed change rate the bridge allows, 1 sigma [m/s^2]
  double odometry_gap_yaw_rate = 0.05; ///< yaw-rate change the bridge allows, 1 sigma [rad/s]
  /// [s] The odometry sender's period (core::OdometryGapConfig::resume_period_us): a daemon
  /// started again from its checkpoint bridges the motion it did not see at the speed of its
  /// first increment over this period; 0 = not known (bridged at speed 0, covariance grown).
  double odometry_period = 0.01;
  /// Physical limits on the inputs (`fusion.limits`: max_speed, max_yaw_rate, max_steering;
  /// bus::LimitCheck): an input beyond them is refused by the daemon's intake.
  bus::InputLimits limits;
};

struct LoggerConfig {
  std::string output = "out/run.lcmlog";  ///< file-name pattern: strftime codes and {index}
  std::vector<std::string> channels;  ///< regexes; empty = everything
  int queue_capacity = 1000000;       ///< messages held for the writer thread
  int64_t queue_bytes = 512ll << 20;  ///< payload bytes held for the writer thread
  int64_t max_file_bytes = 0;         ///< start a new file before exceeding this size (0 = never)
  double max_file_seconds = 0;        ///< start a new file after this long [s, wall] (0 = never)
  double flush_period = 0.2;          ///< fsync period [s, wall]
  std::string status_channel = "LOGGER_STATUS";  ///< logger_status_t channel ("" = none)
  double status_period = 1.0;         ///< status period [s, wall]
  int recv_buf_size = 134217728;      ///< UDP receive buffer the logger sizes its sockets to [bytes]
};

/// A landmark of the map (`landmarks: [{id, x, y}, ...]`, local metres, x east, y north).
struct MapLandmark {
  int id = 0;
  double x = 0.0, y = 0.0;
};

/// What every process reads from the system file (the simulation's sections: SimSystemConfig).
struct SystemConfig {
  std::string file;                   ///< where it was read from
  ChannelConfig channels;
  FusionConfig fusion;
  LoggerConfig logger;
  bus::Datum datum;                        ///< origin of the local frame for lat/lon conversions
  /// The top-level `landmarks`, in the file's order: the world's landmarks (lcmloc-vision
  /// observes them), and fusion.landmarks when that is not given.
  std::vector<MapLandmark> landmarks;
};

/// Reads a system config file (its simulation sections accepted unread: loadSimSystemConfig
/// reads them). Missing sections take defaults; throws ConfigError.
SystemConfig loadSystemConfig(const std::string& path);
/// Throws ConfigError naming flag when output is one of inputs (what: "input log", "input file"):
/// the same file by device and inode, so also under another path, through a symbolic link or as
/// a hard link. Checked before anything is written: writing would destroy the input.
void refuseOutputOverInputs(const std::string& flag, const std::string& output,
                            const std::vector<std::string>& inputs, const std::string& what = "input file");

/// The text of a configuration file (what: "config file", "system file", ...): ConfigError when
/// it does not exist, is a directory or another non-regular file (/dev/zero was read until memory
/// ran out), is larger than 64 MB or cannot be read.
std::string readConfigFile(const std::string& path, const std::string& what = "config file");
/// Same from YAML text (file names the source in errors).
SystemConfig parseSystemConfig(const std::string& yaml_text, const std::string& file);
/// The YAML document of yaml_text: ConfigError naming file, line and column for a syntax error.
YAML::Node parseYamlText(const std::string& yaml_text, const std::string& file);

/// Filter parameters from a YAML map (used for `fusion.filter` and for FUSION_CONTROL's
/// parameters string), applied on top of base. Throws ConfigError.
/// The fusion engine's configuration from a system config (fusion.*): one conversion for the
/// daemon (and so the replay and lcmloc-evaluate).
core::EngineConfig engineConfig(const SystemConfig& cfg);
/// The keys of `fusion.sensors`: the `channels` key of each sensor input the daemon takes.
const std::vector<std::string>& sensorKeys();

core::FilterConfig parseFilterConfig(const YAML::Node& node, const core::FilterConfig& base,
                                     const std::string& file, const std::string& key_prefix);

/// A list of filter types (`fusion.shadow`, `lcmloc-replay --shadow`, the experiments' --filters):
/// each a known type, none twice (a shadow publishes on POSE_<TYPE>, an experiment writes one
/// track per filter). Throws ConfigError naming key[i].
void checkFilterList(const std::vector<std::string>& types, const std::string& file, const std::string& key);

}  // namespace lcmloc::app
