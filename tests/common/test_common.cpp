// lcmloc_app, lcmloc_bus, lcmloc_drivers: YAML config, conversions, the typed LCM bus over memq://, process helpers.
#include <gtest/gtest.h>

#include <chrono>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <filesystem>
#include <limits>
#include <algorithm>
#include <utility>
#include <vector>

#include "lcmloc/app/config.hpp"
#include "lcmloc/drivers/sim_convert.hpp"
#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/files.hpp"
#include "lcmloc/app/heartbeat.hpp"
#include "lcmloc/app/log_throttle.hpp"
#include "lcmloc/app/pacer.hpp"
#include "lcmloc/bus/seq_tracker.hpp"
#include "lcmloc/app/text.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/fusion_control_t.hpp"
#include "lcmloc/heartbeat_t.hpp"
#include "lcmloc/imu_t.hpp"
#include "lcmloc/pose_t.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

using namespace lcmloc;
using app::ConfigError;

namespace {

/// The error of the whole file's reader (the simulation's sections too; with whole_file false, of
/// the reader every process uses, lcmloc_app's, which takes those sections unread), or "(no error)".
std::string errorOf(const std::string& yaml, const std::string& file = "test.yaml", bool whole_file = true) {
  try {
    if (whole_file)
      simconfig::parseSimSystemConfig(yaml, file);
    else
      app::parseSystemConfig(yaml, file);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}
std::string processErrorOf(const std::string& yaml) { return errorOf(yaml, "test.yaml", false); }

}  // namespace

// ---------------------------------------------------------------------------------------------
// Config

TEST(Config, PaperYamlSpellsOutTheDefaults) {
  const auto cfg = simconfig::loadSimSystemConfig(LCMLOC_PAPER_YAML);
  const simconfig::SimSystemConfig def;
  const auto& s = cfg.scenario;
  EXPECT_EQ(cfg.file, LCMLOC_PAPER_YAML);
  EXPECT_EQ(s.name, "paper");
  EXPECT_EQ(s.seed, def.scenario.seed);
  EXPECT_EQ(s.realtime_factor, def.scenario.realtime_factor);
  ASSERT_EQ(s.path.segments.size(), def.scenario.path.segments.size());
  for (std::size_t i = 0; i < s.path.segments.size(); ++i) {
    EXPECT_EQ(s.path.segments[i].length, def.scenario.path.segments[i].length);
    EXPECT_EQ(s.path.segments[i].curvature, def.scenario.path.segments[i].curvature);
  }
  EXPECT_EQ(s.path.theta0, def.scenario.path.theta0);
  EXPECT_EQ(s.markers.count, 20);
  EXPECT_EQ(s.markers.spacing, 2.0);
  EXPECT_EQ(s.vehicle.wheelbase, def.scenario.vehicle.wheelbase);
  EXPECT_EQ(s.vehicle.start_utime, def.scenario.vehicle.start_utime);
  EXPECT_EQ(s.odometry.steering_resolution, def.scenario.odometry.steering_resolution);
  EXPECT_EQ(s.magruler.num_sensors, 13);
  EXPECT_EQ(s.magruler.dipole_moment, def.scenario.magruler.dipole_moment);
  ASSERT_EQ(s.faults.size(), 2u);
  EXPECT_EQ(s.faults[0].kind, "phantom_marker");
  EXPECT_EQ(s.faults[1].at_distance, def.scenario.faults[1].at_distance);
  EXPECT_EQ(cfg.channels.magruler, def.channels.magruler);
  const auto& f = cfg.fusion.filter;
  const core::FilterConfig fd;
  EXPECT_EQ(f.type, "ukf_gated");
  EXPECT_EQ(f.p0_diag, fd.p0_diag);
  EXPECT_EQ(f.pw_diag, fd.pw_diag);
  EXPECT_EQ(f.pv_diag, fd.pv_diag);
  EXPECT_EQ(f.initial_pose, fd.initial_pose);
  EXPECT_EQ(f.sigma.kappa, fd.sigma.kappa);
  EXPECT_FALSE(f.gate.value.has_value());
  EXPECT_EQ(f.gate.probability, 0.99);
  EXPECT_EQ(f.steer_bias_rw, fd.steer_bias_rw);
  EXPECT_EQ(cfg.fusion.reorder_window, def.fusion.reorder_window);
  EXPECT_EQ(cfg.fusion.output_every, def.fusion.output_every);
  EXPECT_EQ(cfg.fusion.max_odometry_gap, def.fusion.max_odometry_gap);
  EXPECT_EQ(cfg.fusion.odometry_gap_accel, def.fusion.odometry_gap_accel);
  EXPECT_EQ(cfg.fusion.odometry_gap_yaw_rate, def.fusion.odometry_gap_yaw_rate);
  EXPECT_EQ(cfg.logger.queue_capacity, def.logger.queue_capacity);
}

TEST(Config, EmptyFileGivesDefaultsAndOverridesApply) {
  const auto empty = simconfig::parseSimSystemConfig("", "empty.yaml");
  EXPECT_EQ(empty.scenario.markers.count, 20);
  EXPECT_EQ(empty.fusion.filter.type, "ukf_gated");

  const auto c = simconfig::parseSimSystemConfig(R"(
scenario: {seed: 42, realtime_factor: 10}
faults: []
fusion:
  filter: {type: ukf, gate: {value: 6.635, dof: 1}, p0_diag: [1, 2, 3]}
  shadow: [dead_reckoning]
logger: {channels: ["POSE.*", GATE]}
)", "o.yaml");
  EXPECT_EQ(c.scenario.seed, 42u);
  EXPECT_EQ(c.scenario.realtime_factor, 10.0);
  EXPECT_TRUE(c.scenario.faults.empty());
  EXPECT_EQ(c.fusion.filter.type, "ukf");
  ASSERT_TRUE(c.fusion.filter.gate.value.has_value());
  EXPECT_DOUBLE_EQ(*c.fusion.filter.gate.value, 6.635);
  EXPECT_EQ(c.fusion.filter.gate.dof, 1);
  EXPECT_EQ(c.fusion.filter.p0_diag, core::Vec3(1, 2, 3));
  EXPECT_EQ(c.fusion.filter.wheelbase, 2.5);  // untouched keys keep their defaults
  EXPECT_EQ(c.fusion.shadow, std::vector<std::string>{"dead_reckoning"});
  EXPECT_EQ(c.logger.channels, (std::vector<std::string>{"POSE.*", "GATE"}));
}

// One file, read by each process for the sections it needs: the reader every process uses
// (lcmloc_app) takes the simulation's sections by name without reading them, and refuses a
// top-level key that is no section, as the whole file's reader (lcmloc_simconfig) does, with the
// same list of valid keys; the whole file's reader refuses what is wrong in the simulation's.
TEST(Config, TheProcessesReaderAcceptsTheSimulationSectionsUnread) {
  const std::string wrong_in_each =
      "scenario: {realtime_factor: -1}\npath: 3\nmarkers: {count: -1}\nvehicle: {speed: fast}\nodometry: {rate_hz: 1000}\n"
      "magruler: {num_sensors: 1}\nfaults: [{kind: gremlin}]\nimu: {rate_hz: 0}\ngps: {gpsd_port: abc}\n"
      "ins_sim: {profile: nope}\nvision: {rate_hz: -1}\n";
  EXPECT_EQ(processErrorOf(wrong_in_each), "(no error)");
  EXPECT_NE(errorOf(wrong_in_each), "(no error)");
  std::size_t start = 0;
  for (std::size_t end; (end = wrong_in_each.find('\n', start)) != std::string::npos; start = end + 1) {
    const std::string line = wrong_in_each.substr(start, end - start);
    const std::string section = line.substr(0, line.find(':'));
    EXPECT_EQ(processErrorOf(line), "(no error)") << line;
    EXPECT_EQ(errorOf(line).rfind("test.yaml: " + section, 0), 0u) << line << " -> " << errorOf(line);
  }
  const std::string unknown = processErrorOf("vehicel: {speed: 1}");
  EXPECT_EQ(unknown.rfind("test.yaml: vehicel: unknown key (valid keys: scenario, path, markers, vehicle, odometry, "
                          "magruler, faults, imu, gps, datum, channels, fusion, logger, ins_sim, vision, landmarks)", 0),
            0u) << unknown;
  EXPECT_EQ(errorOf("vehicel: {speed: 1}"), unknown);
  // A section the process reads is checked as before, whatever the simulation's sections hold.
  EXPECT_EQ(processErrorOf("vehicle: {speed: fast}\nfusion: {output_every: 0}").rfind("test.yaml: fusion.output_every", 0),
            0u);
}

// The fusion's landmark map comes from the part of the file every process reads: the top-level
// `landmarks` (the world's, which lcmloc-vision observes) when fusion.landmarks is not given.
TEST(Config, TheTopLevelLandmarksAreTheFusionsWithoutTheSimulator) {
  const std::string yaml = "landmarks: [{id: 7, x: 10.5, y: -2}, {id: 2, x: 0, y: 40}]\n";
  const auto c = app::parseSystemConfig(yaml, "l.yaml");
  ASSERT_EQ(c.landmarks.size(), 2u);
  EXPECT_EQ(c.landmarks[0].id, 7);  // file order kept
  ASSERT_EQ(c.fusion.landmarks.size(), 2u);
  EXPECT_EQ(c.fusion.landmarks.at(7), core::Vec2(10.5, -2.0));
  EXPECT_EQ(c.fusion.landmarks.at(2), core::Vec2(0.0, 40.0));
  const auto own = app::parseSystemConfig(yaml + "fusion: {landmarks: [{id: 1, x: 1, y: 1}]}", "l.yaml");
  EXPECT_EQ(own.fusion.landmarks.size(), 1u);  // fusion.landmarks given: that one
  const auto sim = simconfig::parseSimSystemConfig(yaml, "l.yaml");
  ASSERT_EQ(sim.scenario.landmarks.size(), 2u);
  EXPECT_EQ(sim.scenario.landmarks[1].id, 2);
  EXPECT_EQ(sim.scenario.landmarks[1].y, 40.0);
  EXPECT_NE(processErrorOf("landmarks: [{id: 1, x: 0, y: 0}, {id: 1, x: 5, y: 5}]").find("landmarks[1].id: duplicate"),
            std::string::npos);
}

TEST(Config, UnknownKeyNamesFileKeyPathAndValidKeys) {
  EXPECT_EQ(errorOf("bogus: 1").rfind("test.yaml: bogus: unknown key (valid keys: scenario, path,", 0), 0u)
      << errorOf("bogus: 1");
  const std::string nested = errorOf("vehicle: {wheelbas: 2.0}");
  EXPECT_NE(nested.find("test.yaml: vehicle.wheelbas: unknown key"), std::string::npos) << nested;
  EXPECT_NE(nested.find("wheelbase"), std::string::npos) << nested;
  const std::string deep = errorOf("fusion: {filter: {gate: {treshold: 3}}}");
  EXPECT_NE(deep.find("test.yaml: fusion.filter.gate.treshold: unknown key"), std::string::npos) << deep;
  const std::string in_list = errorOf("faults: [{kind: wrong_offset, at: 3}]");
  EXPECT_NE(in_list.find("faults[0].at: unknown key"), std::string::npos) << in_list;
}

// fusion.filter.calibration: each state switched on by its key with its prior and random walk;
// off by default; a value outside its range or an unknown mode names the key.
TEST(Config, CalibrationKeysOfTheLandmarkFilter) {
  using BB = lcmloc::core::FilterConfig::Calibration::BeaconBias;
  EXPECT_FALSE(app::parseSystemConfig("", "c.yaml").fusion.filter.calibration.any());
  const auto c = app::parseSystemConfig(
      "fusion: {filter: {type: ukf_landmarks, calibration: {beacon_bias: per_beacon, beacon_bias_std: 0.3, "
      "odo_scale: true, odo_scale_mean: 0.02, odo_scale_rw: 0.001, yaw_rate_scale: true, yaw_rate_scale_std: 0.4, "
      "yaw_rate_bias: true, yaw_rate_bias_std: 0.02}}}",
      "c.yaml").fusion.filter.calibration;
  EXPECT_EQ(c.beacon_bias, BB::PerBeacon);
  EXPECT_EQ(c.beacon_bias_std, 0.3);
  EXPECT_TRUE(c.odo_scale && c.yaw_rate_scale && c.yaw_rate_bias);
  EXPECT_EQ(c.odo_scale_mean, 0.02);
  EXPECT_EQ(c.odo_scale_rw, 0.001);
  EXPECT_EQ(c.yaw_rate_scale_std, 0.4);
  EXPECT_EQ(c.yaw_rate_bias_std, 0.02);
  EXPECT_EQ(app::parseSystemConfig("fusion: {filter: {calibration: {beacon_bias: shared}}}", "c.yaml")
                .fusion.filter.calibration.beacon_bias, BB::Shared);
  EXPECT_NE(processErrorOf("fusion: {filter: {calibration: {beacon_bias: each}}}")
                .find("fusion.filter.calibration.beacon_bias: 'each' is not one of off, shared, per_beacon"),
            std::string::npos);
  EXPECT_NE(processErrorOf("fusion: {filter: {calibration: {odo_scale_std: 0}}}")
                .find("fusion.filter.calibration.odo_scale_std: value 0 out of range"),
            std::string::npos);
  EXPECT_NE(processErrorOf("fusion: {filter: {calibration: {yaw_rate_bias_rw: -1}}}")
                .find("fusion.filter.calibration.yaw_rate_bias_rw"),
            std::string::npos);
}

// yaml-cpp reads the first of two equal keys and drops the other without a word: a second
// `scenario:` appended to a file, or a flow map with `type` twice, was silently ignored.
TEST(Config, AKeyGivenTwiceIsAnError) {
  EXPECT_EQ(errorOf("scenario: {name: a}\nvehicle: {speed: 1}\nscenario: {name: b, seed: 7}\n"),
            "test.yaml: scenario: given twice in one map (again at line 3)");
  EXPECT_EQ(errorOf("fusion: {filter: {type: ukf, type: dead_reckoning}}"),
            "test.yaml: fusion.filter.type: given twice in one map (again at line 1)");
  EXPECT_NE(errorOf("faults: [{kind: phantom_marker, kind: wrong_offset, at_distance: 3}]").find("faults[0].kind: given twice"),
            std::string::npos);
  EXPECT_EQ(errorOf("fusion: {shadow: [ukf, dead_reckoning, ukf]}"),
            "test.yaml: fusion.shadow[2]: 'ukf' is listed twice");
  // Equal values under different maps are fine.
  EXPECT_EQ(errorOf("vehicle: {speed: 1}\nodometry: {rate_hz: 100}\nimu: {rate_hz: 100}\n"), "(no error)");
}

// The simulated sensors sample GROUND_TRUTH: a rate above it was accepted and logged ("ODOMETRY
// at 1000 Hz") while the driver published at the truth's 100 Hz.
TEST(Config, ASensorRateAboveTheGroundTruthRateIsAnError) {
  EXPECT_EQ(errorOf("odometry: {rate_hz: 1000}"),
            "test.yaml: odometry.rate_hz: 1000 Hz is above the ground-truth rate vehicle.rate_hz (100 Hz) the "
            "sensor samples: it would publish at 100 Hz");
  EXPECT_NE(errorOf("imu: {rate_hz: 200}").find("imu.rate_hz: 200 Hz is above"), std::string::npos);
  EXPECT_NE(errorOf("magruler: {publish_rate_hz: 150}").find("magruler.publish_rate_hz: 150 Hz"), std::string::npos);
  EXPECT_EQ(errorOf("vehicle: {rate_hz: 1000}\nodometry: {rate_hz: 1000}\nimu: {rate_hz: 500}"), "(no error)");
}

// What only the filter judges (p0_diag > 0 where the key's range allows 0): its own check at load
// time, with the file and key named (it said "filter config: p0_diag must be > 0", exit 1, when
// the daemon built the filter).
TEST(Config, TheFiltersOwnChecksRunWhenTheConfigIsRead) {
  EXPECT_EQ(errorOf("fusion: {filter: {p0_diag: [0, 0, 0]}}"), "test.yaml: fusion.filter: p0_diag must be > 0");
  EXPECT_EQ(errorOf("fusion: {filter: {p0_diag: [1.0e-2, 1.0e-2, 1.0e-2]}}"), "(no error)");
}

// gps.gpsd_port was taken as any string and failed only when lcmloc-gps connected.
TEST(Config, TheGpsdPortIsANumber) {
  EXPECT_EQ(errorOf("gps: {gpsd_port: abc}"), "test.yaml: gps.gpsd_port: 'abc' is not a TCP port number (1-65535; gpsd's is 2947)");
  EXPECT_NE(errorOf("gps: {gpsd_port: 70000}").find("gps.gpsd_port: '70000' is not a TCP port"), std::string::npos);
  EXPECT_EQ(errorOf("gps: {gpsd_port: 2948}"), "(no error)");
}

TEST(Config, WrongTypeAndRangeAreClear) {
  const std::string t = errorOf("vehicle: {speed: fast}");
  EXPECT_EQ(t, "test.yaml: vehicle.speed: expected a number, got 'fast'");
  EXPECT_NE(errorOf("markers: {count: 2.5}").find("markers.count: expected an integer"), std::string::npos);
  EXPECT_NE(errorOf("markers: {count: -1}").find("markers.count: value -1 out of range"), std::string::npos);
  EXPECT_NE(errorOf("vehicle: 3").find("vehicle: expected a map"), std::string::npos);
  EXPECT_NE(errorOf("fusion: {filter: {p0_diag: [1, 2]}}").find("fusion.filter.p0_diag: expected a list of 3"),
            std::string::npos);
  const std::string type = errorOf("fusion: {filter: {type: ekf}}");
  EXPECT_NE(type.find("fusion.filter.type: unknown filter type 'ekf' (valid: "), std::string::npos) << type;
  EXPECT_NE(type.find("ukf_gated"), std::string::npos);
  EXPECT_NE(errorOf("faults: [{kind: gremlin}]").find("faults[0].kind: unknown fault kind"), std::string::npos);
  EXPECT_NE(errorOf("vehicle: {speed: .nan}").find("expected a finite number"), std::string::npos);
  EXPECT_NE(errorOf("scenario: [1").find("test.yaml: YAML syntax error at line"), std::string::npos);
}

TEST(Config, OutputEveryIsAPositiveInteger) {
  EXPECT_EQ(app::parseSystemConfig("", "e.yaml").fusion.output_every, 1);
  EXPECT_EQ(app::parseSystemConfig("fusion: {output_every: 10}", "o.yaml").fusion.output_every, 10);
  EXPECT_NE(errorOf("fusion: {output_every: 0}").find("test.yaml: fusion.output_every: value 0 out of range"),
            std::string::npos) << errorOf("fusion: {output_every: 0}");
  EXPECT_NE(errorOf("fusion: {output_every: 2.5}").find("fusion.output_every: expected an integer"),
            std::string::npos);
}

// A reorder window as wide as the time-jump guard: a late input within the window was refused
// as "too old" all the same (a live test's widened window did this under load).
TEST(Config, TheReorderWindowIsNarrowerThanTheTimeJumpGuard) {
  EXPECT_EQ(errorOf("fusion: {reorder_window: 2.0}"),
            "test.yaml: fusion.reorder_window: 2 s is not less than fusion.max_time_jump (1 s): an input that late is "
            "taken for a new time base, not reordered (widen max_time_jump with it, or 0 = off)");
  EXPECT_NE(errorOf("fusion: {reorder_window: 1.0}"), "(no error)");
  EXPECT_EQ(errorOf("fusion: {reorder_window: 2.0, max_time_jump: 5.0}"), "(no error)");
  EXPECT_EQ(errorOf("fusion: {reorder_window: 2.0, max_time_jump: 0}"), "(no error)");
  EXPECT_EQ(errorOf("fusion: {reorder_window: 0.99}"), "(no error)");
}

// fusion.sensors: each sensor's expected delay widens the horizon (engineConfig maps the key to
// its channels); a delay that is negative, beyond the horizon's memory bound (fusion.max_horizon)
// or at the time-jump guard, an unknown sensor key or a reorder window beyond the bound is an
// error naming the key.
TEST(Config, SensorDelaysSetTheHorizonWithinItsMemoryBound) {
  const auto c = app::parseSystemConfig(
      "channels: {magruler: [RULER_A, RULER_B]}\n"
      "fusion: {sensors: {gps: {delay: 0.2, period: 0.1}, magruler: {delay: 0.08}}, max_queued: 500}", "s.yaml");
  EXPECT_DOUBLE_EQ(c.fusion.horizon(), 0.2);
  const core::EngineConfig ec = app::engineConfig(c);
  EXPECT_EQ(ec.horizonUs(), 200000);
  EXPECT_EQ(ec.max_queued, 500u);
  ASSERT_EQ(ec.sensors.size(), 3u);
  EXPECT_EQ(ec.sensors.at("GPS").delay_us, 200000);
  EXPECT_EQ(ec.sensors.at("GPS").period_us, 100000);
  EXPECT_EQ(ec.sensors.at("RULER_B").delay_us, 80000);
  EXPECT_EQ(ec.sensors.at("RULER_B").period_us, 0);
  // The defaults: no sensor, the horizon is the reorder window.
  const auto d = app::parseSystemConfig("", "d.yaml");
  EXPECT_TRUE(app::engineConfig(d).sensors.empty());
  EXPECT_EQ(app::engineConfig(d).horizonUs(), app::engineConfig(d).reorder_window_us);

  EXPECT_EQ(errorOf("fusion: {sensors: {gps: {delay: -0.1}}}"),
            "test.yaml: fusion.sensors.gps.delay: value -0.1 out of range [0, 2] (0 to fusion.max_horizon: the "
            "horizon's memory bound)");
  EXPECT_EQ(errorOf("fusion: {sensors: {vision: {delay: 2.5}}, max_time_jump: 10}"),
            "test.yaml: fusion.sensors.vision.delay: value 2.5 out of range [0, 2] (0 to fusion.max_horizon: the "
            "horizon's memory bound)");
  EXPECT_EQ(errorOf("fusion: {sensors: {vision: {delay: 2.5}}, max_time_jump: 10, max_horizon: 3}"), "(no error)");
  EXPECT_EQ(errorOf("fusion: {sensors: {gps: {delay: 1.5}}}"),
            "test.yaml: fusion.sensors.gps.delay: 1.5 s is not less than fusion.max_time_jump (1 s): an input that "
            "late is taken for a new time base (widen max_time_jump with it, or 0 = off)");
  EXPECT_EQ(errorOf("fusion: {reorder_window: 3, max_time_jump: 10}"),
            "test.yaml: fusion.reorder_window: 3 s is more than fusion.max_horizon (2 s), the horizon's memory bound");
  EXPECT_NE(errorOf("fusion: {sensors: {sonar: {delay: 0.1}}}").find("fusion.sensors.sonar: unknown key"),
            std::string::npos);
  EXPECT_NE(errorOf("fusion: {sensors: {gps: {lag: 0.1}}}").find("fusion.sensors.gps.lag: unknown key"),
            std::string::npos);
  EXPECT_NE(errorOf("fusion: {max_queued: 0}").find("fusion.max_queued: value 0 out of range"), std::string::npos);
  EXPECT_NE(errorOf("fusion: {sensors: {gps: {period: -1}}}").find("fusion.sensors.gps.period: value -1 out of range"),
            std::string::npos);
}

TEST(Config, OdometryGapKeysAreCheckedAndNamed) {
  const auto c = app::parseSystemConfig("fusion: {max_odometry_gap: 0.5, odometry_gap_accel: 1.0, odometry_gap_yaw_rate: 0.1}", "g.yaml");
  EXPECT_EQ(c.fusion.max_odometry_gap, 0.5);
  EXPECT_EQ(c.fusion.odometry_gap_accel, 1.0);
  EXPECT_EQ(c.fusion.odometry_gap_yaw_rate, 0.1);
  EXPECT_EQ(app::parseSystemConfig("fusion: {max_odometry_gap: 0}", "g.yaml").fusion.max_odometry_gap, 0.0);
  EXPECT_NE(errorOf("fusion: {max_odometry_gap: -1}").find("test.yaml: fusion.max_odometry_gap: value -1 out of range"),
            std::string::npos) << errorOf("fusion: {max_odometry_gap: -1}");
  EXPECT_NE(errorOf("fusion: {odometry_gap_accel: .nan}").find("test.yaml: fusion.odometry_gap_accel: expected a finite number"),
            std::string::npos) << errorOf("fusion: {odometry_gap_accel: .nan}");
  EXPECT_NE(errorOf("fusion: {odometry_gap_yaw_rate: x}").find("test.yaml: fusion.odometry_gap_yaw_rate"),
            std::string::npos);
}

// The resume period is the fusion's own setting, not the simulated odometry's rate.
TEST(Config, TheResumePeriodIsAFusionSettingNotTheSimulatorsRate) {
  const auto c = app::parseSystemConfig("odometry: {rate_hz: 50}\nfusion: {odometry_period: 0.02}", "g.yaml");
  EXPECT_EQ(app::engineConfig(c).odometry_gap.resume_period_us, 20000);
  const auto d = app::parseSystemConfig("odometry: {rate_hz: 50}", "g.yaml");
  EXPECT_EQ(app::engineConfig(d).odometry_gap.resume_period_us, 10000);  // the default, whatever the simulator
  EXPECT_EQ(app::engineConfig(app::parseSystemConfig("fusion: {odometry_period: 0}", "g.yaml"))
                .odometry_gap.resume_period_us, 0);
  EXPECT_NE(errorOf("fusion: {odometry_period: -0.01}").find("test.yaml: fusion.odometry_period: value -0.01 out of range"),
            std::string::npos) << errorOf("fusion: {odometry_period: -0.01}");
}

// Lists of maps (GPS outages and jumps, INS motion segments and IMU dropouts): read item by
// item; not a list, an unknown key in an item and an out-of-range value name the item.
TEST(Config, ListsOfMapsAreReadItemByItemWithClearErrors) {
  const auto cfg = simconfig::parseSimSystemConfig(
      "gps: {outages: [{start: 5, duration: 2}, {start: 30, duration: 1}], jumps: [{at: 10, duration: 3, dx: 4, dy: -1}]}\n"
      "ins_sim: {imu_dropouts: [{start: 1, duration: 0.5}]}\n",
      "l.yaml");
  ASSERT_EQ(cfg.scenario.gps.outages.size(), 2u);
  EXPECT_EQ(cfg.scenario.gps.outages[1].start, 30.0);
  ASSERT_EQ(cfg.scenario.gps.jumps.size(), 1u);
  EXPECT_EQ(cfg.scenario.gps.jumps[0].dy, -1.0);
  ASSERT_EQ(cfg.ins_sim.imu_dropouts.size(), 1u);
  EXPECT_EQ(cfg.ins_sim.imu_dropouts[0].second, 0.5);
  EXPECT_NE(errorOf("gps: {outages: 5}").find("gps.outages: expected a list of {start, duration}, got '5'"),
            std::string::npos)
      << errorOf("gps: {outages: 5}");
  EXPECT_NE(errorOf("gps: {jumps: [{at: 1, dz: 2}]}").find("gps.jumps[0]"), std::string::npos)
      << errorOf("gps: {jumps: [{at: 1, dz: 2}]}");
  EXPECT_NE(errorOf("ins_sim: {segments: [{duration: 1}, {duration: -1}]}").find("ins_sim.segments[1].duration"),
            std::string::npos)
      << errorOf("ins_sim: {segments: [{duration: 1}, {duration: -1}]}");
}

TEST(Config, MissingFileNamesTheFile) {
  try {
    app::loadSystemConfig("/nonexistent/dir/scenario.yaml");
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), "/nonexistent/dir/scenario.yaml: cannot open config file (does it exist?)");
  }
}

