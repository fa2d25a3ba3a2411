// ukf_landmarks' self-calibration states (FilterConfig::Calibration): a beacon's range bias,
// the odometer scale, the yaw-rate scale and bias, each estimated in simulation from range-only
// beacons and odometry with that error, with a covariance that covers the error; and the states
// carried over by a hand-over (a filter switch of the engine, a process-level initialize).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "lcmloc/core/engine.hpp"
#include "lcmloc/core/filter.hpp"
#include "lcmloc/core/vehicle_model.hpp"

using namespace lcmloc::core;
using BeaconBias = FilterConfig::Calibration::BeaconBias;

namespace {

const MarkerMap kBeacons{{1, 6.0, 6.0}, {2, -6.0, 6.0}, {3, -6.0, -6.0}, {4, 6.0, -6.0}};

FilterConfig baseConfig() {
  FilterConfig c;
  c.type = "ukf_landmarks";
  c.initial_pose = Vec3(2.0, 0.0, M_PI / 2);
  c.p0_diag = Vec3(0.01, 0.01, 0.003);
  c.landmarks.beacon_std = 0.05;
  c.pw_diag = Vec3(4e-4, 4e-4, 4e-4);  // the odometry's simulated noise below, per 2 m
  c.pw_turn = 1e-4;
  return c;
}

/// What the simulated odometry and beacons get wrong.
struct Errors {
  double beacon2_bias = 0.0;  ///< added to every range of beacon 2 [m]
  double all_bias = 0.0;      ///< added to every range of every beacon [m]
  double odo_scale = 0.0;     ///< true ds = (1 + k) measured ds
  double yaw_scale = 0.0;     ///< true dtheta = (1 + g) measured dtheta - b dt
  double yaw_bias = 0.0;      ///< b [rad/s]
};

struct DriveResult {
  double rmse = 0;   ///< position error over the second half [m]
  double final_error = 0;
  int refused2 = 0;  ///< ranges of beacon 2 the gate refused
  FilterState state;
};

/// 120 s of driving a figure eight (1 m/s, 20 Hz odometry with noise), a beacon range every
/// step in turn, through filter f.
DriveResult drive(Filter& f, const Errors& e, const MarkerMap& beacons = kBeacons, unsigned seed = 3) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  Pose truth(2.0, 0.0, M_PI / 2);
  const double dt = 0.05, v = 1.0;
  const int steps = 2400;
  double se = 0;
  int counted = 0;
  DriveResult r;
  for (int k = 1; k <= steps; ++k) {
    const double t = k * dt;
    const double w = 0.5 * std::sin(2 * M_PI * t / 25.0);  // a figure eight [rad/s]
    const double ds = v * dt, dth = w * dt;
    truth = propagatePose(truth, ds, dth);
    OdometryInput o;
    o.utime = static_cast<int64_t>(k) * 50000;
    o.delta_s = ds / (1 + e.odo_scale) + 0.002 * n01(rng);
    o.delta_theta = (dth + e.yaw_bias * dt) / (1 + e.yaw_scale) + 0.002 * n01(rng);
    f.predict(o);
    const Marker& m = beacons[static_cast<std::size_t>(k) % beacons.size()];
    BeaconRange b;
    b.utime = o.utime + 1;
    b.beacon_id = m.id;
    b.range = std::hypot(m.x - truth.x(), m.y - truth.y()) + 0.05 * n01(rng) + (m.id == 2 ? e.beacon2_bias : 0.0) + e.all_bias;
    b.sensor = "UWB";
    const auto d = f.update(b);
    if (m.id == 2 && d && !d->accepted) ++r.refused2;
    const FilterState s = f.state();
    const double err = std::hypot(s.x[0] - truth.x(), s.x[1] - truth.y());
    if (k > steps / 2) {
      se += err * err;
      ++counted;
    }
  }
  r.state = f.state();
  r.final_error = std::hypot(r.state.x[0] - truth.x(), r.state.x[1] - truth.y());
  r.rmse = std::sqrt(se / counted);
  return r;
}

/// The calibration state `name` (without "cal_") of s; fails when it has none.
CalibrationValue calib(const FilterState& s, const std::string& name) {
  for (const auto& c : calibrationValues(s))
    if (c.name == name) return c;
  ADD_FAILURE() << "no calibration state " << name;
  return {};
}

}  // namespace

TEST(LandmarkCalibration, OffByDefaultTheStateIsThePoseOnly) {
  auto f = makeFilter(baseConfig(), kBeacons);
  EXPECT_EQ(f->state().x.size(), 3);
  EXPECT_TRUE(calibrationValues(f->state()).empty());
  EXPECT_EQ(calibrationSummary(f->state()), "");
}

