// ukf_landmarks (range-bearing landmarks with known or unknown id, range-only beacons) and the
// heading process noise of a robot turning in place, for it and the magnetic-ruler family.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <random>

#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/engine.hpp"
#include "lcmloc/core/filter.hpp"
#include "lcmloc/core/ruler_model.hpp"
#include "lcmloc/core/vehicle_model.hpp"

using namespace lcmloc::core;

namespace {

MarkerMap landmarks() {
  return {{10, 5.0, 0.0}, {11, 0.0, 5.0}, {12, -5.0, 0.0}, {13, 0.0, -5.0}, {14, 4.0, 4.0}};
}

FilterConfig landmarkConfig(const Vec3& initial, double p0) {
  FilterConfig c;
  c.type = "ukf_landmarks";
  c.initial_pose = initial;
  c.p0_diag = Vec3(p0, p0, 0.05);
  c.landmarks.range_std = 0.05;
  c.landmarks.bearing_std = 0.01;
  c.landmarks.beacon_std = 0.05;
  return c;
}

OdometryInput odo(int64_t utime, double ds, double dth) {
  OdometryInput o;
  o.utime = utime;
  o.delta_s = ds;
  o.delta_theta = dth;
  o.has_steering = false;
  return o;
}

LandmarkObservation observe(const Pose& truth, const Marker& m, int id, int64_t utime, double dr = 0, double db = 0) {
  const Vec2 z = predictRangeBearing(truth, m.x, m.y);
  LandmarkObservation o;
  o.utime = utime;
  o.landmark_id = id;
  o.range = z[0] + dr;
  o.bearing = z[1] + db;
  o.sensor = "LANDMARKS";
  return o;
}

/// Drives a circle of radius 2 m about the origin (truth), odometry exact; after each step the
/// filter gets obs(step, truth). Returns the final truth.
template <typename Obs>
Pose driveCircle(Filter& f, int steps, Obs&& obs) {
  Pose truth(2.0, 0.0, M_PI / 2);
  const double ds = 0.05, dth = ds / 2.0;
  for (int k = 1; k <= steps; ++k) {
    truth = propagatePose(truth, ds, dth);
    f.predict(odo(k * 50000, ds, dth));
    obs(k, truth);
  }
  return truth;
}

}  // namespace

TEST(TurnInPlace, HeadingCovarianceGrowsAndPositionDoesNotDrift) {
  for (const std::string type : {"ukf_landmarks", "ukf_gated", "ukf", "ukf_calib", "dead_reckoning"}) {
    SCOPED_TRACE(type);
    FilterConfig c;
    c.type = type;
    c.initial_pose = Vec3(1.0, 2.0, 0.3);
    auto f = makeFilter(c, landmarks());
    const FilterState s0 = f->state();
    for (int k = 1; k <= 40; ++k) f->predict(odo(k * 10000, 0.0, 0.05));  // 2 rad in place
    const FilterState s1 = f->state();
    EXPECT_NEAR(s1.x[0], 1.0, 1e-12);
    EXPECT_NEAR(s1.x[1], 2.0, 1e-12);
    EXPECT_NEAR(s1.x[2], wrapAngle(0.3 + 2.0), 1e-9);
    // pw_turn |dtheta| per step: 2 rad turned adds 2 pw_turn to the heading variance
    EXPECT_NEAR(s1.P(2, 2) - s0.P(2, 2), 2.0 * c.pw_turn, 1e-9);
    EXPECT_NEAR(s1.P(0, 0), s0.P(0, 0), 1e-12);
    EXPECT_NEAR(s1.P(1, 1), s0.P(1, 1), 1e-12);
  }
}

TEST(TurnInPlace, ZeroTurnNoiseIsAllowedButDefaultIsNot) {
  FilterConfig c;
  EXPECT_GT(c.pw_turn, 0.0);
  c.type = "ukf_landmarks";
  c.pw_turn = -1.0;
  EXPECT_THROW(makeFilter(c, landmarks()), std::invalid_argument);
}

