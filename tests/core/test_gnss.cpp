// GNSS filters (tvekf, ukf_gps): each stage against hand-worked values, gates, bad input,
// saturation, outage, lock-out, and their place in the engine (re-localization:
// test_gnss_relocalization.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "lcmloc/core/engine.hpp"
#include "lcmloc/core/gnss_model.hpp"

using namespace lcmloc::core;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
const std::vector<std::string> kGnssTypes{"tvekf", "ukf_gps"};

FilterConfig gnssConfig(const std::string& type) {
  FilterConfig c;
  c.type = type;
  c.initial_pose = Vec3(0.0, 0.0, 0.0);
  c.p0_diag = Vec3(4.0, 4.0, 0.01);
  c.gnss.use_magnetometer = false;
  return c;
}

OdometryInput odo(int64_t utime, double ds, double psi = 0.0) {
  OdometryInput o;
  o.utime = utime;
  o.delta_s = ds;
  o.steering = psi;
  o.has_steering = true;
  return o;
}

ImuInput imu(int64_t utime, double ax, double heading = 0.0, double decl = 0.0) {
  ImuInput m;
  m.utime = utime;
  m.accel = Vec3(ax, 0.0, 9.81);
  m.mag = gnss::earthFieldBody(heading, decl, 0.2, -0.4);
  return m;
}

GpsInput gps(int64_t utime, double x, double y, double sd = 2.0) {
  GpsInput g;
  g.utime = utime;
  g.x = x;
  g.y = y;
  g.position_std = sd;
  return g;
}

/// Drives straight east at v [m/s] for `seconds` (odometry + IMU at 100 Hz), optional GPS at
/// 1 Hz from the truth shifted by `gps_offset`.
struct Drive {
  int64_t t = 1'000'000;
  double x = 0.0;  ///< true position along X
  void run(Filter& f, double v, double seconds, bool with_gps, double gps_offset = 0.0,
           std::vector<GateDecision>* decisions = nullptr) {
    const int steps = static_cast<int>(std::lround(seconds * 100));
    for (int k = 0; k < steps; ++k) {
      t += 10'000;
      x += v * 0.01;
      f.predict(odo(t, v * 0.01));
      f.update(imu(t, 0.0));
      if (with_gps && (t / 10'000) % 100 == 0) {
        auto d = f.update(gps(t, x + gps_offset, 0.0));
        if (d && decisions) decisions->push_back(*d);
      }
    }
  }
};

double posVar(const FilterState& s) { return s.P(0, 0) + s.P(1, 1); }

}  // namespace

TEST(GnssModel, DerivedKinematicMatricesAndStep) {
  const double T = 0.5;
  const Mat2 A = gnss::kinematicA(T);
  const Vec2 B = gnss::kinematicB(T);
  EXPECT_DOUBLE_EQ(A(0, 1), 0.5);   // the printed A has 1 here: garbled
  EXPECT_DOUBLE_EQ(A(1, 0), 0.0);
  EXPECT_DOUBLE_EQ(B[0], 0.125);    // T^2 / 2 (printed: T)
  EXPECT_DOUBLE_EQ(B[1], 0.5);      // T (printed: 1)
  // From s = 0, v = 1, a = 2 for 0.5 s: s = 0.5 + 0.25 = 0.75, v = 2.
  const Vec2 x = gnss::kinematicStep(Vec2(0.0, 1.0), 2.0, T);
  EXPECT_DOUBLE_EQ(x[0], 0.75);
  EXPECT_DOUBLE_EQ(x[1], 2.0);
  EXPECT_DOUBLE_EQ((A * Vec2(0.0, 1.0) + B * 2.0 - x).norm(), 0.0);
  // eq. 10: v tan(psi) / L; eq. 17: 10 m/s for 0.1 s heading north -> +1 m in y.
  EXPECT_NEAR(gnss::headingRate(10.0, std::atan(0.25), 2.5), 1.0, 1e-12);
  const Vec2 p = gnss::positionStep(Vec2(1.0, 2.0), 10.0, M_PI / 2, 0.1);
  EXPECT_NEAR(p[0], 1.0, 1e-12);
  EXPECT_NEAR(p[1], 3.0, 1e-12);
}