TEST(LandmarkCalibration, EachKeyAddsItsStatesWithTheirPriors) {
  FilterConfig c = baseConfig();
  c.calibration.odo_scale = true;
  c.calibration.odo_scale_std = 0.03;
  c.calibration.yaw_rate_bias = true;
  c.calibration.beacon_bias = BeaconBias::PerBeacon;
  c.calibration.beacon_bias_std = 2.0;
  const FilterState s = makeFilter(c, kBeacons)->state();
  ASSERT_EQ(s.x.size(), 3 + 2 + 4);
  EXPECT_EQ(s.names[3], "cal_odo_scale");
  EXPECT_EQ(s.names[4], "cal_yaw_rate_bias");
  EXPECT_EQ(s.names[8], "cal_beacon_bias_4");
  EXPECT_DOUBLE_EQ(s.P(3, 3), 0.03 * 0.03);
  EXPECT_DOUBLE_EQ(s.P(8, 8), 4.0);
  c.calibration.beacon_bias = BeaconBias::Shared;
  EXPECT_EQ(makeFilter(c, kBeacons)->state().names.back(), "cal_beacon_bias");
  // More map entries than per-beacon states: refused, naming the way out.
  MarkerMap many;
  for (int i = 0; i < 9; ++i) many.push_back({i, double(i), 0.0});
  c.calibration.beacon_bias = BeaconBias::PerBeacon;
  EXPECT_THROW(makeFilter(c, many), std::invalid_argument);
}

// A calibration state the filter does not have is refused, naming the ones it has (it was
// ignored: the user believed the bias estimated). Filters with no calibration states at all
// (the ruler filters, a shadow of the same parameters) are left alone.
TEST(LandmarkCalibration, AStateTheFilterDoesNotHaveIsRefusedNamingItsStates) {
  FilterConfig c = baseConfig();
  c.calibration.steering_bias = true;
  try {
    makeFilter(c, kBeacons);
    ADD_FAILURE() << "steering_bias on ukf_landmarks was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("calibration.steering_bias is not a state of ukf_landmarks (its states: "
                                         "beacon_bias, odo_scale, yaw_rate_scale, yaw_rate_bias)"),
              std::string::npos)
        << e.what();
  }
  c.calibration.steering_bias = false;
  c.calibration.mag_bias = true;
  EXPECT_THROW(makeFilter(c, kBeacons), std::invalid_argument);
  FilterConfig g = c;
  g.type = "tvekf";  // has mag_bias
  EXPECT_NO_THROW(makeFilter(g, kBeacons));
  g.calibration.yaw_rate_bias = true;
  EXPECT_THROW(makeFilter(g, kBeacons), std::invalid_argument);
  g.type = "ukf_gps";
  EXPECT_THROW(makeFilter(g, kBeacons), std::invalid_argument);
  g.type = "dead_reckoning";
  EXPECT_NO_THROW(makeFilter(g, kBeacons));
  // The accelerometer bias is a state of the GNSS filters only.
  FilterConfig a = baseConfig();
  a.calibration.accel_bias = true;
  EXPECT_THROW(makeFilter(a, kBeacons), std::invalid_argument);
  a.type = "ukf_gps";
  EXPECT_NO_THROW(makeFilter(a, kBeacons));
  a.calibration.accel_bias_std = 0.0;
  EXPECT_THROW(makeFilter(a, kBeacons), std::invalid_argument);
  a.calibration.accel_bias_std = 0.02;
  a.calibration.accel_bias_rw = -1e-3;
  EXPECT_THROW(makeFilter(a, kBeacons), std::invalid_argument);
}

// A beacon that reads 3 m long: with its bias state on, the bias is found within 0.2 m (and
// inside 3 sigma of its estimate) and the position stays within a few centimetres; with the
// state off, that beacon's ranges are refused or pull the estimate, and the error is larger.
TEST(LandmarkCalibration, ABeaconRangeBiasOf3mIsEstimatedWithinTwentyCentimetres) {
  Errors e;
  e.beacon2_bias = 3.0;
  FilterConfig on = baseConfig();
  on.calibration.beacon_bias = BeaconBias::PerBeacon;
  on.calibration.beacon_bias_std = 5.0;
  auto f_on = makeFilter(on, kBeacons);
  const DriveResult r_on = drive(*f_on, e);
  const CalibrationValue b2 = calib(r_on.state, "beacon_bias_2");
  EXPECT_NEAR(b2.value, 3.0, 0.2);
  EXPECT_LT(std::abs(b2.value - 3.0), 3 * b2.sigma + 0.02);
  EXPECT_NEAR(calib(r_on.state, "beacon_bias_1").value, 0.0, 0.2);
  EXPECT_LT(r_on.rmse, 0.1);

  auto f_off = makeFilter(baseConfig(), kBeacons);
  const DriveResult r_off = drive(*f_off, e);
  // Off: the gate refuses that beacon's ranges, the position has one beacon fewer.
  EXPECT_LT(r_on.refused2, 20);  // about the 1 % a 99 % gate refuses of good ranges
  EXPECT_GT(r_off.refused2, 500);  // of its 600
  EXPECT_GT(r_off.rmse, 1.5 * r_on.rmse);
}