TEST(UkfLandmarks, KnownIdConvergesAndRejectsAFaultObservation) {
  const auto map = landmarks();
  auto f = makeFilter(landmarkConfig(Vec3(2.4, -0.3, M_PI / 2 + 0.1), 0.5), map);
  EXPECT_TRUE(f->uses(Measurement::Landmark));
  EXPECT_FALSE(f->uses(Measurement::Ruler));
  int accepted = 0;
  const Pose truth = driveCircle(*f, 100, [&](int k, const Pose& t) {
    const Marker& m = map[static_cast<std::size_t>(k % 5)];
    const auto d = f->update(observe(t, m, m.id, k * 50000 + 1));
    ASSERT_TRUE(d);
    EXPECT_EQ(d->sensor, "LANDMARKS");
    EXPECT_EQ(d->marker_id, m.id);
    accepted += d->accepted;
  });
  EXPECT_GE(accepted, 95);
  FilterState s = f->state();
  EXPECT_LT(std::hypot(s.x[0] - truth.x(), s.x[1] - truth.y()), 0.01);
  EXPECT_LT(std::abs(wrapAngle(s.x[2] - truth.z())), 0.005);
  // a fault: 1.5 m too long
  const auto d = f->update(observe(truth, map[0], map[0].id, 6000000, 1.5));
  ASSERT_TRUE(d);
  EXPECT_FALSE(d->accepted);
  EXPECT_EQ(d->reason, "gate");
  EXPECT_GT(d->mahalanobis, d->gate);
  EXPECT_EQ(f->state().x, s.x);  // prior untouched
  // an id that is not in the map
  const auto u = f->update(observe(truth, map[0], 99, 6000001));
  ASSERT_TRUE(u);
  EXPECT_FALSE(u->accepted);
  EXPECT_EQ(u->reason, "unknown_id");
}

// Observations whose errors persist from one to the next: the correlation factor discounts what
// each tells the update, and leaves the gate's distance (against the observation's own variance)
// as it is, so that the gate does not widen for it.
TEST(UkfLandmarks, TheCorrelationFactorWeighsTheUpdateAndNotTheGate) {
  const auto map = landmarks();
  FilterConfig c = landmarkConfig(Vec3(2.0, 0.0, M_PI / 2), 0.04);
  auto plain = makeFilter(c, map);
  c.landmarks.correlation_factor = 16.0;
  auto discounted = makeFilter(c, map);
  const Pose truth(2.0, 0.0, M_PI / 2);
  // 0.1 m long: within the gate of both.
  const auto a = plain->update(observe(truth, map[0], map[0].id, 1000, 0.1));
  const auto b = discounted->update(observe(truth, map[0], map[0].id, 1000, 0.1));
  ASSERT_TRUE(a && b);
  EXPECT_TRUE(a->accepted);
  EXPECT_TRUE(b->accepted);
  EXPECT_NEAR(a->mahalanobis, b->mahalanobis, 1e-9 * a->mahalanobis);
  // Landmark 10 lies 3 m along +x from (2, 0): a longer range pushes x back.
  const double moved_plain = 2.0 - plain->state().x[0], moved = 2.0 - discounted->state().x[0];
  EXPECT_GT(moved_plain, 0.05);
  EXPECT_GT(moved, 0.0);
  // The gain on x: P / (P + R) without, P / (P + 16 R) with (P 0.04, R 0.05^2).
  EXPECT_NEAR(moved / moved_plain, (0.04 + 0.0025) / (0.04 + 0.04), 0.05);
  EXPECT_GT(discounted->state().P(0, 0), 2.0 * plain->state().P(0, 0));
  // 0.8 m long: 3.9 sigma of the prior and the range, refused by both (were the factor part of
  // the gate's variance, 2.8 sigma: taken).
  auto c1 = landmarkConfig(Vec3(2.0, 0.0, M_PI / 2), 0.04);
  auto p1 = makeFilter(c1, map);
  c1.landmarks.correlation_factor = 16.0;
  auto d1 = makeFilter(c1, map);
  const auto r1 = p1->update(observe(truth, map[0], map[0].id, 2000, 0.8));
  const auto r2 = d1->update(observe(truth, map[0], map[0].id, 2000, 0.8));
  ASSERT_TRUE(r1 && r2);
  EXPECT_EQ(r1->reason, "gate");
  EXPECT_EQ(r2->reason, "gate");
  EXPECT_NEAR(r1->mahalanobis, r2->mahalanobis, 1e-9 * r1->mahalanobis);
  c1.landmarks.correlation_factor = 0.5;
  EXPECT_THROW(makeFilter(c1, map), std::invalid_argument);
}