TEST(Config, ADirectoryOrADeviceIsNoConfigFile) {
  // A directory was read as an empty file (all defaults, exit 0); /dev/zero until memory ran out.
  auto errorLoading = [](const std::string& path) -> std::string {
    try {
      app::loadSystemConfig(path);
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "(no error)";
  };
  EXPECT_EQ(errorLoading("/tmp"), "/tmp: is a directory: not a config file");
  EXPECT_EQ(errorLoading("/dev/zero"), "/dev/zero: is not a regular file: not a config file");
}

TEST(Config, ChannelNamesAreNonEmptyAndTheDaemonsOutputsHaveChannelsOfTheirOwn) {
  // An empty POSE channel made the replay write events a log reader cannot read back; POSE on
  // ODOMETRY made the daemon read its own estimates as odometry (1 of 3116 inputs used).
  EXPECT_NE(errorOf("channels: {pose: \"\"}\n").find("channels.pose: a channel name must be non-empty"),
            std::string::npos);
  EXPECT_NE(errorOf("channels: {magruler: [MAGRULER, \"A B\"]}\n").find("channels.magruler[1]"), std::string::npos);
  EXPECT_NE(errorOf("channels: {pose: ODOMETRY}\n").find("channels.pose: 'ODOMETRY' is also channels.odometry"),
            std::string::npos);
  EXPECT_NE(errorOf("channels: {status: GATE}\n").find("channels.gate: 'GATE' is also channels.status"), std::string::npos);
  EXPECT_NE(errorOf("channels: {control: MAGRULER}\n").find("channels.control: 'MAGRULER' is also channels.magruler[0]"),
            std::string::npos);
  EXPECT_EQ(errorOf("channels: {pose: POSE_MAIN, magruler: [R1, R2, R3], magruler_fault: R3}\n"), "(no error)");
}

TEST(Process, AnExistingOutputIsRefusedWithoutOverwrite) {
  namespace fs = std::filesystem;
  const fs::path base = fs::temp_directory_path() / ("lcmloc_refuse_" + std::to_string(::getpid()));
  fs::remove_all(base);
  fs::create_directories(base / "empty");
  fs::create_directories(base / "full");
  std::ofstream((base / "full" / "report.json").string()) << "{}";
  std::ofstream((base / "file.lcmlog").string()) << "x";
  // Nothing there, or an empty directory: nothing to replace.
  EXPECT_NO_THROW(app::refuseExistingOutput((base / "new.lcmlog").string(), false));
  EXPECT_NO_THROW(app::refuseExistingOutput((base / "empty").string(), false));
  EXPECT_NO_THROW(app::refuseExistingOutput("", false));
  EXPECT_NO_THROW(app::refuseExistingOutput("/dev/null", false));  // a device is written to, not replaced
  try {
    app::refuseExistingOutput((base / "file.lcmlog").string(), false, "--log");
    ADD_FAILURE() << "an existing file was accepted";
  } catch (const app::UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("--log '" + (base / "file.lcmlog").string() + "' exists: give --overwrite"),
              std::string::npos) << e.what();
  }
  EXPECT_THROW(app::refuseExistingOutput((base / "full").string(), false), app::UsageError);
  EXPECT_THROW(app::prepareOutputDir((base / "full").string(), false), app::UsageError);
  EXPECT_NO_THROW(app::refuseExistingOutput((base / "file.lcmlog").string(), true));
  EXPECT_NO_THROW(app::prepareOutputDir((base / "full").string(), true));
  EXPECT_TRUE(fs::exists(base / "full" / "report.json"));  // --overwrite replaces files; it deletes none
  fs::remove_all(base);
}