// Every beacon 3 m long (a common delay): one shared bias state finds it; without it every
// range is refused and the filter dead-reckons.
TEST(LandmarkCalibration, ASharedRangeBiasIsEstimated) {
  Errors e;
  e.all_bias = 3.0;
  FilterConfig on = baseConfig();
  on.calibration.beacon_bias = BeaconBias::Shared;
  on.calibration.beacon_bias_std = 5.0;
  auto f_on = makeFilter(on, kBeacons);
  const DriveResult r_on = drive(*f_on, e);
  EXPECT_NEAR(calib(r_on.state, "beacon_bias").value, 3.0, 0.2);
  EXPECT_LT(r_on.rmse, 0.1);
  auto f_off = makeFilter(baseConfig(), kBeacons);
  EXPECT_GT(drive(*f_off, e).rmse, 5 * r_on.rmse);
}

// Odometry whose distance reads 6 % short and whose yaw rate carries a 0.02 rad/s bias: both
// states recovered (scale within 0.01, bias within 0.004 rad/s, each within 3 sigma), the
// position better than without them.
TEST(LandmarkCalibration, OdometerScaleAndYawRateBiasAreRecovered) {
  Errors e;
  e.odo_scale = 0.06;
  e.yaw_bias = 0.02;
  FilterConfig c = baseConfig();
  c.calibration.odo_scale = true;
  c.calibration.odo_scale_std = 0.1;
  c.calibration.yaw_rate_bias = true;
  c.calibration.yaw_rate_bias_std = 0.05;
  auto f = makeFilter(c, kBeacons);
  const DriveResult r = drive(*f, e);
  const auto k = calib(r.state, "odo_scale"), b = calib(r.state, "yaw_rate_bias");
  EXPECT_NEAR(k.value, 0.06, 0.01);
  EXPECT_NEAR(b.value, 0.02, 0.004);
  EXPECT_LT(std::abs(k.value - 0.06), 3 * k.sigma);
  EXPECT_LT(std::abs(b.value - 0.02), 3 * b.sigma);
  EXPECT_LT(k.sigma, 0.01);
  auto plain = makeFilter(baseConfig(), kBeacons);
  EXPECT_LT(r.rmse, drive(*plain, e).rmse);
}

// A yaw rate that reads 1.75 times the truth (a wrong wheel distance of a differential drive):
// the yaw-rate scale state finds g = 1 / 1.75 - 1 within 0.02.
TEST(LandmarkCalibration, YawRateScaleIsRecovered) {
  Errors e;
  e.yaw_scale = 1.0 / 1.75 - 1.0;
  FilterConfig c = baseConfig();
  c.calibration.yaw_rate_scale = true;
  c.calibration.yaw_rate_scale_std = 0.5;
  auto f = makeFilter(c, kBeacons);
  const DriveResult r = drive(*f, e);
  const auto g = calib(r.state, "yaw_rate_scale");
  EXPECT_NEAR(g.value, e.yaw_scale, 0.02);
  EXPECT_LT(std::abs(g.value - e.yaw_scale), 3 * g.sigma);
  EXPECT_LT(r.rmse, 0.1);
}

// The calibration survives a hand-over: a filter of the same type started from the state
// (process-level hand-over, a checkpoint's state) and the engine's switch to the same type
// both keep the estimates and their covariance; a filter without those states drops them.
TEST(LandmarkCalibration, TheStatesSurviveAHandOver) {
  Errors e;
  e.beacon2_bias = 1.0;
  e.odo_scale = 0.05;
  FilterConfig c = baseConfig();
  c.calibration.odo_scale = true;
  c.calibration.beacon_bias = BeaconBias::PerBeacon;
  c.calibration.beacon_bias_std = 2.0;
  auto f = makeFilter(c, kBeacons);
  const FilterState s = drive(*f, e).state;
  ASSERT_NEAR(calib(s, "beacon_bias_2").value, 1.0, 0.2);

  auto g = makeFilter(c, kBeacons);
  g->initialize(s);
  const FilterState t = g->state();
  ASSERT_EQ(t.names, s.names);
  EXPECT_EQ(t.x, s.x);
  EXPECT_EQ(t.P, s.P);

  // The engine: inputs, then a switch to the same filter type.
  EngineConfig ec;
  ec.filter = c;
  FusionEngine engine(ec, kBeacons, EngineOutputs{});
  engine.initialize(s);
  engine.push({"CTL", 0, s.utime + 1000, ControlCommand{SwitchFilter{c}}});
  engine.flush();
  const FilterState u = engine.activeState();
  ASSERT_EQ(u.names, s.names);
  EXPECT_EQ(u.x.tail(5), s.x.tail(5));
  EXPECT_EQ(u.P.bottomRightCorner(5, 5), s.P.bottomRightCorner(5, 5));

  // A different set of calibration states keeps the ones it shares by name.
  FilterConfig only_scale = baseConfig();
  only_scale.calibration.odo_scale = true;
  auto h = makeFilter(only_scale, kBeacons);
  h->initialize(s);
  EXPECT_EQ(h->state().x.size(), 4);
  EXPECT_EQ(calib(h->state(), "odo_scale").value, calib(s, "odo_scale").value);
}