TEST(GnssModel, MagnetometerHeadingWithDeclination) {
  // Heading east, no declination: magnetic north (world +Y) is on the body's left (+y).
  const Vec3 m = gnss::earthFieldBody(0.0, 0.0, 0.2, -0.4);
  EXPECT_NEAR(m[0], 0.0, 1e-12);
  EXPECT_NEAR(m[1], 0.2, 1e-12);
  EXPECT_DOUBLE_EQ(m[2], -0.4);
  for (double th : {-3.0, -1.0, 0.0, 0.7, 2.9})
    for (double d : {-0.2, 0.0, 0.15})
      EXPECT_NEAR(gnss::magnetometerHeading(gnss::earthFieldBody(th, d, 0.2, -0.4), d), th, 1e-12);
  // Ignoring a 0.1 rad east declination reads the heading 0.1 rad too far left (CCW).
  EXPECT_NEAR(gnss::magnetometerHeading(gnss::earthFieldBody(0.5, 0.1, 0.2, -0.4), 0.0), 0.6, 1e-12);
  EXPECT_TRUE(std::isnan(gnss::magnetometerHeading(Vec3(0, 0, -0.4), 0.0)));
}

TEST(Tvekf, KinematicFilterStepAgainstHandWorkedValues) {
  // §2.1, one step T = 0.1 s, a = 1, encoder 0.02 m, from s = v = 0, P = diag(0.01, 1):
  // P- = A P A' + B B' 0.25 = [0.02000625 0.100125; 0.100125 1.0025], x- = [0.005, 0.1],
  // F = P- C' / (C P- C' + 0.01), x = x- + F (0.02 - 0.005).
  FilterConfig c = gnssConfig("tvekf");
  c.gnss.encoder_std = 0.1;
  c.gnss.speed_std0 = 1.0;
  c.gnss.accel_std = 0.5;
  auto f = makeFilter(c, {});
  f->predict(odo(1'000'000, 0.5));   // starts the clock; this increment precedes the filter
  f->update(imu(1'050'000, 1.0));
  f->predict(odo(1'100'000, 0.02));
  const FilterState s = f->state();
  ASSERT_EQ(s.names[3], "speed");
  ASSERT_EQ(s.names[4], "distance");
  EXPECT_NEAR(s.x[4], 0.0150010414497, 1e-12);
  EXPECT_NEAR(s.x[3], 0.150052072485, 1e-11);
  EXPECT_NEAR(s.P(4, 4), 0.00666736096647, 1e-12);
  EXPECT_NEAR(s.P(3, 4), 0.0333680483233, 1e-12);
  EXPECT_NEAR(s.P(3, 3), 0.668402416163, 1e-11);
}

TEST(Tvekf, HeadingAndPositionGainsAgainstHandWorkedValues) {
  FilterConfig c = gnssConfig("tvekf");
  c.gnss.use_magnetometer = true;
  c.gnss.mag_std = 0.1;   // R = 0.01, P_theta = 0.01 -> L = 0.5
  auto f = makeFilter(c, {});
  auto d = f->update(imu(1, 0.0, 0.1));
  ASSERT_TRUE(d);
  EXPECT_TRUE(d->accepted);
  EXPECT_NEAR(d->innovation[0], 0.1, 1e-12);
  EXPECT_NEAR(d->mahalanobis, 0.5, 1e-12);          // 0.1^2 / 0.02
  EXPECT_NEAR(d->gate, 6.634896601, 1e-6);           // chi2 99 %, 1 dof
  EXPECT_NEAR(f->state().x[2], 0.05, 1e-12);
  EXPECT_NEAR(f->state().P(2, 2), 0.005, 1e-12);
  // Second sample: the gain is recomputed, L = 0.005 / 0.015 = 1/3.
  d = f->update(imu(2, 0.0, 0.05 + 0.03));
  EXPECT_NEAR(f->state().x[2], 0.06, 1e-12);
  EXPECT_NEAR(f->state().P(2, 2), 0.005 * 2.0 / 3.0, 1e-12);
  // §2.3: P_p = 4 I, R = 4 I -> J = 0.5 I; fix (2, -4): tau = 20 / 8 = 2.5.
  d = f->update(gps(3, 2.0, -4.0, 2.0));
  ASSERT_TRUE(d);
  EXPECT_TRUE(d->accepted);
  EXPECT_EQ(d->reason, "accepted");
  EXPECT_NEAR(d->mahalanobis, 2.5, 1e-12);
  EXPECT_NEAR(d->gate, 9.210340372, 1e-6);
  EXPECT_NEAR(f->state().x[0], 1.0, 1e-12);
  EXPECT_NEAR(f->state().x[1], -2.0, 1e-12);
  EXPECT_NEAR(f->state().P(0, 0), 2.0, 1e-12);
  EXPECT_EQ(f->state().status, FilterStatus::Ok);
}