TEST(Process, RunProcessGivesTheSharedExitCodesVersionAndFooter) {
  auto run = [](std::vector<std::string> args, const std::function<int()>& body, std::string* help = nullptr) {
    CLI::App app{"test program"};
    app::CommonOptions opts;
    opts.log_level = "off";
    std::string out;
    app::addOutputOption(app, out, "output");
    args.insert(args.begin(), "prog");
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    testing::internal::CaptureStdout();
    const int rc = app::runProcess(app, static_cast<int>(argv.size()), argv.data(), opts, "lcmloc-test", body);
    const std::string printed = testing::internal::GetCapturedStdout();
    if (help) *help = printed;
    return rc;
  };
  auto ok = [] { return app::kExitOk; };
  std::string printed;
  EXPECT_EQ(run({"--version"}, ok, &printed), 0);
  EXPECT_EQ(printed, "lcmloc-test " + app::version() + "\n");
  EXPECT_EQ(run({"--help"}, ok, &printed), 0);
  EXPECT_NE(printed.find(app::kExitCodesHelp), std::string::npos) << printed;
  EXPECT_NE(printed.find("-o,--output"), std::string::npos) << printed;
  EXPECT_EQ(run({"--bogus"}, ok), app::kExitUsageError);
  EXPECT_EQ(run({}, [] () -> int { throw app::UsageError("no"); }), 2);
  EXPECT_EQ(run({}, [] () -> int { throw app::ConfigError("f.yaml", "k", "bad"); }), 2);
  EXPECT_EQ(run({}, [] () -> int { throw std::runtime_error("disk full"); }), 1);
  EXPECT_EQ(run({}, [] { return app::kExitInputDamaged; }), 3);
  EXPECT_EQ(app::kExitOk, 0);
  EXPECT_EQ(app::kExitRuntimeError, 1);
  EXPECT_EQ(app::kExitConfigError, 2);
  EXPECT_EQ(app::kExitInputDamaged, 3);
}

