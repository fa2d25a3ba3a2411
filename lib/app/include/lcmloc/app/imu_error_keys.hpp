#pragma once
// The IMU error model's keys, the same in the simulator's section (`ins_sim`, read by
// lcmloc_simconfig) and in the filter's (`fusion.filter.ins`): the filter models the sensor the
// simulator draws (first-order Markov + white noise per axis).
#include "lcmloc/app/yaml_reader.hpp"

namespace lcmloc::app {

template <class Config>
void readImuErrorModel(KeyReader& r, Config& c) {
  r.get("gyro_markov", c.gyro_markov, 0.0, 1e6, "deg/h");
  r.get("gyro_tau", c.gyro_tau, 1e-3, 1e9);
  r.get("gyro_white", c.gyro_white, 0.0, 1e6, "deg/h");
  r.get("accel_markov", c.accel_markov, 0.0, 1.0, "g");
  r.get("accel_tau", c.accel_tau, 1e-3, 1e9);
  r.get("accel_white", c.accel_white, 0.0, 1.0, "g");
}

}  // namespace lcmloc::app
