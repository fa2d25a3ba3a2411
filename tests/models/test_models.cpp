// Unit tests of the simulated world and sensor models.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

#include "lcmloc/core/ruler_model.hpp"
#include "lcmloc/core/vehicle_model.hpp"
#include "lcmloc/sim/gnss_sensors.hpp"
#include "lcmloc/sim/schedule.hpp"
#include "lcmloc/sim/world.hpp"

using namespace lcmloc;
using namespace lcmloc::sim;

namespace {
constexpr double kPi = 3.14159265358979323846;

TruthState straightTruth(int64_t utime, double distance, double steering = 0.0) {
  TruthState t;
  t.utime = utime;
  t.distance = distance;
  t.y = distance;
  t.heading = kPi / 2;
  t.steering = steering;
  return t;
}
}  // namespace

TEST(Path, SegmentsOfConstantCurvature) {
  const Path path(PathConfig{});  // 12 m straight north, 14 m at 0.06 1/m, 16 m straight
  EXPECT_DOUBLE_EQ(path.length(), 42.0);
  const core::Pose p12 = path.poseAt(12.0);
  EXPECT_NEAR(p12.x(), 0.0, 1e-12);
  EXPECT_NEAR(p12.y(), 12.0, 1e-12);
  EXPECT_NEAR(p12.z(), kPi / 2, 1e-12);
  // End of the arc: centre of the circle at (-1/k, 12), heading turned by k*14 = 0.84 rad.
  const double k = 0.06, r = 1.0 / k;
  const core::Pose p26 = path.poseAt(26.0);
  EXPECT_NEAR(p26.x(), -r + r * std::cos(0.84), 1e-9);
  EXPECT_NEAR(p26.y(), 12.0 + r * std::sin(0.84), 1e-9);
  EXPECT_NEAR(p26.z(), kPi / 2 + 0.84, 1e-12);
  EXPECT_DOUBLE_EQ(path.curvatureAt(20.0), 0.06);
  EXPECT_DOUBLE_EQ(path.curvatureAt(30.0), 0.0);
  // The last straight keeps the heading; beyond the end the path extends straight on.
  const core::Pose p42 = path.poseAt(42.0), p44 = path.poseAt(44.0);
  EXPECT_NEAR(p42.z(), p26.z(), 1e-12);
  EXPECT_NEAR(std::hypot(p44.x() - p42.x(), p44.y() - p42.y()), 2.0, 1e-9);
  // Projection of a point 0.3 m left of the path at s = 20.
  const core::Pose p20 = path.poseAt(20.0);
  const double px = p20.x() - 0.3 * std::sin(p20.z()), py = p20.y() + 0.3 * std::cos(p20.z());
  EXPECT_NEAR(path.project(px, py, 19.0), 20.0, 1e-7);
}

TEST(Path, MarkerMapAtArcLengths) {
  const Path path(PathConfig{});
  const core::MarkerMap map = makeMarkerMap(path, MarkerLayout{});
  ASSERT_EQ(map.size(), 20u);
  for (int i = 0; i < 20; ++i) {
    EXPECT_EQ(map[i].id, i);
    const core::Pose p = path.poseAt(2.0 + 2.0 * i);
    EXPECT_NEAR(map[i].x, p.x(), 1e-12);
    EXPECT_NEAR(map[i].y, p.y(), 1e-12);
  }
  EXPECT_NEAR(map[0].y, 2.0, 1e-12);
  EXPECT_NEAR(std::hypot(map[1].x - map[0].x, map[1].y - map[0].y), 2.0, 1e-12);
}

TEST(Path, RespacedMarkersCoverTheSameStretch) {
  const MarkerLayout paper;  // 20 markers 2 m apart from 2 m: the last at 40 m
  MarkerLayout m = respaced(paper, 5.0);
  EXPECT_EQ(m.count, 8);  // 2 .. 37 m: none beyond the old last marker
  EXPECT_EQ(m.spacing, 5.0);
  EXPECT_EQ(m.first_at, 2.0);
  EXPECT_EQ(respaced(paper, 1.0).count, 39);  // 2 .. 40 m
  // 0.3 / 0.1 is 2.9999999999999996 in doubles: still four markers, the last on the old last one
  EXPECT_EQ(respaced(MarkerLayout{2, 0.3, 2.0}, 0.1).count, 4);
  EXPECT_EQ(respaced(paper, 100.0).count, 1);   // wider than the stretch: the first marker only
  EXPECT_EQ(respaced(MarkerLayout{1, 2.0, 3.0}, 4.0).count, 1);
  EXPECT_EQ(respaced(MarkerLayout{0, 2.0, 3.0}, 4.0).count, 0);  // no markers stay none
}