TEST(Tvekf, PredictionFollowsEq10AndEq17) {
  FilterConfig c = gnssConfig("tvekf");
  auto f = makeFilter(c, {});
  FilterState s0 = f->state();
  s0.x[3] = 10.0;  // speed 10 m/s
  f->initialize(s0);
  const double psi = std::atan(0.25);  // heading rate 10 * 0.25 / 2.5 = 1 rad/s
  f->predict(odo(1'000'000, 0.1, psi));
  f->update(imu(1'000'000, 0.0));
  f->predict(odo(1'010'000, 0.1, psi));
  const FilterState s = f->state();
  EXPECT_NEAR(s.x[0], 0.1, 1e-9);      // eq. 17 with theta(k) = 0
  EXPECT_NEAR(s.x[1], 0.0, 1e-9);
  EXPECT_NEAR(s.x[2], 0.01, 1e-9);     // eq. 10: T v tan(psi) / L
  EXPECT_NEAR(s.x[3], 10.0, 1e-3);
}

TEST(GnssFilters, GateNoFixNaNAndJump) {
  for (const auto& type : kGnssTypes) {
    auto f = makeFilter(gnssConfig(type), {});
    EXPECT_TRUE(f->uses(Measurement::Gps));
    EXPECT_FALSE(f->uses(Measurement::Ruler));
    Drive drive;
    std::vector<GateDecision> dec;
    drive.run(*f, 10.0, 10.0, true, 0.0, &dec);
    ASSERT_EQ(dec.size(), 10u) << type;
    for (const auto& d : dec) EXPECT_TRUE(d.accepted) << type << " tau " << d.mahalanobis;
    const FilterState before = f->state();
    GpsInput nofix = gps(drive.t, drive.x, 0.0);
    nofix.has_fix = false;
    auto d = f->update(nofix);
    ASSERT_TRUE(d);
    EXPECT_EQ(d->reason, "no_fix") << type;
    d = f->update(gps(drive.t, kNaN, 0.0));
    EXPECT_EQ(d->reason, "bad_input") << type;
    d = f->update(gps(drive.t, drive.x + 100.0, 0.0));  // a 100 m jump
    EXPECT_FALSE(d->accepted) << type;
    EXPECT_EQ(d->reason, "gate") << type;
    EXPECT_GT(d->mahalanobis, 100.0) << type;
    EXPECT_EQ(f->state().x, before.x) << type;
    EXPECT_EQ(f->state().P, before.P) << type;
    EXPECT_EQ(f->state().status, FilterStatus::Ok) << type;  // one jump is no lock-out
    // the next good fix is accepted
    drive.run(*f, 10.0, 1.0, true, 0.0, &dec);
    EXPECT_TRUE(dec.back().accepted) << type;
  }
}

