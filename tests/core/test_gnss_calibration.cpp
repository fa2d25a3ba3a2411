// Self-calibration states of the GNSS filters (fusion.filter.calibration: odometer scale,
// steering bias, magnetometer bias, accelerometer bias; docs/tvekf.md "Self-calibration"): each estimated from the
// measurement that observes it, with an honest sigma, and carried through a hand-over.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "lcmloc/core/filter.hpp"
#include "lcmloc/core/gnss_model.hpp"

using namespace lcmloc::core;

namespace {

const std::vector<std::string> kGnssTypes{"tvekf", "ukf_gps"};

FilterConfig config(const std::string& type) {
  FilterConfig c;
  c.type = type;
  c.initial_pose = Vec3(0.0, 0.0, 0.0);
  c.p0_diag = Vec3(4.0, 4.0, 1e-4);
  c.gnss.steering_std = 0.002;
  c.gnss.heading_rw = 0.001;
  c.gnss.position_rw = 0.016;
  c.gnss.mag_std = 0.01;
  return c;
}

const CalibrationValue* find(const std::vector<CalibrationValue>& v, const std::string& name) {
  for (const auto& c : v)
    if (c.name == name) return &c;
  return nullptr;
}

/// Drives straight east at 8 m/s (odometry and IMU at 100 Hz, GPS at 1 Hz from the truth): the
/// encoder reports (1 + enc_error) times the travel, the steering reads steering_bias when the
/// wheels are straight, the magnetometer reads the heading plus mag_bias, the accelerometer
/// reads accel_bias forward (the speed is constant).
struct Drive {
  int64_t t = 1'000'000;
  double x = 0;
  void run(Filter& f, double seconds, double enc_error, double steering_bias, double mag_bias,
           double accel_bias = 0.0);
};

void Drive::run(Filter& f, double seconds, double enc_error, double steering_bias, double mag_bias,
                double accel_bias) {
  const double v = 8.0;
  for (int k = 0; k < static_cast<int>(std::lround(seconds * 100)); ++k) {
    t += 10'000;
    x += v * 0.01;
    OdometryInput o;
    o.utime = t;
    o.delta_s = (1.0 + enc_error) * v * 0.01;
    o.steering = steering_bias;
    o.has_steering = true;
    f.predict(o);
    ImuInput m;
    m.utime = t;
    m.accel = Vec3(accel_bias, 0.0, 9.81);
    m.mag = gnss::earthFieldBody(mag_bias, 0.0, 0.2, -0.4);
    f.update(m);
    if ((t / 10'000) % 100 == 0) {
      GpsInput g;
      g.utime = t;
      g.x = x;
      g.y = 0.0;
      g.position_std = 2.0;
      f.update(g);
    }
  }
}

}  // namespace

TEST(GnssCalibration, StatesAreAppendedOnlyWhenSwitchedOn) {
  for (const auto& type : kGnssTypes) {
    FilterConfig c = config(type);
    EXPECT_EQ(makeFilter(c, {})->state().x.size(), 5) << type;
    EXPECT_TRUE(calibrationValues(makeFilter(c, {})->state()).empty()) << type;
    c.calibration.odo_scale = c.calibration.steering_bias = c.calibration.mag_bias = c.calibration.accel_bias = true;
    c.calibration.steering_bias_mean = 0.003;
    c.calibration.steering_bias_std = 0.02;
    c.calibration.accel_bias_std = 0.04;
    const FilterState s = makeFilter(c, {})->state();
    ASSERT_EQ(s.x.size(), 9) << type;
    EXPECT_EQ(s.names[5], "cal_odo_scale");
    EXPECT_EQ(s.names[6], "cal_steering_bias");
    EXPECT_EQ(s.names[7], "cal_mag_bias");
    EXPECT_EQ(s.names[8], "cal_accel_bias");
    EXPECT_DOUBLE_EQ(s.x[6], 0.003);
    EXPECT_DOUBLE_EQ(s.P(6, 6), 0.02 * 0.02);
    EXPECT_DOUBLE_EQ(s.P(7, 7), c.calibration.mag_bias_std * c.calibration.mag_bias_std);
    EXPECT_DOUBLE_EQ(s.x[8], 0.0);
    EXPECT_DOUBLE_EQ(s.P(8, 8), 0.04 * 0.04);
  }
}

TEST(GnssCalibration, OdometerScaleIsEstimatedFromGps) {
  for (const auto& type : kGnssTypes) {
    FilterConfig c = config(type);
    c.gnss.use_magnetometer = false;
    c.calibration.odo_scale = true;
    auto f = makeFilter(c, {});
    Drive().run(*f, 300.0, 0.02, 0.0, 0.0);  // the encoder counts 2 % too much
    const auto cal = calibrationValues(f->state());
    const auto* k = find(cal, "odo_scale");
    ASSERT_NE(k, nullptr) << type;
    const double truth = 1.0 / 1.02 - 1.0;  // true travel = (1 + k) encoder travel
    EXPECT_NEAR(k->value, truth, 3.0 * k->sigma) << type;
    EXPECT_LT(k->sigma, 0.005) << type;   // from 0.05: the fixes saw it
    EXPECT_GT(k->sigma, 1e-4) << type;    // and not more than 300 s of them can
    // The speed in the state is the encoder's; the true one is (1 + k) times it.
    EXPECT_NEAR((1.0 + k->value) * f->state().x[3], 8.0, 0.05) << type;
  }
}

TEST(GnssCalibration, SteeringBiasIsEstimatedFromTheMagnetometer) {
  for (const auto& type : kGnssTypes) {
    FilterConfig c = config(type);
    c.calibration.steering_bias = true;
    auto f = makeFilter(c, {});
    Drive().run(*f, 60.0, 0.0, 0.01, 0.0);  // straight on, the potentiometer reads 0.01 rad
    const auto values = calibrationValues(f->state());  // (find points into it)
    const auto* b = find(values, "steering_bias");
    ASSERT_NE(b, nullptr) << type;
    EXPECT_NEAR(b->value, 0.01, std::max(3.0 * b->sigma, 5e-4)) << type;
    EXPECT_LT(b->sigma, 0.002) << type;
    EXPECT_NEAR(f->state().x[2], 0.0, 0.01) << type;  // the heading did not drift with the bias
    // Without the state the same drive turns the heading away from the magnetometer's.
    FilterConfig off = config(type);
    auto g = makeFilter(off, {});
    Drive().run(*g, 60.0, 0.0, 0.01, 0.0);
    EXPECT_GT(std::abs(g->state().x[2]), std::abs(f->state().x[2])) << type;
  }
}

TEST(GnssCalibration, MagnetometerBiasTakesAPersistentOffsetWithinItsSigma) {
  for (const auto& type : kGnssTypes) {
    FilterConfig c = config(type);
    c.calibration.mag_bias = true;
    auto f = makeFilter(c, {});
    Drive().run(*f, 5.0, 0.0, 0.0, 0.03);  // the magnetometer reads 0.03 rad off the true heading 0
    const FilterState s = f->state();
    // A step of the magnetometer against a steering that says straight on: the bias state takes
    // part of it, the heading less than all of it.
    EXPECT_GT(s.x[5], 0.005) << type;
    EXPECT_LT(std::abs(s.x[2]), 0.03 - 0.005) << type;
    EXPECT_NEAR(s.x[2] + s.x[5], 0.03, 0.005) << type;  // together: what the magnetometer reads
  }
}

// The forward accelerometer reads 0.05 m/s^2 while the speed is constant: the encoder's distance
// shows the speed does not grow, so the bias state takes the reading, and the speed stays the
// encoder's. Without the state the kinematic filter of §2.1 follows the accelerometer between
// encoder corrections and its speed runs ahead.
TEST(GnssCalibration, AccelerometerBiasIsEstimatedFromTheEncoder) {
  for (const auto& type : kGnssTypes) {
    FilterConfig c = config(type);
    c.gnss.accel_std = 0.01;  // an accelerometer trusted between encoder corrections
    c.gnss.encoder_std = 0.05;
    c.calibration.accel_bias = true;
    auto f = makeFilter(c, {});
    Drive().run(*f, 120.0, 0.0, 0.0, 0.0, 0.05);
    const auto values = calibrationValues(f->state());
    const auto* b = find(values, "accel_bias");
    ASSERT_NE(b, nullptr) << type;
    EXPECT_NEAR(b->value, 0.05, std::max(3.0 * b->sigma, 0.002)) << type;
    EXPECT_LT(b->sigma, 0.01) << type;   // from 0.02: the encoder saw it
    EXPECT_GT(b->sigma, 1e-5) << type;
    const double with_state = std::abs(f->state().x[3] - 8.0);
    FilterConfig off = config(type);
    off.gnss.accel_std = 0.01;
    off.gnss.encoder_std = 0.05;
    auto g = makeFilter(off, {});
    Drive().run(*g, 120.0, 0.0, 0.0, 0.0, 0.05);
    const double without = std::abs(g->state().x[3] - 8.0);
    EXPECT_LT(with_state, 0.02) << type;
    EXPECT_GT(without, 2.0 * with_state) << type;
  }
}

TEST(GnssCalibration, StatesSurviveAHandOver) {
  for (const auto& type : kGnssTypes) {
    FilterConfig c = config(type);
    c.calibration.odo_scale = c.calibration.steering_bias = c.calibration.mag_bias = c.calibration.accel_bias = true;
    auto a = makeFilter(c, {});
    Drive().run(*a, 20.0, 0.01, 0.005, 0.01, 0.03);
    const FilterState s = a->state();
    auto b = makeFilter(c, {});
    b->initialize(s);
    const FilterState t = b->state();
    ASSERT_EQ(t.x.size(), s.x.size()) << type;
    for (int i = 5; i < 9; ++i) {
      EXPECT_EQ(t.x[i], s.x[i]) << type << " " << s.names[i];
      for (int j = 0; j < 9; ++j) EXPECT_EQ(t.P(i, j), s.P(i, j)) << type << " " << i << "," << j;
    }
    // A filter without the states takes the pose and the speed, and drops the rest.
    FilterConfig plain = config(type);
    auto p = makeFilter(plain, {});
    p->initialize(s);
    EXPECT_EQ(p->state().x.size(), 5) << type;
    EXPECT_EQ(p->state().x.head<5>(), s.x.head<5>()) << type;
  }
}