TEST(Seeds, ComponentSeedsAreStableAndDistinct) {
  EXPECT_EQ(componentSeed(1, "vehicle"), componentSeed(1, "vehicle"));
  EXPECT_NE(componentSeed(1, "vehicle"), componentSeed(1, "odometry"));
  EXPECT_NE(componentSeed(1, "vehicle"), componentSeed(2, "vehicle"));
}

TEST(VehicleSim, FollowsPathWithinWeaveAndStops) {
  const ScenarioConfig sc;
  const Path path(sc.path);
  const double stop_at = 40.0 + sc.vehicle.end_margin;
  VehicleSim sim(sc.vehicle, path, stop_at, 7);
  double hint = 0.0, max_lateral = 0.0, max_speed = 0.0, max_steer = 0.0;
  int64_t last_utime = sim.state().utime;
  EXPECT_EQ(last_utime, sc.vehicle.start_utime);
  int steps = 0;
  while (!sim.finished() && steps < 100000) {
    const TruthState& t = sim.step();
    ++steps;
    EXPECT_EQ(t.utime - last_utime, 10000);
    last_utime = t.utime;
    hint = path.project(t.x, t.y, hint);
    const core::Pose p = path.poseAt(hint);
    const double lateral = -(t.x - p.x()) * std::sin(p.z()) + (t.y - p.y()) * std::cos(p.z());
    max_lateral = std::max(max_lateral, std::abs(lateral));
    max_speed = std::max(max_speed, t.speed);
    max_steer = std::max(max_steer, std::abs(t.steering));
  }
  ASSERT_TRUE(sim.finished());
  std::printf("vehicle: %d samples, max |lateral| %.4f m, max speed %.3f m/s, stop at arc %.4f\n",
              steps, max_lateral, max_speed, hint);
  EXPECT_LE(max_lateral, sc.vehicle.weave_amplitude + 0.03);
  EXPECT_GE(max_lateral, 0.5 * sc.vehicle.weave_amplitude);  // the weave is really there
  EXPECT_NEAR(max_speed, sc.vehicle.speed, 1e-9);
  EXPECT_LE(max_steer, sc.vehicle.max_steering);
  EXPECT_NEAR(hint, stop_at, 0.01);
  EXPECT_EQ(sim.state().speed, 0.0);
  EXPECT_NEAR(sim.state().distance, stop_at, 0.1);  // weave and corner cutting: a few cm
}

TEST(Schedule, TicksAfterNowInOneStepAndRestartsWhenTimeGoesBack) {
  int64_t next = 1000;
  EXPECT_FALSE(scheduleDue(next, 999, 100));
  EXPECT_EQ(next, 1000);
  EXPECT_TRUE(scheduleDue(next, 1000, 100));
  EXPECT_EQ(next, 1100);
  EXPECT_TRUE(scheduleDue(next, 1350, 100));  // ticks 1100..1300 passed: the next after now
  EXPECT_EQ(next, 1400);
  EXPECT_TRUE(scheduleDue(next, int64_t{1} << 60, 100));  // one step, not 10^16
  EXPECT_GT(next, int64_t{1} << 60);
  EXPECT_TRUE(scheduleDue(next, 1500, 100));  // back in time: restarts at now
  EXPECT_EQ(next, 1600);
  EXPECT_TRUE(scheduleDue(next, std::numeric_limits<int64_t>::max() - 5, 100));  // no overflow
  EXPECT_EQ(next, std::numeric_limits<int64_t>::max());
}

TEST(OdometrySensor, AGroundTruthWithACorruptUtimeNeitherHangsNorSilencesTheSensor) {
  OdometrySensor odo(OdometrySensorConfig{}, 2.5, 3);  // 100 Hz
  int emitted_after = 0;
  for (int k = 0; k < 200; ++k) {
    TruthState t = straightTruth(1000000 + 10000 * k, 0.01 * k);
    if (k == 100) t.utime = int64_t{1} << 60;  // a flipped high bit
    const auto s = odo.sample(t);
    if (k > 101 && s) ++emitted_after;
  }
  EXPECT_EQ(emitted_after, 98);  // every truth sample after the corrupt one and its successor
}