TEST(UkfLandmarks, UnknownIdAssociatesTheNearestLandmarkAndConverges) {
  const auto map = landmarks();
  auto f = makeFilter(landmarkConfig(Vec3(2.3, 0.2, M_PI / 2 - 0.05), 0.3), map);
  int right = 0, total = 0;
  const Pose truth = driveCircle(*f, 100, [&](int k, const Pose& t) {
    const Marker& m = map[static_cast<std::size_t>((3 * k) % 5)];
    const auto d = f->update(observe(t, m, -1, k * 50000 + 1));
    ASSERT_TRUE(d);
    ++total;
    right += d->accepted && d->marker_id == m.id;
  });
  EXPECT_GE(right, total - 3);
  FilterState s = f->state();
  EXPECT_LT(std::hypot(s.x[0] - truth.x(), s.x[1] - truth.y()), 0.01);
  // a phantom: no landmark at that range and bearing
  const auto d = f->update(observe(truth, Marker{0, truth.x() + 1.0, truth.y() + 0.2}, -1, 6000000));
  ASSERT_TRUE(d);
  EXPECT_FALSE(d->accepted);
  EXPECT_TRUE(d->reason == "gate" || d->reason == "no_candidate") << d->reason;
  EXPECT_EQ(f->state().x, s.x);
}

TEST(UkfLandmarks, RangeOnlyBeaconsConvergeAndAFaultRangeIsRejected) {
  const MarkerMap beacons{{1, 5.0, 5.0}, {2, -5.0, 5.0}, {3, 0.0, -6.0}};
  auto f = makeFilter(landmarkConfig(Vec3(2.5, 0.4, M_PI / 2 + 0.1), 0.5), beacons);
  EXPECT_TRUE(f->uses(Measurement::Beacon));
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.02);
  int accepted = 0;
  const Pose truth = driveCircle(*f, 200, [&](int k, const Pose& t) {
    const Marker& m = beacons[static_cast<std::size_t>(k % 3)];
    BeaconRange b;
    b.utime = k * 50000 + 1;
    b.beacon_id = m.id;
    b.range = std::hypot(m.x - t.x(), m.y - t.y()) + noise(rng);
    b.sensor = "BEACONS";
    const auto d = f->update(b);
    ASSERT_TRUE(d);
    EXPECT_EQ(d->innovation.size(), 1);
    accepted += d->accepted;
  });
  EXPECT_GE(accepted, 190);
  FilterState s = f->state();
  EXPECT_LT(std::hypot(s.x[0] - truth.x(), s.x[1] - truth.y()), 0.05);
  EXPECT_LT(std::sqrt(s.P(0, 0) + s.P(1, 1)), 0.05);
  BeaconRange bad;
  bad.utime = 20000000;
  bad.beacon_id = 1;
  bad.range = std::hypot(5.0 - truth.x(), 5.0 - truth.y()) + 1.0;
  const auto d = f->update(bad);
  ASSERT_TRUE(d);
  EXPECT_FALSE(d->accepted);
  EXPECT_EQ(d->reason, "gate");
  bad.beacon_id = 42;
  EXPECT_EQ(f->update(bad)->reason, "unknown_id");
}

