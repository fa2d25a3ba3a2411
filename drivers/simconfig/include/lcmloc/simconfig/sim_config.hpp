#pragma once
// The simulation's sections of the system file: `scenario`, `path`, `markers`, `vehicle`,
// `odometry`, `magruler`, `faults`, `imu`, `gps`, `vision` and `ins_sim` (what the simulated
// world, its sensors and the INS simulator are, and where lcmloc-gps takes its fixes from).
// The file stays one: parseSimSystemConfig reads these sections and everything
// parseSystemConfig (lcmloc_app) reads, each checked as strictly (ConfigError naming the file,
// the key path and the reason). lcmloc_app accepts these sections' names without reading them,
// so the fusion daemon and the logger do not link the simulator.
#include <string>

#include "lcmloc/app/config.hpp"
#include "lcmloc/sim/ins_sim.hpp"
#include "lcmloc/sim/scenario_config.hpp"

namespace lcmloc::simconfig {

inline constexpr app::Bounds kImuRateHz{0.1, 10000.0};         ///< imu.rate_hz, lcmloc-imu --rate
inline constexpr app::Bounds kVisionRateHz{1e-3, 1000.0};      ///< vision.rate_hz, lcmloc-vision --rate
inline constexpr app::Bounds kMarkerCount{0, 100000};          ///< markers.count, lcmloc-montecarlo --marker-spacing
inline constexpr app::Bounds kRealtimeFactor{0.0, 1e6};        ///< scenario.realtime_factor, --realtime-factor
inline constexpr app::Bounds kInsSimDuration{0.01, 1e6};       ///< ins_sim.duration [s], --duration
inline constexpr app::Bounds kOdometryScaleError{-0.5, 0.5};   ///< odometry.scale_error, montecarlo --scale-error
inline constexpr app::Bounds kOdometrySteeringBias{-0.5, 0.5}; ///< odometry.steering_bias [rad]

/// Where lcmloc-gps takes its fixes from (the `gps` section; the simulated receiver's model is
/// sim::GpsSensorConfig in the same section).
struct GpsDriverConfig {
  std::string source = "sim";         ///< "sim" (from GROUND_TRUTH) or "gpsd"
  std::string gpsd_host = "localhost";
  std::string gpsd_port = "2947";
  std::string time_source = "fix";    ///< gpsd: utime from the fix's time ("fix") or on receipt ("receive")
};

/// The whole system file: what every process reads (SystemConfig) and the simulation's sections.
struct SimSystemConfig : app::SystemConfig {
  /// The simulated world and its sensors; scenario.landmarks is the top-level `landmarks`
  /// (SystemConfig::landmarks, the landmarks lcmloc-vision observes).
  sim::ScenarioConfig scenario;
  GpsDriverConfig gps_driver;
  sim::InsSimConfig ins_sim;       ///< `ins_sim`: lcmloc-ins-sim and lcmloc-ins-experiment
};

/// Reads a system config file with its simulation sections. Missing sections take defaults;
/// throws ConfigError.
SimSystemConfig loadSimSystemConfig(const std::string& path);
/// Same from YAML text (file names the source in errors).
SimSystemConfig parseSimSystemConfig(const std::string& yaml_text, const std::string& file);

/// A simulated sensor samples GROUND_TRUTH: its rate (key) cannot be above vehicle.rate_hz.
/// Throws ConfigError.
void checkSampledRate(double rate_hz, const sim::ScenarioConfig& sc, const std::string& file,
                      const std::string& key);

}  // namespace lcmloc::simconfig