TEST(Process, AnOutputDirectoryIsCheckedBeforeTheWork) {
  // The experiments computed everything and then failed to create --output.
  namespace fs = std::filesystem;
  const fs::path base = fs::temp_directory_path() / ("lcmloc_outdir_" + std::to_string(::getpid()));
  fs::remove_all(base);
  fs::create_directories(base);
  app::prepareOutputDir((base / "a" / "b").string(), false);
  EXPECT_TRUE(fs::is_directory(base / "a" / "b"));
  EXPECT_TRUE(fs::is_empty(base / "a" / "b"));  // the probe is removed
  std::ofstream((base / "file").string()) << "x";
  try {
    app::prepareOutputDir((base / "file" / "sub").string(), true);
    ADD_FAILURE() << "a directory under a file was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("output directory '" + (base / "file" / "sub").string() + "'"), std::string::npos)
        << e.what();
  }
  fs::remove_all(base);
}

TEST(Config, FilterParametersFromAControlString) {
  const core::FilterConfig base;
  const auto c = app::parseFilterConfig(YAML::Load("{type: ukf_calib, scale_std0: 0.05}"), base,
                                           "FUSION_CONTROL", "parameters");
  EXPECT_EQ(c.type, "ukf_calib");
  EXPECT_EQ(c.scale_std0, 0.05);
  EXPECT_THROW(app::parseFilterConfig(YAML::Load("{kapa: 1}"), base, "FUSION_CONTROL", "parameters"),
               ConfigError);
}