TEST(OdometrySensor, QuantizationScaleAndBias) {
  OdometrySensorConfig cfg;
  cfg.scale_error = 0.01;
  cfg.steering_bias = 0.008727;
  cfg.rate_hz = 50.0;  // every second truth sample at 100 Hz
  OdometrySensor odo(cfg, 2.5, 3);
  const double speed = 1.5, steer = 0.1;
  double sum_ds = 0.0, sum_bias = 0.0;
  int n = 0;
  for (int k = 0; k <= 10000; ++k) {  // 100 s at 100 Hz: 150 m
    auto s = odo.sample(straightTruth(1000000 + 10000 * k, speed * 0.01 * k, steer));
    if (k == 0 || k % 2 == 1) {
      EXPECT_FALSE(s.has_value()) << k;
      continue;
    }
    ASSERT_TRUE(s.has_value()) << k;
    ++n;
    EXPECT_EQ(s->input.utime, 1000000 + 10000 * k);
    EXPECT_DOUBLE_EQ(s->input.delta_s, s->ticks * cfg.tick_length);
    EXPECT_TRUE(s->input.has_steering);
    const double q = s->input.steering / cfg.steering_resolution;
    EXPECT_NEAR(q, std::round(q), 1e-9);
    EXPECT_DOUBLE_EQ(s->input.delta_theta,
                     core::headingIncrement(s->input.delta_s, s->input.steering, 2.5));
    sum_ds += s->input.delta_s;
    sum_bias += s->input.steering - steer;
  }
  EXPECT_EQ(n, 5000);
  const double true_total = speed * 0.01 * 10000;
  // Slip: std 0.002 * sqrt(150) = 2.4 cm; quantization never accumulates (< 1 tick).
  const double scale_meas = sum_ds / true_total - 1.0;
  std::printf("odometry: measured scale error %.5f (true 0.01), steering bias %.6f (true %.6f)\n",
              scale_meas, sum_bias / n, cfg.steering_bias);
  EXPECT_NEAR(sum_ds, 1.01 * true_total, 5 * 0.002 * std::sqrt(true_total) + cfg.tick_length);
  // Bias: noise 0.002 / sqrt(5000) plus quantization (<= 0.00025 bias possible).
  EXPECT_NEAR(sum_bias / n, cfg.steering_bias, 0.0003);
}

TEST(OdometrySensor, SlipNoiseGrowsWithSqrtDistance) {
  OdometrySensorConfig cfg;
  cfg.scale_error = 0.0;
  cfg.slip_std = 0.01;
  std::vector<double> err;
  for (int seed = 0; seed < 400; ++seed) {
    OdometrySensor odo(cfg, 2.5, componentSeed(seed, "odometry"));
    double total = 0.0;
    for (int k = 0; k <= 1000; ++k)  // 10 m
      if (auto s = odo.sample(straightTruth(10000 * k, 0.01 * k))) total += s->input.delta_s;
    err.push_back(total - 10.0);
  }
  double m = 0.0, v = 0.0;
  for (double e : err) m += e / err.size();
  for (double e : err) v += (e - m) * (e - m) / (err.size() - 1);
  // Expected std 0.01 * sqrt(10) = 0.0316 m; the tick floor biases the mean by < 1 mm.
  EXPECT_NEAR(std::sqrt(v), 0.01 * std::sqrt(10.0), 0.005);
  EXPECT_NEAR(m, 0.0, 0.006);
}