TEST(GnssFilters, SaturatedAccelerationIsNotUsed) {
  // Constant 10 m/s; every 10th IMU sample is a saturated +20 m/s^2 spike (pothole).
  auto run = [](const std::string& type, double saturation) {
    FilterConfig c = gnssConfig(type);
    c.gnss.accel_saturation = saturation;
    c.gnss.encoder_std = 0.05;
    auto f = makeFilter(c, {});
    FilterState s0 = f->state();
    s0.x[3] = 10.0;
    f->initialize(s0);
    int64_t t = 0;
    double worst = 0.0;
    for (int k = 0; k < 500; ++k) {
      t += 10'000;
      f->predict(odo(t, 0.1));
      f->update(imu(t, k % 10 == 0 ? 20.0 : 0.0));
      worst = std::max(worst, std::abs(f->state().x[3] - 10.0));
    }
    return worst;
  };
  for (const auto& type : kGnssTypes) {
    const double with_check = run(type, 19.9), without = run(type, 0.0);
    EXPECT_LT(with_check, 0.01) << type;
    EXPECT_GT(without, 5.0 * with_check) << type;
  }
}

TEST(GnssFilters, OutageCoastsCovarianceGrowsAndRecovers) {
  for (const auto& type : kGnssTypes) {
    FilterConfig c = gnssConfig(type);
    auto f = makeFilter(c, {});
    Drive drive;
    drive.run(*f, 10.0, 10.0, true);
    EXPECT_EQ(f->state().status, FilterStatus::Ok) << type;
    double var = posVar(f->state());
    for (int s = 0; s < 20; ++s) {  // 20 s without GPS
      drive.run(*f, 10.0, 1.0, false);
      const double v = posVar(f->state());
      EXPECT_GT(v, var) << type << " at " << s;
      var = v;
    }
    EXPECT_EQ(f->state().status, FilterStatus::DeadReckoning) << type;
    EXPECT_LT(std::abs(f->state().x[0] - drive.x), 2.0) << type;  // coasted on the encoder
    std::vector<GateDecision> dec;
    drive.run(*f, 10.0, 2.0, true, 0.0, &dec);
    ASSERT_FALSE(dec.empty());
    EXPECT_TRUE(dec.front().accepted) << type;
    EXPECT_EQ(f->state().status, FilterStatus::Ok) << type;
    EXPECT_LT(posVar(f->state()), var) << type;
  }
}

TEST(GnssFilters, GpsLockoutDeadReckonsWithoutInflation) {
  // 20 minutes of fixes 10 km off, each in another direction (never two alike): every fix is
  // refused, none re-localizes (they do not agree with each other), the status is LOCKOUT, and
  // the state, covariance included, is that of the same drive without GPS: the covariance grows
  // by the dead reckoning's own noise only (the GPS lock-out inflates nothing).
  for (const auto& type : kGnssTypes) {
    FilterConfig c = gnssConfig(type);
    auto f = makeFilter(c, {}), twin = makeFilter(c, {});
    Drive drive, twin_drive;
    int refused = 0;
    for (int s = 0; s < 1200; ++s) {
      drive.run(*f, 10.0, 1.0, false);
      twin_drive.run(*twin, 10.0, 1.0, false);
      const double a = s * 2.39996;  // the golden angle
      const auto d = f->update(gps(drive.t, drive.x + 1e4 * std::cos(a), 1e4 * std::sin(a)));
      ASSERT_TRUE(d);
      refused += d->reason == "gate";
      ASSERT_FALSE(f->takeRelocalization()) << type << " at " << s;
    }
    EXPECT_EQ(refused, 1200) << type;
    const FilterState st = f->state(), ts = twin->state();
    EXPECT_EQ(st.status, FilterStatus::Lockout) << type;
    ASSERT_TRUE(st.x.allFinite() && st.P.allFinite()) << type;
    EXPECT_LT((st.x - ts.x).norm(), 1e-9) << type;
    EXPECT_LT((st.P - ts.P).norm(), 1e-9 * ts.P.norm()) << type;
  }
}