// ---------------------------------------------------------------------------------------------
// Conversions

TEST(Convert, OdometryRejectsNaNInfAndOutOfRange) {
  lcmloc::odometry_t m{};
  m.utime = 1000;
  m.seq = 3;
  m.delta_s = 0.015;
  m.steering = 0.1;
  m.has_steering = true;
  std::string why;
  auto ok = bus::toCore(m, &why);
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->utime, 1000);
  EXPECT_EQ(ok->delta_s, 0.015);
  EXPECT_TRUE(ok->has_steering);

  auto bad = m;
  bad.delta_s = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(bus::toCore(bad, &why));
  EXPECT_EQ(why, "delta_s is NaN");
  bad = m;
  bad.steering = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(bus::toCore(bad, &why));
  EXPECT_EQ(why, "steering is Inf");
  bad = m;
  bad.steering = 1.6;
  EXPECT_FALSE(bus::toCore(bad, &why));
  EXPECT_NE(why.find("steering"), std::string::npos);
  bad = m;
  bad.utime = -5;
  EXPECT_FALSE(bus::toCore(bad, &why));
  EXPECT_NE(why.find("utime"), std::string::npos);
}

TEST(Convert, RulerDetectionsOnlyAndValidated) {
  sim::RulerReading r;
  r.utime = 2000;
  r.readings.assign(13, -0.45);
  r.detected = true;
  r.lateral_offset = -0.123;
  r.quality = 0.8;
  const auto m = drivers::toLcm(r, 7);
  EXPECT_EQ(m.num_sensors, 13);
  std::string why = "x";
  auto d = bus::toCore(m, "MAGRULER_FAULT", &why);
  ASSERT_TRUE(d);
  EXPECT_EQ(d->lateral_offset, -0.123);
  EXPECT_EQ(d->sensor, "MAGRULER_FAULT");
  EXPECT_EQ(d->seq, 7);

  auto none = m;
  none.detected = false;
  EXPECT_FALSE(bus::toCore(none, "MAGRULER", &why));
  EXPECT_TRUE(why.empty());
  auto nan = m;
  nan.readings[4] = std::nan("");
  EXPECT_FALSE(bus::toCore(nan, "MAGRULER", &why));
  EXPECT_EQ(why, "readings[4] is NaN");
  auto q = m;
  q.quality = 1.5;
  EXPECT_FALSE(bus::toCore(q, "MAGRULER", &why));
  EXPECT_NE(why.find("quality"), std::string::npos);
}

namespace {
/// pose_t::encode's bytes of toLcm(s, filter, seq): what encodePose must give.
std::vector<uint8_t> lcmGenBytes(const core::FilterState& s, const std::string& filter, int64_t seq) {
  const lcmloc::pose_t m = bus::toLcm(s, filter, seq);
  std::vector<uint8_t> b(static_cast<std::size_t>(m.getEncodedSize()));
  const int size = m.encode(b.data(), 0, static_cast<int>(b.size()));
  EXPECT_GT(size, 0);
  // (shorter than getEncodedSize() only for a string with a NUL inside: getEncodedSize counts
  // all of it, encode writes it up to the NUL)
  b.resize(static_cast<std::size_t>(std::max(size, 0)));
  return b;
}
}  // namespace

TEST(Convert, EncodePoseGivesLcmGensBytesForEveryShapeOfState) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::pair<core::FilterState, std::string>> cases;
  core::FilterState s;
  s.utime = -7;  // negative and large values: the byte order of every field shows
  s.x = Eigen::Vector3d(1.5, -2.25e7, 3.1);
  s.P = Eigen::Matrix3d::Random();
  s.names = {"x", "y", "theta"};
  s.status = core::FilterStatus::DeadReckoning;
  cases.push_back({s, "ukf_gated"});
  s.x = Eigen::VectorXd::LinSpaced(5, -1.0, 1.0);
  s.P = Eigen::MatrixXd::Random(5, 5);
  s.P(4, 0) = nan;
  s.names = {"x", "y", "theta", "odo_scale", "steer_bias"};
  s.status = core::FilterStatus::Lockout;
  cases.push_back({s, "ukf_calib"});
  s.names = {"x", "y"};  // fewer names than states: "s2".. like toLcm
  s.P = Eigen::MatrixXd::Random(3, 2);  // a P smaller than x: zeros beyond it
  cases.push_back({s, ""});
  s.x.resize(12);
  s.x.setConstant(-0.0);
  s.P = Eigen::MatrixXd::Identity(12, 12);
  s.names.assign(12, std::string("a\0b", 3));  // lcm-gen encodes a string up to its first NUL
  cases.push_back({s, "long_filter_name_for_a_shadow"});
  s.x.resize(0);
  s.P.resize(0, 0);
  s.names.clear();
  cases.push_back({s, "empty"});

  std::vector<uint8_t> out;  // reused, as the daemon does: a smaller state after a larger one
  int64_t seq = 1LL << 40;
  for (const auto& [state, filter] : cases) {
    const std::size_t size = bus::encodePose(state, filter, seq, out);
    const auto want = lcmGenBytes(state, filter, seq);
    ASSERT_EQ(size, want.size()) << filter;
    EXPECT_TRUE(std::equal(want.begin(), want.end(), out.begin())) << filter;
    lcmloc::pose_t back;
    ASSERT_EQ(back.decode(out.data(), 0, static_cast<int>(size)), static_cast<int>(size)) << filter;
    EXPECT_EQ(back.seq, seq);
    EXPECT_EQ(back.filter, filter);
    ++seq;
  }
}

TEST(Convert, ImuSamplesBeyondAnySensorsRangeAreRefused) {
  // A finite but absurd sample (a corrupt message) used to reach the filters: accel 1e200 made
  // tvekf's state infinite, and the next switch or set_pose stopped the daemon.
  lcmloc::imu_t m{};
  m.utime = 1000;
  m.accel[2] = 9.81;
  m.gyro[2] = 0.1;
  m.mag[0] = 0.2;
  std::string why;
  ASSERT_TRUE(bus::toCore(m, "IMU", &why)) << why;
  auto strong = m;  // a hard hit and a fast spin are still samples
  strong.accel[0] = -150.0;
  strong.gyro[2] = 30.0;
  EXPECT_TRUE(bus::toCore(strong, "IMU", &why)) << why;
  auto a = m;
  a.accel[0] = 1e200;
  EXPECT_FALSE(bus::toCore(a, "IMU", &why));
  EXPECT_NE(why.find("accel[0]"), std::string::npos) << why;
  EXPECT_NE(why.find("out of range"), std::string::npos) << why;
  auto g = m;
  g.gyro[1] = -500.0;
  EXPECT_FALSE(bus::toCore(g, "IMU", &why));
  EXPECT_NE(why.find("gyro[1]"), std::string::npos) << why;
  auto b = m;
  b.mag[2] = 1e6;
  EXPECT_FALSE(bus::toCore(b, "IMU", &why));
  EXPECT_NE(why.find("mag[2]"), std::string::npos) << why;
}