TEST(MagneticRuler, DipoleFieldAgainstHandValues) {
  // On the axis: mu0/(4 pi) * 2 m / h^3 = 1e-7 * 10 / 0.1925^3 T = 1e-6 / 0.007133328 T
  // = 1.401870e-4 T = 1.401870 gauss.
  EXPECT_NEAR(dipoleVerticalField(5.0, 0.0, 0.1925), 1.401870, 1e-6);
  // rho = dz = 0.2: cos^2 = 0.5, r^3 = 0.0226274: 1e-7 * 5 * 0.5 / r^3 T = 0.110485 gauss.
  EXPECT_NEAR(dipoleVerticalField(5.0, 0.2, 0.2), 0.110485, 1e-5);
  // The vertical component vanishes where cos^2 = 1/3 (rho = sqrt(2) dz) and is negative beyond.
  EXPECT_NEAR(dipoleVerticalField(5.0, 0.1925 * std::sqrt(2.0), 0.1925), 0.0, 1e-12);
  EXPECT_LT(dipoleVerticalField(5.0, 0.5, 0.1925), 0.0);
  // The ruler's field includes the Earth's vertical field.
  MagRulerConfig cfg;
  MagneticRuler ruler(cfg, {core::Marker{0, 1.0, 2.0}}, 1);
  EXPECT_NEAR(ruler.fieldAt(1.0, 2.0), cfg.earth_field_z + 1.401870, 1e-6);
  EXPECT_NEAR(ruler.fieldAt(100.0, 2.0), cfg.earth_field_z, 1e-9);
  EXPECT_DOUBLE_EQ(ruler.sensorLateral(0), -0.5);
  EXPECT_DOUBLE_EQ(ruler.sensorLateral(6), 0.0);
  EXPECT_DOUBLE_EQ(ruler.sensorLateral(12), 0.5);
}

TEST(MagneticRuler, FieldOfALongRouteIsTheSumOverEveryMarkerInReach) {
  // The ruler looks markers up in a grid; the field must be exactly what a scan of the whole map
  // in map order gives: markers in clusters (within reach of each other across cell borders),
  // on cell borders, far away (negative coordinates too), one listed twice, and non-finite ones.
  MagRulerConfig cfg;
  const double dz = cfg.height + cfg.marker_depth;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> far(-5000.0, 5000.0), near(-4.0, 4.0);
  core::MarkerMap map;
  for (int i = 0; i < 2000; ++i) {
    const double cx = far(rng), cy = far(rng);
    for (int j = 0; j < 4; ++j) map.push_back(core::Marker{static_cast<int>(map.size()), cx + near(rng), cy + near(rng)});
  }
  for (double b : {-6.0, -3.0, 0.0, 3.0, 6.0}) map.push_back(core::Marker{static_cast<int>(map.size()), b, 0.5 * b});
  map.push_back(map[7]);
  map.push_back(core::Marker{static_cast<int>(map.size()), std::numeric_limits<double>::quiet_NaN(), 0.0});
  map.push_back(core::Marker{static_cast<int>(map.size()), std::numeric_limits<double>::infinity(), 1.0});
  MagneticRuler ruler(cfg, map, 1);
  auto scan = [&](double x, double y) {
    double b = cfg.earth_field_z;
    for (const auto& m : map) {
      const double rho = std::hypot(x - m.x, y - m.y);
      if (rho < 3.0) b += dipoleVerticalField(cfg.dipole_moment, rho, dz);
    }
    return b;
  };
  int with_markers = 0;
  for (int i = 0; i < 6000; ++i) {
    // Half of the points next to a marker, the rest anywhere (mostly in empty road).
    const auto& m = map[static_cast<std::size_t>(i) % 8000];
    const double x = i % 2 ? m.x + near(rng) : far(rng), y = i % 2 ? m.y + near(rng) : far(rng);
    const double want = scan(x, y);
    with_markers += want != cfg.earth_field_z;
    ASSERT_EQ(ruler.fieldAt(x, y), want) << "at (" << x << ", " << y << ")";
  }
  EXPECT_GT(with_markers, 1500);  // most of the points near markers do see them
  for (double b : {-6.0, -3.0, 0.0, 3.0, 6.0}) {
    for (double d : {-2.9, -1.0, -1e-9, 0.0, 1e-9, 1.0, 2.9}) EXPECT_EQ(ruler.fieldAt(b + d, 0.5 * b), scan(b + d, 0.5 * b));
  }
  EXPECT_EQ(ruler.fieldAt(map[7].x, map[7].y), scan(map[7].x, map[7].y));  // the marker listed twice counts twice
  EXPECT_EQ(ruler.fieldAt(std::numeric_limits<double>::quiet_NaN(), 0.0), cfg.earth_field_z);
  EXPECT_EQ(ruler.fieldAt(1e300, -1e300), cfg.earth_field_z);
}