TEST(GnssFilters, APoseFixLosesNoMotion) {
  // 10 m/s with odometry at 10 Hz; a pose fix placed exactly on the estimate (as a landmark fix,
  // set_pose, a hot swap or a checkpoint start re-initializes the filter). The next second must
  // advance as far as without the fix: the filter used to take the first increment after an
  // initialization only to start its clock, and fell v T = 1 m behind at every fix.
  for (const auto& type : kGnssTypes) {
    auto f = makeFilter(gnssConfig(type), {});
    FilterState s0 = f->state();
    s0.x[3] = 10.0;
    f->initialize(s0);
    auto twin = makeFilter(gnssConfig(type), {});
    twin->initialize(s0);
    int64_t t = 1'000'000;
    auto second = [&] {
      for (int k = 0; k < 10; ++k) {
        t += 100'000;
        for (Filter* g : {f.get(), twin.get()}) {
          g->predict(odo(t, 1.0));
          g->update(imu(t, 0.0));
        }
      }
    };
    second();
    const FilterState before = f->state();
    ASSERT_EQ(before.x, twin->state().x);
    PoseFix fix;
    fix.utime = t;
    fix.pose = before.x.head<3>();
    fix.cov = before.P.topLeftCorner<3, 3>();
    ASSERT_TRUE(f->applyFix(fix));
    second();
    const double moved = f->state().x[0] - before.x[0], twin_moved = twin->state().x[0] - before.x[0];
    EXPECT_NEAR(twin_moved, 10.0, 0.1) << type;  // (ukf_gps: the UKF mean of cos(theta) < 1)
    EXPECT_NEAR(moved, twin_moved, 0.01) << type;
    // A state far older than the next increment (a daemon started from its checkpoint 30 s
    // after a crash): the motion in between is unknown, not v T along the old heading (300 m).
    FilterState old = f->state();
    old.utime = t;
    f->initialize(old);
    t += 30'000'000;
    f->predict(odo(t, 1.0));
    EXPECT_NEAR(f->state().x[0], old.x[0], 1e-9) << type;
  }
}

TEST(GnssFilters, HotSwapKeepsPoseSpeedAndDistance) {
  auto a = makeFilter(gnssConfig("tvekf"), {});
  Drive drive;
  drive.run(*a, 8.0, 5.0, true);
  auto b = makeFilter(gnssConfig("ukf_gps"), {});
  b->initialize(a->state());
  EXPECT_EQ(b->state().x, a->state().x);
  drive.run(*a, 8.0, 5.0, true);
  drive.run(*b, 8.0, 0.0, false);
  FilterState from_a = a->state();
  // a ruler filter takes x, y, theta; its state names do not include speed
  FilterConfig rc;
  rc.type = "ukf_gated";
  auto r = makeFilter(rc, {});
  r->initialize(from_a);
  EXPECT_EQ(r->state().x.head<3>(), from_a.x.head<3>());
}

TEST(GnssEngine, MeasurementsGoOnlyToFiltersThatUseThem) {
  EngineConfig ec;
  ec.filter = gnssConfig("tvekf");
  ec.shadow = {"ukf_gated", "ukf_gps"};
  std::vector<std::pair<std::string, GateDecision>> decisions;
  std::vector<std::string> events;
  EngineOutputs out;
  out.on_decision = [&](const std::string& f, bool, const GateDecision& d) { decisions.push_back({f, d}); };
  out.on_event = [&](const EngineEvent& e) { events.push_back(eventName(e.kind)); };
  MarkerMap map{{0, 100.0, 0.0}};
  FusionEngine engine(ec, map, out);
  int64_t t = 1'000'000, seq = 0;
  engine.push({"ODOMETRY", seq++, t, odo(t, 0.0)});
  engine.push({"IMU", seq++, t, imu(t, 0.0)});
  GpsInput g = gps(t + 10, 0.5, 0.5);
  engine.push({"GPS", seq++, t + 10, g});
  RulerDetection det;
  det.utime = t + 20;
  engine.push({"MAGRULER", seq++, t + 20, det});
  ImuInput bad = imu(t + 30, kNaN);
  engine.push({"IMU", seq++, t + 30, bad});
  engine.flush();
  // GPS: decisions from tvekf and ukf_gps only; ruler: from ukf_gated only; IMU without the
  // magnetometer: none; NaN IMU: a bad_input event.
  ASSERT_EQ(decisions.size(), 3u);
  EXPECT_EQ(decisions[0].first, "tvekf");
  EXPECT_EQ(decisions[0].second.sensor, "GPS");
  EXPECT_EQ(decisions[1].first, "ukf_gps");
  EXPECT_EQ(decisions[2].first, "ukf_gated");
  EXPECT_EQ(decisions[2].second.sensor, "MAGRULER");
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0], "bad_input");
  EXPECT_EQ(engine.counters().accepted, 1);
}