TEST(Convert, RoundTrips) {
  sim::TruthState t;
  t.utime = 123456;
  t.x = 1.5;
  t.y = -2.25;
  t.heading = 3.0;
  t.speed = 1.4;
  t.steering = -0.2;
  t.distance = 17.0;
  const auto back = drivers::toCore(drivers::toLcm(t, 9));
  EXPECT_EQ(back.utime, t.utime);
  EXPECT_EQ(back.x, t.x);
  EXPECT_EQ(back.heading, t.heading);
  EXPECT_EQ(back.distance, t.distance);

  core::FilterState s;
  s.utime = 99;
  s.x = Eigen::VectorXd::LinSpaced(5, 1.0, 5.0);
  s.P = Eigen::MatrixXd::Random(5, 5);
  s.names = {"x", "y", "theta", "odo_scale", "steer_bias"};
  s.status = core::FilterStatus::Lockout;
  const auto msg = bus::toLcm(s, "ukf_calib", 4);
  EXPECT_EQ(msg.dim, 5);
  EXPECT_EQ(msg.filter, "ukf_calib");
  EXPECT_EQ(msg.status, lcmloc::pose_t::STATUS_LOCKOUT);
  const auto s2 = bus::toCore(msg);
  EXPECT_EQ(s2.x, s.x);
  EXPECT_EQ(s2.P, s.P);
  EXPECT_EQ(s2.names, s.names);
  EXPECT_EQ(s2.status, s.status);

  core::GateDecision d;
  d.utime = 5;
  d.sensor = "MAGRULER";
  d.measurement_seq = 11;
  d.innovation = Eigen::Vector2d(0.01, -0.02);
  d.mahalanobis = 3.2;
  d.gate = 9.21;
  d.accepted = true;
  d.marker_id = 4;
  d.reason = "accepted";
  const auto g = bus::toLcm(d, "ukf_gated", 1);
  EXPECT_EQ(g.dim, 2);
  EXPECT_EQ(g.innovation[1], -0.02);
  EXPECT_EQ(g.measurement_seq, 11);
  EXPECT_EQ(g.marker_id, 4);
  EXPECT_TRUE(g.accepted);
}

// ---------------------------------------------------------------------------------------------
// Transport over memq://

TEST(Transport, PublishSubscribeTyped) {
  bus::Bus bus("memq://");
  std::vector<lcmloc::odometry_t> got;
  std::string channel;
  bus.subscribe<lcmloc::odometry_t>("ODO.*", [&](const std::string& ch, const lcmloc::odometry_t& m, int64_t) {
    channel = ch;
    got.push_back(m);
  });
  lcmloc::odometry_t m{};
  m.utime = 42;
  m.seq = 1;
  m.delta_s = 0.5;
  ASSERT_TRUE(bus.publish("ODOMETRY", m));
  m.seq = 2;
  ASSERT_TRUE(bus.publish("ODOMETRY", m));
  for (int i = 0; i < 10 && got.size() < 2; ++i) bus.handle(100);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(channel, "ODOMETRY");
  EXPECT_EQ(got[0].utime, 42);
  EXPECT_EQ(got[1].seq, 2);
  EXPECT_EQ(got[1].delta_s, 0.5);
}

TEST(Transport, DrainTakesWhatArrivedButStopsUnderAFlood) {
  // The daemon and the logger drained the bus at a stop with `while (handle(0) > 0)`: a sender
  // faster than them kept them from stopping (SIGTERM waited for the flood to end).
  bus::Bus bus("memq://");
  int handled = 0;
  bool flood = false;
  lcmloc::odometry_t m{};
  bus.subscribe<lcmloc::odometry_t>("ODOMETRY", [&](const std::string&, const lcmloc::odometry_t&, int64_t) {
    ++handled;
    if (flood) bus.publish("ODOMETRY", m);  // every message handled brings the next
  });
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(bus.publish("ODOMETRY", m));
  EXPECT_TRUE(bus.drain());
  EXPECT_EQ(handled, 5);
  flood = true;
  ASSERT_TRUE(bus.publish("ODOMETRY", m));
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_FALSE(bus.drain(100));
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(5));
  EXPECT_GT(handled, 6);
}

TEST(Transport, UndecodablePayloadIsCountedNotFatal) {
  bus::Bus bus("memq://");
  int good = 0;
  std::vector<std::string> errors;
  bus.subscribe<lcmloc::magruler_t>(
      "MAGRULER", [&](const std::string&, const lcmloc::magruler_t&, int64_t) { ++good; },
      [&](const std::string& ch, const std::string& why) { errors.push_back(ch + ": " + why); });
  const char garbage[] = "definitely not a magruler_t";
  bus.publishRaw("MAGRULER", garbage, sizeof garbage);
  // A right fingerprint with a negative array length must not crash either.
  lcmloc::magruler_t m{};
  m.num_sensors = 1;
  m.readings = {0.1};
  std::vector<uint8_t> buf(m.getEncodedSize());
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  buf[8 + 16 + 3] = 0xff;  // num_sensors = 0x000000ff -> longer than the payload
  bus.publishRaw("MAGRULER", buf.data(), buf.size());
  buf[8 + 16] = 0xff;      // num_sensors negative
  bus.publishRaw("MAGRULER", buf.data(), buf.size());
  m.num_sensors = 0;
  m.readings.clear();
  bus.publish("MAGRULER", m);
  for (int i = 0; i < 10 && good + static_cast<int>(errors.size()) < 4; ++i) bus.handle(100);
  EXPECT_EQ(errors.size(), 3u);
  EXPECT_EQ(bus.decodeErrors("MAGRULER"), 3);
  EXPECT_EQ(bus.decodeErrors(), 3);
  EXPECT_EQ(good, 1);  // the valid message after the bad ones still arrives
  ASSERT_FALSE(errors.empty());
  EXPECT_NE(errors[0].find("cannot decode magruler_t"), std::string::npos) << errors[0];
}

TEST(Transport, BadUrlThrowsClearError) {
  try {
    bus::Bus bus("nonsense://nowhere");
    FAIL() << "no error";
  } catch (const bus::TransportError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot start LCM on 'nonsense://nowhere'"), std::string::npos);
  }
}

/// Writes a big-endian int32 at byte i of an encoded message.
void putInt32(std::vector<uint8_t>& b, std::size_t i, int32_t v) {
  const auto u = static_cast<uint32_t>(v);
  for (int k = 0; k < 4; ++k) b[i + static_cast<std::size_t>(k)] = static_cast<uint8_t>(u >> (24 - 8 * k));
}

template <typename T>
std::vector<uint8_t> encoded(const T& m) {
  std::vector<uint8_t> b(static_cast<std::size_t>(m.getEncodedSize()));
  EXPECT_GE(m.encode(b.data(), 0, static_cast<int>(b.size())), 0);
  return b;
}

TEST(Transport, CorruptLengthsInAMessageFailTheDecodeInsteadOfCrashing) {
  // lcm-gen's decoders are hardened at build time (lcmtypes/harden_decode.cmake).
  lcmloc::fusion_control_t c{};
  c.filter = "ukf";
  const auto good = encoded(c);
  lcmloc::fusion_control_t dc;
  ASSERT_EQ(dc.decode(good.data(), 0, static_cast<int>(good.size())), static_cast<int>(good.size()));
  EXPECT_EQ(dc.filter, "ukf");
  // The filter string's length (hash 8, utime 8, seq 8, command 4: byte 28). INT_MIN made the
  // decoder copy 2 GB from past the buffer.
  for (int32_t len : {std::numeric_limits<int32_t>::min(), -5, 0}) {
    auto bad = good;
    putInt32(bad, 28, len);
    EXPECT_LT(dc.decode(bad.data(), 0, static_cast<int>(bad.size())), 0) << len;
  }

  lcmloc::pose_t p{};
  p.filter = "ukf";  // length 4 at byte 24, characters 28..31, status 32, dim 36
  p.dim = 2;
  p.state = {1.0, 2.0};
  p.state_names = {"x", "y"};
  p.covariance = {{1.0, 0.0}, {0.0, 1.0}};
  const auto pose = encoded(p);
  lcmloc::pose_t dp;
  ASSERT_EQ(dp.decode(pose.data(), 0, static_cast<int>(pose.size())), static_cast<int>(pose.size()));
  EXPECT_EQ(dp.state_names[1], "y");
  // An absurd count fails before anything is allocated (2^31 - 1 doubles were 16 GB).
  for (int32_t dim : {std::numeric_limits<int32_t>::max(), 1000, -3}) {
    auto bad = pose;
    putInt32(bad, 36, dim);
    EXPECT_LT(dp.decode(bad.data(), 0, static_cast<int>(bad.size())), 0) << dim;
  }

  // A well-formed message above 1 MiB is refused before it is read (300,000 counters: 4.2 MB on
  // the wire; a hostile 16 MB one took 548 MB of memory to fail). Under the bound it decodes.
  lcmloc::heartbeat_t h{};
  h.process = "p";
  h.state = "ok";
  for (const int n : {1000, 300000}) {
    h.num_counters = n;
    h.counter_names.assign(static_cast<std::size_t>(n), "c");
    h.counters.assign(static_cast<std::size_t>(n), 0);
    const auto big = encoded(h);
    lcmloc::heartbeat_t dh;
    const int got = dh.decode(big.data(), 0, static_cast<int>(big.size()));
    if (big.size() <= 1048576) {
      EXPECT_EQ(got, static_cast<int>(big.size())) << n;
    } else {
      EXPECT_LT(got, 0) << n;
      EXPECT_TRUE(dh.counter_names.empty());
    }
  }
}