TEST(MagneticRuler, PeakMappingAccuracyAcrossWidth) {
  MagRulerConfig cfg;
  MagneticRuler ruler(cfg, {core::Marker{0, 0.0, 0.0}}, 11);
  // Noise-free, marker on the ruler line.
  double max_clean = 0.0;
  for (int k = -450; k <= 450; ++k) {
    const double d = 1e-3 * k + 0.00037;  // off the calibration grid
    auto est = ruler.peakMap(singleMarkerReadings(cfg, 0.0, d));
    ASSERT_TRUE(est.has_value()) << d;
    max_clean = std::max(max_clean, std::abs(*est - d));
  }
  // With noise, disturbance and sensor gain mismatch (20 rulers), the marker up to half a
  // sample (0.75 cm) along track.
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> along(-0.0075, 0.0075);
  double max_noisy = 0.0, sq = 0.0;
  int n = 0;
  for (uint64_t seed = 0; seed < 20; ++seed) {
    MagneticRuler noisy(cfg, {core::Marker{0, 0.0, 0.0}}, componentSeed(seed, "magruler"));
    for (int k = -450; k <= 450; k += 5) {
      const double d = 1e-3 * k;
      // Heading north: body-left is -x. Marker (0,0) at ruler forward a, left d.
      const double a = along(rng);
      TruthState t;
      t.utime = 1000000 + 10000 * n;
      t.heading = kPi / 2;
      t.x = d;
      t.y = -cfg.ruler_offset - a;
      auto est = noisy.peakMap(noisy.read(t));
      ASSERT_TRUE(est.has_value()) << d;
      const double e = *est - d;
      max_noisy = std::max(max_noisy, std::abs(e));
      sq += e * e;
      ++n;
    }
  }
  std::printf("peak mapping over [-0.45, 0.45] m: max error noise-free %.2e m, with noise %.5f m "
              "(rms %.5f m)\n", max_clean, max_noisy, std::sqrt(sq / n));
  EXPECT_LT(max_clean, 0.001);
  EXPECT_LT(max_noisy, 0.01);
  // No marker nearby: no peak.
  TruthState far;
  far.x = 50.0;
  EXPECT_FALSE(ruler.peakMap(ruler.read(far)).has_value());
}

TEST(MagneticRuler, DetectsEachMarkerOnceAtTheCrossing) {
  const ScenarioConfig sc;
  const Path path(sc.path);
  const core::MarkerMap map = makeMarkerMap(path, sc.markers);
  double max_along = 0.0, max_dm = 0.0, max_step = 0.0;
  for (uint64_t seed = 1; seed <= 20; ++seed) {  // 20 rulers (gain mismatch) and noise draws
    VehicleSim sim(sc.vehicle, path, 40.0 + sc.vehicle.end_margin, seed);
    MagneticRuler ruler(sc.magruler, map, componentSeed(seed, "magruler"));
    std::vector<TruthState> truth{sim.state()};
    std::vector<RulerReading> dets;
    auto feed = [&](const TruthState& t) {
      if (auto r = ruler.sample(t)) {
        ASSERT_TRUE(r->detected);  // publish_rate_hz = 0: detections only
        ASSERT_EQ(r->readings.size(), 13u);
        dets.push_back(*r);
      }
    };
    feed(sim.state());
    while (!sim.finished()) {
      truth.push_back(sim.step());
      feed(truth.back());
    }
    ASSERT_EQ(dets.size(), map.size()) << "seed " << seed;
    for (std::size_t i = 0; i < dets.size(); ++i) {
      const int64_t k = (dets[i].utime - sc.vehicle.start_utime) / 10000;
      const TruthState& t = truth.at(k);
      ASSERT_EQ(t.utime, dets[i].utime);
      const core::Vec2 body =
          core::markerInBody(core::Pose(t.x, t.y, t.heading), map[i].x, map[i].y);
      const double along = body.x() - sc.magruler.ruler_offset;
      const double step = t.speed * 0.01;
      max_along = std::max(max_along, std::abs(along));
      max_step = std::max(max_step, step);
      EXPECT_LE(std::abs(along), step + 1e-3) << "seed " << seed << " marker " << i;
      max_dm = std::max(max_dm, std::abs(dets[i].lateral_offset - body.y()));
      EXPECT_GT(dets[i].quality, 0.8);
    }
  }
  std::printf("detection (20 seeds x 20 markers): max along-track distance at detection %.4f m "
              "(sample spacing %.4f m), max d_m error %.5f m\n", max_along, max_step, max_dm);
  EXPECT_LT(max_dm, 0.01);
}