TEST(GnssEngine, LockoutRelocalizationAndRecoveryEventsForGps) {
  // GPS only: six fixes 500 m off in different directions (refused, no two agree: a lock-out
  // after five), then fixes at (80, 0): the second of them agrees with the first and the filter,
  // whose start no fix confirmed, re-localizes there (event with its evidence) and leaves the
  // lock-out.
  EngineConfig ec;
  ec.filter = gnssConfig("tvekf");
  ec.filter.p0_diag = Vec3(1.0, 1.0, 0.01);
  std::vector<std::string> events;
  EngineOutputs out;
  out.on_event = [&](const EngineEvent& e) { events.push_back(eventName(e.kind)); };
  FusionEngine engine(ec, {}, out);
  for (int k = 0; k < 12; ++k) {
    const int64_t t = 1'000'000 + k * 1'000'000;
    const double a = k * 2.39996;
    engine.push({"GPS", k, t, k < 6 ? gps(t, 500.0 * std::cos(a), 500.0 * std::sin(a)) : gps(t, 80.0, 0.0)});
  }
  engine.flush();
  ASSERT_EQ(events.size(), 3u);
  EXPECT_EQ(events[0], "lockout");
  EXPECT_EQ(events[1], "relocalized");
  EXPECT_EQ(events[2], "recovered");
  EXPECT_NEAR(engine.activeState().x[0], 80.0, 1.0);
}

// A saturated IMU sample is not used (above) and shows on FUSION_STATUS: one "imu_saturated"
// event at the start of each saturated stretch, not one per sample; none without saturation.
TEST(GnssEngine, SaturatedImuStretchesAreReportedOncePerStretch) {
  EngineConfig ec;
  ec.filter = gnssConfig("ukf_gps");
  ec.filter.gnss.accel_saturation = 19.9;
  ec.shadow = {"tvekf"};
  std::vector<std::pair<std::string, std::string>> events;
  EngineOutputs out;
  out.on_event = [&](const EngineEvent& e) { events.push_back({eventName(e.kind), eventText(e)}); };
  FusionEngine engine(ec, {}, out);
  for (int k = 0; k < 100; ++k) {
    const int64_t t = 1'000'000 + k * 10'000;
    engine.push({"ODOMETRY", k, t, odo(t, 0.1)});
    const bool spike = (k >= 10 && k < 13) || k == 50;
    engine.push({"IMU", k, t, imu(t, spike ? 20.5 : 0.3)});
  }
  engine.flush();
  std::vector<std::string> details;
  for (const auto& [e, d] : events)
    if (e == "imu_saturated") details.push_back(d);
  ASSERT_EQ(details.size(), 2u);
  EXPECT_NE(details[0].find("IMU seq 10: forward acceleration 20.50 m/s^2"), std::string::npos) << details[0];
  EXPECT_NE(details[0].find("gnss.accel_saturation 19.90"), std::string::npos) << details[0];
  EXPECT_NE(details[0].find("by ukf_gps (1 samples so far)"), std::string::npos) << details[0];
  EXPECT_NE(details[1].find("IMU seq 50"), std::string::npos) << details[1];
  EXPECT_NE(details[1].find("(4 samples so far)"), std::string::npos) << details[1];

  // Without a saturation limit nothing is reported.
  ec.filter.gnss.accel_saturation = 0.0;
  events.clear();
  FusionEngine unlimited(ec, {}, out);
  for (int k = 0; k < 20; ++k) unlimited.push({"IMU", k, 1'000'000 + k * 10'000, imu(1'000'000 + k * 10'000, 20.5)});
  unlimited.flush();
  for (const auto& [e, d] : events) EXPECT_NE(e, "imu_saturated") << d;
}