TEST(LogThrottle, FirstFivePerKeyThenOneInAThousand) {
  app::LogThrottle t;
  std::vector<int> allowed;
  for (int i = 1; i <= 3000; ++i)
    if (t.allow("ODOMETRY")) allowed.push_back(i);
  EXPECT_EQ(allowed, (std::vector<int>{1, 2, 3, 4, 5, 1000, 2000, 3000}));
  EXPECT_TRUE(t.allow("GPS"));  // counted per key
}

TEST(Transport, InvalidChannelRegexThrowsInsteadOfCrashing) {
  bus::Bus bus("memq://");
  try {
    bus.subscribeRaw("([", [](const std::string&, const uint8_t*, std::size_t, int64_t) {});
    FAIL() << "no error";
  } catch (const bus::TransportError& e) {
    EXPECT_NE(std::string(e.what()).find("'([': not a valid channel regex"), std::string::npos) << e.what();
  }
  int n = 0;  // the bus still works
  bus.subscribeRaw("A|B", [&](const std::string&, const uint8_t*, std::size_t, int64_t) { ++n; });
  const uint8_t byte = 0;
  bus.publishRaw("B", &byte, 1);
  for (int i = 0; i < 10 && n == 0; ++i) bus.handle(100);
  EXPECT_EQ(n, 1);
}

// ---------------------------------------------------------------------------------------------
// Process helpers

// follows() takes the in-order message of the key observed last and nothing else: what it
// refuses, observe() then judges as if follows() had not been asked.
TEST(Process, SeqTrackerFollowsTakesOnlyTheNextSeqOfTheLastKey) {
  bus::SeqTracker t, u;  // u: observe() alone
  EXPECT_FALSE(t.follows("A", 0)) << "no key yet";
  auto both = [&](const char* key, int64_t seq) {
    const bool took = t.follows(key, seq);
    const bus::SeqGap g = took ? bus::SeqGap{} : t.observe(key, seq);
    const bus::SeqGap ref = u.observe(key, seq);
    EXPECT_EQ(g.missing, ref.missing) << key << " " << seq;
    EXPECT_EQ(g.restarted, ref.restarted) << key << " " << seq;
    EXPECT_EQ(g.ignored, ref.ignored) << key << " " << seq;
    EXPECT_EQ(t.gaps(), u.gaps());
    EXPECT_EQ(t.ignored(), u.ignored());
    return took;
  };
  EXPECT_FALSE(both("A", 5));
  EXPECT_TRUE(both("A", 6));
  EXPECT_TRUE(both("A", 7));
  EXPECT_FALSE(both("A", 9)) << "a gap";
  EXPECT_TRUE(both("A", 10));
  EXPECT_FALSE(both("B", 11)) << "another key";
  EXPECT_FALSE(both("A", 11)) << "in order, but not on the key observed last";
  EXPECT_TRUE(both("A", 12));
  EXPECT_FALSE(both("A", 12)) << "a duplicate";
  EXPECT_FALSE(both("A", 3)) << "a step back";
  EXPECT_FALSE(both("A", 13)) << "after a step back, observe() decides";
  EXPECT_TRUE(both("A", 14));
  EXPECT_EQ(t.gaps("A"), 1) << "8";
  EXPECT_EQ(t.gaps("A"), u.gaps("A"));
  EXPECT_EQ(t.ignored("A"), u.ignored("A"));
}

TEST(Process, SeqTrackerCountsGapsPerKey) {
  bus::SeqTracker t;
  auto missing = [&](const char* key, int64_t seq) { return t.observe(key, seq).missing; };
  EXPECT_EQ(missing("A", 5), 0);  // first message: no gap whatever its seq
  EXPECT_EQ(missing("A", 6), 0);
  const bus::SeqGap g = t.observe("A", 9);
  EXPECT_EQ(g.missing, 2);
  EXPECT_EQ(g.before_seq, 9);
  EXPECT_EQ(g.describe("A"), "A: 2 message(s) missing before seq 9");
  EXPECT_EQ(missing("B", 0), 0);
  EXPECT_EQ(missing("B", 2), 1);
  EXPECT_EQ(missing("A", 9), 0);  // duplicate
  EXPECT_FALSE(t.observe("A", 10).restarted);
  EXPECT_FALSE(t.observe("A", 0).restarted);  // went back: said when the next message goes on from it
  const bus::SeqGap back = t.observe("A", 1);  // the sender started over
  EXPECT_TRUE(back.restarted);
  EXPECT_EQ(back.missing, 0);
  EXPECT_EQ(back.describeRestart("A"),
            "A: seq went back from 10 to 0 (the sender started over?): messages it did not send meanwhile are not "
            "counted");
  EXPECT_EQ(missing("A", 2), 0);
  EXPECT_EQ(t.gaps("A"), 2);
  EXPECT_EQ(t.gaps("B"), 1);
  EXPECT_EQ(t.gaps(), 3);
  // A jump far ahead, confirmed: up to kMaxSeqGap it is lost messages, beyond a new sequence.
  const int64_t k = bus::SeqTracker::kMaxSeqGap;
  EXPECT_EQ(missing("B", 3 + k), 0);
  EXPECT_EQ(missing("B", 4 + k), k);  // the bound
  EXPECT_EQ(missing("B", 6 + 2 * k), 0);  // one more: beyond it
  const bus::SeqGap beyond = t.observe("B", 7 + 2 * k);
  EXPECT_EQ(beyond.missing, 0);
  EXPECT_TRUE(beyond.restarted);
  EXPECT_EQ(beyond.describeRestart("B"),
            "B: seq jumped ahead from " + std::to_string(4 + k) + " to " + std::to_string(6 + 2 * k) +
                " (a new sequence, not lost messages): messages it did not send meanwhile are not counted");
  EXPECT_EQ(missing("B", 9 + 2 * k), 1);
  // The ends of the range: no overflow, and a lone seq there is ignored.
  EXPECT_EQ(missing("C", -5), 0);
  EXPECT_EQ(missing("C", INT64_MAX), 0);
  EXPECT_EQ(missing("C", -4), 0);
  EXPECT_EQ(missing("C", -2), 1);
  EXPECT_EQ(missing("C", INT64_MIN), 0);
  EXPECT_EQ(missing("C", INT64_MAX), 0);
  EXPECT_EQ(missing("C", INT64_MIN), 0);
  EXPECT_EQ(t.gaps(), 3 + k + 1 + 1);
  EXPECT_EQ(t.ignored("C"), 3);
}