TEST(MagneticRuler, RawReadingsAtPublishRate) {
  MagRulerConfig cfg;
  cfg.publish_rate_hz = 10.0;
  MagneticRuler ruler(cfg, {}, 3);
  int raw = 0;
  for (int k = 0; k < 1000; ++k)  // 10 s at 100 Hz, no marker
    if (auto r = ruler.sample(straightTruth(10000 * k, 0.015 * k))) {
      EXPECT_FALSE(r->detected);
      EXPECT_NEAR(r->readings[6], cfg.earth_field_z, 0.02);
      ++raw;
    }
  EXPECT_EQ(raw, 100);
}

TEST(FaultInjector, FiresOnceAtEachDistance) {
  const ScenarioConfig sc;  // faults at 12.9 m (0.10 m) and 24.5 m (0.35 m)
  FaultInjector inj(sc.faults, sc.magruler, 9);
  std::vector<InjectedFault> fired;
  for (int k = 0; k <= 3000; ++k)
    if (auto f = inj.sample(straightTruth(10000 * k, 0.015 * k))) fired.push_back(*f);
  ASSERT_EQ(fired.size(), 2u);
  EXPECT_EQ(fired[0].fault.kind, "phantom_marker");
  EXPECT_EQ(fired[1].fault.kind, "wrong_offset");
  for (const auto& f : fired) {
    EXPECT_GE(f.truth.distance, f.fault.at_distance);
    EXPECT_LT(f.truth.distance - 0.015, f.fault.at_distance);  // the first sample that reaches it
    EXPECT_EQ(f.reading.utime, f.truth.utime);
    EXPECT_TRUE(f.reading.detected);
    EXPECT_DOUBLE_EQ(f.reading.quality, 1.0);
    EXPECT_NEAR(f.reading.lateral_offset, f.fault.lateral_offset, 0.003);
    ASSERT_EQ(f.reading.readings.size(), 13u);
    // Single peak at the sensor nearest the offset.
    const auto imax = std::max_element(f.reading.readings.begin(), f.reading.readings.end()) -
                      f.reading.readings.begin();
    EXPECT_EQ(imax, std::lround((f.fault.lateral_offset + 0.5) * 12));
  }
}

// Corrupt ground truth that gets to a model (the drivers refuse it before, in TruthDriver; the
// offline runner and a future caller might not): the time arithmetic saturates instead of
// overflowing, and a sample the model cannot use leaves its state as it was.

TEST(Schedule, ExtremeTimesNeitherOverflowNorLoseTheGrid) {
  constexpr int64_t kMin = std::numeric_limits<int64_t>::min(), kMax = std::numeric_limits<int64_t>::max();
  EXPECT_EQ(saturatingAdd(kMax - 5, 100), kMax);
  EXPECT_EQ(saturatingAdd(kMin + 5, -100), kMin);
  EXPECT_EQ(saturatingAdd(1000, -100), 900);
  EXPECT_DOUBLE_EQ(secondsBetween(3000000, 1000000), 2.0);
  EXPECT_NEAR(secondsBetween(kMax, kMin), 18446744073709.55, 0.01);  // 2^64 us, no overflow
  EXPECT_NEAR(secondsBetween(kMin, kMax), -18446744073709.55, 0.01);

  // A schedule started at utime INT64_MIN (next = INT64_MIN + period), then a sample at 1e18:
  // now - next does not fit in int64. The next tick is the first of the grid after now.
  const int64_t start = kMin + 100, now = 1000000000000000000;
  int64_t next = start;
  EXPECT_TRUE(scheduleDue(next, now, 100));
  EXPECT_GT(next, now);
  EXPECT_LE(next, now + 100);
  EXPECT_EQ((static_cast<uint64_t>(next) - static_cast<uint64_t>(start)) % 100, 0u);
  next = kMin;  // the whole int64 range in one step
  EXPECT_TRUE(scheduleDue(next, kMax, 1));
  EXPECT_EQ(next, kMax);
  EXPECT_TRUE(scheduleDue(next, kMin, 100));  // back to INT64_MIN: restarts there
  EXPECT_EQ(next, kMin + 100);
  next = kMax;
  EXPECT_FALSE(scheduleDue(next, kMax - 50, 100));
  EXPECT_EQ(next, kMax);
}