TEST(GnssFilters, InvalidConfigIsRefused) {
  FilterConfig c = gnssConfig("tvekf");
  c.gnss.mag_std = 0.0;
  EXPECT_THROW(makeFilter(c, {}), std::invalid_argument);
  c = gnssConfig("ukf_gps");
  c.gnss.gps_std = kNaN;
  try {
    makeFilter(c, {});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("gnss.gps_std"), std::string::npos);
  }
}

TEST(GnssEngine, ABrokenFilterIsRepairedBySwitchAndSetPoseNotFatal) {
  // An absurd IMU sample handed to the engine directly (the daemon refuses it) makes the GNSS
  // filters' state infinite. Switching away from such a filter, or setting its pose, threw out of
  // FusionEngine::push and stopped the daemon; now the new filter (or the filter to be set) starts
  // from its configured initial state, and says so.
  EngineConfig ec;
  ec.filter = gnssConfig("tvekf");
  ec.shadow = {"ukf_gps"};
  ec.reorder_window_us = 0;
  std::vector<std::pair<std::string, std::string>> events;
  EngineOutputs out;
  out.on_event = [&](const EngineEvent& e) { events.emplace_back(eventName(e.kind), eventText(e)); };
  FusionEngine engine(ec, {}, out);
  int64_t t = 1'000'000, seq = 0;
  for (int k = 0; k < 10; ++k, t += 10'000) {
    engine.push({"ODOMETRY", seq++, t, odo(t, 0.1)});
    engine.push({"IMU", seq++, t, imu(t, k == 1 ? 1e200 : 0.0)});
  }
  ASSERT_FALSE(engine.activeState().x.allFinite() && engine.activeState().P.allFinite())
      << "the sample no longer breaks the filter: this test needs another way to break it";
  FilterConfig to = gnssConfig("ukf_gps");
  ASSERT_NO_THROW({
    engine.push({"FUSION_CONTROL", seq++, t, ControlCommand(SwitchFilter{to})});
    engine.flush();
  });
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events.back().first, "ack");
  EXPECT_NE(events.back().second.find("started from its configured initial state"), std::string::npos)
      << events.back().second;
  EXPECT_EQ(engine.activeFilter(), "ukf_gps");
  EXPECT_TRUE(engine.activeState().x.allFinite() && engine.activeState().P.allFinite());

  // set_pose on a broken filter: tvekf active again, broken again
  ASSERT_NO_THROW({
    engine.push({"FUSION_CONTROL", seq++, t, ControlCommand(SwitchFilter{gnssConfig("tvekf")})});
    engine.flush();
  });
  for (int k = 0; k < 10; ++k, t += 10'000) {
    engine.push({"ODOMETRY", seq++, t, odo(t, 0.1)});
    engine.push({"IMU", seq++, t, imu(t, k == 1 ? 1e200 : 0.0)});
  }
  ASSERT_FALSE(engine.activeState().x.allFinite() && engine.activeState().P.allFinite());
  events.clear();
  ASSERT_NO_THROW({
    engine.push({"FUSION_CONTROL", seq++, t, ControlCommand(SetPose{Pose(5.0, 6.0, 0.3), Vec3(1.0, 1.0, 0.1)})});
    engine.flush();
  });
  const FilterState s = engine.activeState();
  ASSERT_TRUE(s.x.allFinite() && s.P.allFinite());
  EXPECT_NEAR(s.x[0], 5.0, 1e-9);
  EXPECT_NEAR(s.x[1], 6.0, 1e-9);
  EXPECT_NEAR(s.x[2], 0.3, 1e-9);
  // (tvekf's broken entries were all in the pose rows the fix replaces; the shadow ukf_gps had to
  // start again)
  bool restarted = false;
  for (const auto& [e, d] : events) restarted |= e == "restarted" && d.find("ukf_gps: ") == 0;
  EXPECT_TRUE(restarted);
  EXPECT_EQ(events.back().first, "ack");
}
