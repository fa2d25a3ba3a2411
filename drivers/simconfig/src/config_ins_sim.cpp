#include "config_ins_sim.hpp"

#include <cmath>

#include "lcmloc/app/imu_error_keys.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

namespace lcmloc::simconfig::ins_config {

// Built on the application layer (configuration, process helpers).
using namespace lcmloc::app;

void parseInsSim(KeyReader& root, sim::InsSimConfig& c) {
  KeyReader r(root.child("ins_sim"), root.file(), "ins_sim");
  r.get<uint64_t>("seed", c.seed);
  r.get("rate_hz", c.rate_hz, 1.0, 10000.0);
  r.get("odometry_divider", c.odometry_divider, 1, 10000);
  r.get("duration", c.duration, kInsSimDuration.lo, kInsSimDuration.hi);
  r.get("profile", c.profile);
  if (c.profile != "paper" && c.profile != "custom")
    throw ConfigError(root.file(), "ins_sim.profile", "unknown profile '" + c.profile + "' (valid: paper, custom)");
  r.get("start", c.start);
  if (!sim::insStartValid(c.start))
    throw ConfigError(root.file(), "ins_sim.start",
                      "unknown start '" + c.start + "' (valid: hard, gentle, gentle_turn, gentle_stopgo, steady)");
  r.getList("segments", c.segments, "{duration, accel, yaw_rate}", [](KeyReader& s, sim::InsMotionSegment& v) {
    s.get("duration", v.duration, 1e-3, 1e6);
    s.get("accel", v.accel, -20.0, 20.0);
    s.get("yaw_rate", v.yaw_rate, -180.0, 180.0, "deg/s");
  });
  if (c.profile == "custom" && c.segments.empty())
    throw ConfigError(root.file(), "ins_sim.segments", "the custom profile needs a non-empty list of segments");
  r.get("latitude", c.latitude, -89.0, 89.0);
  r.get("longitude", c.longitude, -180.0, 180.0);
  r.get("height", c.height, -1e4, 1e5);
  r.get("heading", c.heading, -M_PI, M_PI);
  readImuErrorModel(r, c);
  r.get("scale_error", c.scale_error, -0.5, 0.5);
  r.get("scale_markov", c.scale_markov, 0.0, 0.5);
  r.get("scale_tau", c.scale_tau, 1e-3, 1e9);
  r.get("scale_white", c.scale_white, 0.0, 0.5);
  r.getList("imu_dropouts", c.imu_dropouts, "{start, duration}", [](KeyReader& d, auto& v) {
    d.get("start", v.first, 0.0, 1e7);
    d.get("duration", v.second, 0.0, 1e7);
  });
  r.finish();
}

}  // namespace lcmloc::simconfig::ins_config