TEST(OdometrySensor, ANonFiniteOrHugeDistanceIsSkippedAndTheIncrementsAfterItAreRight) {
  OdometrySensorConfig cfg;  // 100 Hz, 1 mm ticks
  cfg.scale_error = 0.0;
  cfg.slip_std = 0.0;
  for (const double bad : {std::nan(""), std::numeric_limits<double>::infinity(), 1e300, -1e300, 1e17}) {
    OdometrySensor odo(cfg, 2.5, 3);
    double sum = 0.0;
    int n = 0;
    for (int k = 0; k < 200; ++k) {
      TruthState t = straightTruth(1000000 + 10000 * k, 0.01 * k);
      if (k == 100) t.distance = bad;
      const auto s = odo.sample(t);
      if (k == 100) {
        EXPECT_FALSE(s.has_value()) << bad;
        continue;
      }
      if (!s) continue;
      ++n;
      // 1 cm per truth sample, 2 cm for the one after the skipped sample; NaN made it 9.2e15 m
      // once and 0 ever after.
      EXPECT_GE(s->input.delta_s, 0.0) << bad << " k " << k;
      EXPECT_LE(s->input.delta_s, 0.0211) << bad << " k " << k;
      if (k > 101) {
        EXPECT_NEAR(s->input.delta_s, 0.01, 0.0011) << bad << " k " << k;
      }
      EXPECT_TRUE(std::isfinite(s->input.delta_theta)) << bad;
      sum += s->input.delta_s;
    }
    EXPECT_EQ(n, 198) << bad;  // every sample but the first and the bad one
    EXPECT_NEAR(sum, 1.99, cfg.tick_length) << bad;
  }
}

TEST(OdometrySensor, ExtremeUtimesNeitherOverflowNorSilenceTheSensor) {
  constexpr int64_t kMin = std::numeric_limits<int64_t>::min(), kMax = std::numeric_limits<int64_t>::max();
  for (const int64_t first : {kMax - 5, kMin}) {
    OdometrySensorConfig cfg;
    cfg.scale_error = 0.0;
    cfg.slip_std = 0.0;
    OdometrySensor odo(cfg, 2.5, 3);
    EXPECT_FALSE(odo.sample(straightTruth(first, 0.0)).has_value());
    int n = 0;
    double sum = 0.0;
    for (int k = 1; k < 100; ++k)
      if (auto s = odo.sample(straightTruth(1000000 + 10000 * k, 0.01 * k))) {
        ++n;
        sum += s->input.delta_s;
        EXPECT_EQ(s->input.utime, 1000000 + 10000 * k);
      }
    EXPECT_EQ(n, 99) << first;
    EXPECT_NEAR(sum, 0.99, cfg.tick_length) << first;
  }
}

TEST(ImuSensor, ANonFiniteSpeedIsSkippedAndDoesNotPoisonTheSamplesAfterIt) {
  ImuSensorConfig cfg;  // 100 Hz
  ImuSensor imu(cfg, 2.5, 5);
  int n = 0;
  for (int k = 0; k < 100; ++k) {
    TruthState t = straightTruth(1000000 + 10000 * k, 0.02 * k);
    t.speed = k == 50 ? std::nan("") : 2.0;
    const auto s = imu.sample(t);
    if (k == 50) {
      EXPECT_FALSE(s.has_value());
    }
    if (!s) continue;
    ++n;
    for (int i = 0; i < 3; ++i) {
      EXPECT_TRUE(std::isfinite(s->accel[i]) && std::isfinite(s->gyro[i]) && std::isfinite(s->mag[i])) << "k " << k;
      EXPECT_LT(std::abs(s->accel[0]), 1.0) << "k " << k;  // constant speed: noise and bias only
    }
  }
  EXPECT_EQ(n, 98);  // every sample but the first and the NaN one
}

TEST(FaultInjector, ANaNDistanceFiresNothingAndTheFaultsStillFireAtTheirDistances) {
  const ScenarioConfig sc;  // faults at 12.9 m and 24.5 m
  FaultInjector inj(sc.faults, sc.magruler, 9);
  std::vector<InjectedFault> fired;
  for (int k = 0; k <= 3000; ++k) {
    TruthState t = straightTruth(10000 * k, 0.015 * k);
    if (k == 10) t.distance = std::nan("");  // fired the phantom marker at 0.15 m
    if (auto f = inj.sample(t)) fired.push_back(*f);
  }
  ASSERT_EQ(fired.size(), 2u);
  for (const auto& f : fired) {
    EXPECT_GE(f.truth.distance, f.fault.at_distance);
    EXPECT_LT(f.truth.distance - 0.015, f.fault.at_distance);
  }
}