// A seq that broke the sequence and was not followed is said: which, after what, and why.
TEST(Process, SeqTrackerSaysWhichSeqItIgnoredAndTakesBackASmallJumpThatWasALoneOutlier) {
  bus::SeqTracker t;
  for (int64_t s = 0; s <= 100; ++s) t.observe("A", s);
  EXPECT_FALSE(t.observe("A", 100 | (int64_t{1} << 30)).ignored);
  const bus::SeqGap g = t.observe("A", 101);
  EXPECT_TRUE(g.ignored);
  EXPECT_FALSE(g.restarted);
  EXPECT_EQ(g.missing, 0);
  EXPECT_EQ(g.describeIgnored("A"),
            "A: seq 1073741924 (after 100) ignored: the next message (seq 101) did not go on from it (a corrupt "
            "seq, or a message out of order); not counted as a gap");
  // Bit 3 flipped: 102 -> 110 looks like 7 lost messages, counted at once; 103 goes on from 102:
  // the 7 are taken back.
  EXPECT_EQ(t.observe("A", 102).missing, 0);
  EXPECT_EQ(t.observe("A", 110).missing, 7);
  EXPECT_EQ(t.gaps(), 7);
  const bus::SeqGap back = t.observe("A", 103);
  EXPECT_TRUE(back.ignored);
  EXPECT_FALSE(back.restarted);
  EXPECT_EQ(back.uncounted, 7);
  EXPECT_EQ(back.ignored_seq, 110);
  EXPECT_EQ(back.ignored_after, 102);
  EXPECT_EQ(back.describeIgnored("A"),
            "A: seq 110 (after 102) ignored: the next message (seq 103) did not go on from it (a corrupt seq, or a "
            "message out of order); not counted as a gap (the 7 message(s) counted missing before it are taken back)");
  EXPECT_EQ(t.gaps(), 0);
  EXPECT_EQ(t.gaps("A"), 0);
  EXPECT_EQ(t.observe("A", 104).missing, 0);
  EXPECT_EQ(t.ignored(), 2);
  EXPECT_EQ(t.ignored("A"), 2);
  // Every other message lost (a burst): each small gap is counted, none is taken for an outlier.
  bus::SeqTracker lossy;
  for (int64_t s = 0; s < 100; s += 2) lossy.observe("B", s);
  EXPECT_EQ(lossy.gaps(), 49);
  EXPECT_EQ(lossy.ignored(), 0);
  // Keys are found by name however many there are.
  bus::SeqTracker many;
  for (int64_t s = 0; s < 3; ++s)
    for (int c = 0; c < 2000; ++c) many.observe("C" + std::to_string(c), s * 2);
  EXPECT_EQ(many.size(), 2000u);
  EXPECT_TRUE(many.tracks("C1999"));
  EXPECT_FALSE(many.tracks("C2000"));
  EXPECT_EQ(many.gaps("C1234"), 2);
  EXPECT_EQ(many.gaps(), 4000);
}

// One corrupt seq used to add up to 2^31 "missing" messages: the audit's ODOMETRY seqs 0, 2^31, 0,
// 2^31, ... gave 4294967294 gaps for 8 messages, and one seq with bit 30 flipped 1.07e9; a corrupt
// seq that went back was a "restart" and the next good one a gap of its own.
TEST(Process, SeqTrackerIgnoresALoneCorruptSeq) {
  bus::SeqTracker alternating;
  for (int i = 0; i < 8; ++i) alternating.observe("ODOMETRY", i % 2 ? int64_t{1} << 31 : 0);
  EXPECT_EQ(alternating.gaps(), 0);
  for (const int bit : {62, 40, 30, 20, 12, 5, 3, 1}) {  // one bit flipped in one message of a counting stream
    SCOPED_TRACE(bit);
    bus::SeqTracker t;
    int restarts = 0;
    for (int64_t s = 0; s < 200; ++s) {
      const auto g = t.observe("A", s == 100 ? s ^ (int64_t{1} << bit) : s);
      restarts += g.restarted;
    }
    EXPECT_EQ(t.gaps(), 0);
    EXPECT_EQ(restarts, 0);
  }
  bus::SeqTracker junk;  // the audit's seqjunk stream
  for (const int64_t s : {int64_t{0}, int64_t{1} << 31, int64_t{0}, int64_t{1} << 31, INT64_MAX, INT64_MIN})
    junk.observe("ODOMETRY", s);
  EXPECT_EQ(junk.gaps(), 0);
  EXPECT_EQ(junk.observe("ODOMETRY", 1).missing, 0);  // goes on from 0
  EXPECT_EQ(junk.observe("ODOMETRY", 4).missing, 2);
  EXPECT_EQ(junk.gaps(), 2);
}

// A real loss or restart is still counted or said, once the next message goes on from the new seq.
TEST(Process, SeqTrackerTakesABigJumpOrAStepBackWhenTheNextMessageGoesOnFromIt) {
  bus::SeqTracker t;
  for (int64_t s = 0; s < 10; ++s) t.observe("A", s);
  EXPECT_EQ(t.observe("A", 5010).missing, 0);  // 5000 missing, or a corrupt seq: not known yet
  const bus::SeqGap g = t.observe("A", 5011);  // goes on from it: 5000 lost
  EXPECT_EQ(g.missing, 5000);
  EXPECT_EQ(g.before_seq, 5010);
  EXPECT_EQ(g.describe("A"), "A: 5000 message(s) missing before seq 5010");
  EXPECT_EQ(t.gaps(), 5000);
  EXPECT_EQ(t.observe("A", 5013).missing, 1);  // a small gap: at once
  EXPECT_FALSE(t.observe("A", 0).restarted);  // went back: not known yet
  const bus::SeqGap back = t.observe("A", 1);  // the sender started over
  EXPECT_TRUE(back.restarted);
  EXPECT_EQ(back.missing, 0);
  EXPECT_EQ(back.last_seq, 5013);
  EXPECT_EQ(back.before_seq, 0);
  EXPECT_EQ(t.observe("A", 2).missing, 0);
  EXPECT_EQ(t.gaps(), 5001);
  // The jumped message lost too: the one after it starts the wait again, and the total is right.
  for (int64_t s = 3; s < 10; ++s) t.observe("A", s);
  EXPECT_EQ(t.observe("A", 3009).missing, 0);
  EXPECT_EQ(t.observe("A", 3011).missing, 0);  // 3010 lost as well
  EXPECT_EQ(t.observe("A", 3012).missing, 3001);  // 10 .. 3010 (3009 came, but its seq was not taken)
  EXPECT_EQ(t.gaps(), 5001 + 3001);
}

TEST(Process, PacerFollowsTheRealtimeFactor) {
  app::Pacer fast(0.0);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_TRUE(fast.waitUntil(0));
  EXPECT_TRUE(fast.waitUntil(3600000000LL));  // an hour of sim time, no wait
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(1));

  app::Pacer x100(100.0);
  const auto t1 = std::chrono::steady_clock::now();
  EXPECT_TRUE(x100.waitUntil(1000000));
  EXPECT_TRUE(x100.waitUntil(1000000 + 20000000));  // 20 s of sim time at x100 = 200 ms wall
  EXPECT_GE(std::chrono::steady_clock::now() - t1, std::chrono::milliseconds(195));
}

TEST(Process, HeartbeatPublishesNameStateAndCounters) {
  bus::Bus bus("memq://");
  std::vector<lcmloc::heartbeat_t> got;
  bus.subscribe<lcmloc::heartbeat_t>("HEARTBEAT",
                                     [&](const std::string&, const lcmloc::heartbeat_t& m, int64_t) { got.push_back(m); });
  int64_t n = 0;
  app::Heartbeat hb(bus, "HEARTBEAT", "test-proc", [&] { return app::Heartbeat::Counters{{"n", n}}; });
  n = 7;
  hb.tick();
  hb.tick();  // within the same second: nothing
  hb.publish("stopping");
  for (int i = 0; i < 10 && got.size() < 2; ++i) bus.handle(100);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].process, "test-proc");
  EXPECT_EQ(got[0].state, "running");
  EXPECT_EQ(got[0].seq, 0);
  EXPECT_EQ(got[1].seq, 1);
  EXPECT_EQ(got[1].state, "stopping");
  ASSERT_EQ(got[0].num_counters, 1);
  EXPECT_EQ(got[0].counter_names[0], "n");
  EXPECT_EQ(got[0].counters[0], 7);
}

TEST(Printable, ControlCharactersAndInvalidUtf8BecomeQuestionMarks) {
  EXPECT_EQ(app::printable("POSE_A.b-1"), "POSE_A.b-1");
  EXPECT_EQ(app::printable("a\nb\x1b[2J\x07\x7f"), "a?b?[2J??");
  // C1 controls in UTF-8 (U+009B is CSI, ESC [ in one character), kept: text beyond them.
  EXPECT_EQ(app::printable("\xc2\x9b" "2J\xc2\x9d" "0;x\xc2\x9c"), "?2J?0;x?");
  EXPECT_EQ(app::printable("caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x9a\x97 \xc2\xa0"), "caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x9a\x97 \xc2\xa0");
  // Not UTF-8: stray continuation and lead bytes, an overlong '/', a surrogate, a cut sequence.
  EXPECT_EQ(app::printable("\xff\xfe\x80"), "???");
  EXPECT_EQ(app::printable("\xc0\xaf"), "??");
  EXPECT_EQ(app::printable("\xed\xa0\x80"), "???");
  EXPECT_EQ(app::printable("ok\xe2\x82"), "ok??");
}