// Ranges without the beacon's id (beacon_id -1): the filter tries the beacons the range can match
// and takes it only when exactly one passes the gate, the decision naming that beacon; the same
// run as with the ids converges as well. A range that two beacons at the same distance both
// explain is refused as ambiguous.
TEST(UkfLandmarks, RangesWithoutAnIdAreAssociatedWhenOneBeaconAloneMatches) {
  const MarkerMap beacons{{1, 5.0, 5.0}, {2, -5.0, 5.0}, {3, 0.0, -6.0}};
  auto f = makeFilter(landmarkConfig(Vec3(2.5, 0.4, M_PI / 2 + 0.1), 0.5), beacons);
  std::mt19937 rng(8);
  std::normal_distribution<double> noise(0.0, 0.02);
  int accepted = 0, right = 0, ambiguous = 0;
  const Pose truth = driveCircle(*f, 200, [&](int k, const Pose& t) {
    const Marker& m = beacons[static_cast<std::size_t>(k % 3)];
    BeaconRange b;
    b.utime = k * 50000 + 1;
    b.beacon_id = -1;
    b.range = std::hypot(m.x - t.x(), m.y - t.y()) + noise(rng);
    b.sensor = "BEACONS";
    const auto d = f->update(b);
    ASSERT_TRUE(d);
    accepted += d->accepted;
    right += d->accepted && d->marker_id == m.id;
    ambiguous += d->reason == "ambiguous";
  });
  EXPECT_GE(accepted, 150) << ambiguous << " ambiguous";
  EXPECT_EQ(right, accepted) << "every range taken was given to its own beacon";
  FilterState s = f->state();
  EXPECT_LT(std::hypot(s.x[0] - truth.x(), s.x[1] - truth.y()), 0.1);
  // At the origin, beacons 1 and 2 are both 7.07 m away (beacon 3 6 m): a range of 7.07 m is
  // either one's.
  auto g = makeFilter(landmarkConfig(Vec3(0.0, 0.0, M_PI / 2), 0.5), beacons);
  BeaconRange both;
  both.utime = 1000;
  both.beacon_id = -1;
  both.range = std::hypot(5.0, 5.0);
  const auto d = g->update(both);
  ASSERT_TRUE(d);
  EXPECT_FALSE(d->accepted);
  EXPECT_EQ(d->reason, "ambiguous");
  EXPECT_EQ(g->state().x, makeFilter(landmarkConfig(Vec3(0.0, 0.0, M_PI / 2), 0.5), beacons)->state().x);
}

TEST(UkfLandmarks, EngineHandsLandmarksAndBeaconsToTheFilterWithTheChannelAsSensor) {
  EngineConfig ec;
  ec.filter = landmarkConfig(Vec3(2.0, 0.0, M_PI / 2), 0.01);
  std::vector<GateDecision> decisions;
  EngineOutputs out;
  out.on_decision = [&](const std::string&, bool, const GateDecision& d) { decisions.push_back(d); };
  FusionEngine e(ec, landmarks(), out);
  LandmarkObservation o = observe(Pose(2.0, 0.0, M_PI / 2), landmarks()[0], 10, 1000);
  o.sensor = "CAM";
  e.push({"CAM", 0, 1000, o});
  BeaconRange b;
  b.utime = 2000;
  b.beacon_id = 11;
  b.range = std::hypot(2.0, 5.0);
  b.sensor = "UWB";
  e.push({"UWB", 0, 2000, b});
  e.flush();
  ASSERT_EQ(decisions.size(), 2u);
  EXPECT_EQ(decisions[0].sensor, "CAM");
  EXPECT_TRUE(decisions[0].accepted);
  EXPECT_EQ(decisions[1].sensor, "UWB");
  EXPECT_TRUE(decisions[1].accepted);
}

// Re-localization from evidence: a robot carried off (its pose jumps by metres) is found again
// from observations of known landmarks that agree with each other, within a bounded number of
// them, and the filter says so once with its evidence.
TEST(UkfLandmarksRelocalization, AKidnappedRobotIsFoundAgainFromAgreeingObservations) {
  const auto map = landmarks();
  auto f = makeFilter(landmarkConfig(Vec3(2.0, 0.0, M_PI / 2), 0.01), map);
  int k = 0, relocalized = 0, refused_after_jump = 0;
  std::optional<Relocalization> event;
  Pose truth(2.0, 0.0, M_PI / 2);
  const double ds = 0.05, dth = ds / 2.0;
  for (int step = 1; step <= 600; ++step) {
    truth = propagatePose(truth, ds, dth);
    if (step == 200) truth = Pose(truth.x() - 3.0, truth.y() + 2.0, wrapAngle(truth.z() + 0.6));  // carried off
    f->predict(odo(step * 50000, ds, dth));
    if (step % 4) continue;
    const Marker& m = map[static_cast<std::size_t>(k++ % map.size())];
    const auto d = f->update(observe(truth, m, m.id, step * 50000));
    ASSERT_TRUE(d);
    if (step > 200 && !relocalized && !d->accepted) ++refused_after_jump;
    if (d->reason == "relocalized") {
      ++relocalized;
      event = f->takeRelocalization();
    }
  }
  EXPECT_EQ(relocalized, 1);
  ASSERT_TRUE(event);
  EXPECT_TRUE(event->from_landmarks);
  EXPECT_GE(event->fixes, 3);
  EXPECT_GE(event->landmarks, 2);
  EXPECT_GT(event->jump, 3.0);  // the position moved to where the robot is
  EXPECT_LE(refused_after_jump, 6);  // found within a bounded number of observations
  const auto s = f->state();
  EXPECT_NEAR(s.x[0], truth.x(), 0.05);
  EXPECT_NEAR(s.x[1], truth.y(), 0.05);
  EXPECT_NEAR(wrapAngle(s.x[2] - truth.z()), 0.0, 0.02);
  EXPECT_EQ(s.status, FilterStatus::Ok);
}

// Lone outliers of known landmarks (each far off, each alone) never re-localize the filter and
// never move it: over 60 s of them it follows its dead reckoning exactly. Observations without
// identity are never evidence: a minute of them gives no re-localization either.
TEST(UkfLandmarksRelocalization, LoneOutliersAndDistractorsNeverRelocalize) {
  const auto map = landmarks();
  for (const bool distractors : {false, true}) {
    FilterConfig c = landmarkConfig(Vec3(2.0, 0.0, M_PI / 2), 0.01);
    c.p0_diag[2] = 1e-4;  // the heading known and the odometry good: every outlier is outside the gate
    c.pw_diag = Vec3(1e-6, 1e-6, 1e-6);
    c.pw_turn = 1e-6;
    auto f = makeFilter(c, map);
    auto dr = makeFilter(c, map);  // the same without observations
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Pose truth(2.0, 0.0, M_PI / 2);
    const double ds = 0.05, dth = ds / 2.0;
    for (int step = 1; step <= 1200; ++step) {  // 60 s
      truth = propagatePose(truth, ds, dth);
      f->predict(odo(step * 50000, ds, dth));
      dr->predict(odo(step * 50000, ds, dth));
      if (step % 2) continue;
      LandmarkObservation o;
      if (!distractors) {  // a known landmark, 2-3 m too far, its bearing off by up to 0.8 rad
        const Marker& m = map[static_cast<std::size_t>(step / 2 % map.size())];
        o = observe(truth, m, m.id, step * 50000, 2.0 + u(rng), 0.8 * u(rng));
      } else {  // something seen without identity, anywhere
        o.utime = step * 50000;
        o.sensor = "LANDMARKS";
        o.landmark_id = -1;
        o.range = 3.0 + 2.0 * u(rng);
        o.bearing = M_PI * u(rng);
      }
      const auto d = f->update(o);
      ASSERT_TRUE(d);
      EXPECT_NE(d->reason, "relocalized") << step;
      EXPECT_FALSE(f->takeRelocalization()) << step;
      if (!distractors) {
        EXPECT_FALSE(d->accepted) << step;
      }
    }
    if (distractors) continue;
    const auto a = f->state(), b = dr->state();
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(a.x[i], b.x[i], 1e-9) << i;
    EXPECT_EQ(a.status, FilterStatus::Lockout);  // a status only: no covariance inflated
    EXPECT_NEAR(a.P(0, 0), b.P(0, 0), 1e-12);
  }
}
