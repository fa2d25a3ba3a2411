// The odo_ins filter behind the Filter interface and the engine: IMU + odometry in, pose out;
// bad input (NaN IMU sample, IMU dropout); the three-landmark fix through the engine
// re-initializes the filter (position and heading jump to the fix, covariance reset).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/engine.hpp"
#include "lcmloc/core/ins.hpp"
#include "lcmloc/core/landmark_fix.hpp"

using namespace lcmloc::core;

namespace {

constexpr double kLat = 40.0 * M_PI / 180.0, kLon = 116.0 * M_PI / 180.0;

FilterConfig insConfig(double theta0 = M_PI / 2) {
  FilterConfig c;
  c.type = "odo_ins";
  c.initial_pose = Vec3(0.0, 0.0, theta0);
  return c;
}

/// IMU sample (imu_t frame: x forward, y left, z up) of a vehicle at 40 N driving straight with
/// heading theta (CCW from east) at speed v [m/s], accelerating at a [m/s^2].
ImuInput drivingImu(int64_t utime, double theta, double v, double a) {
  ins::InsState s;
  s.lat = kLat;
  s.lon = kLon;
  s.q_bn = Eigen::Quaterniond(ins::cbnFromHeading(M_PI / 2 - theta));
  const ins::Vec3 dir(std::cos(theta), std::sin(theta), 0.0);
  s.v = v * dir;
  ins::Vec3 w, f;
  ins::idealImu(s, a * dir, ins::Vec3::Zero(), &w, &f);
  ImuInput m;
  m.utime = utime;
  m.gyro = Vec3(w.y(), -w.x(), w.z());
  m.accel = Vec3(f.y(), -f.x(), f.z());
  return m;
}

ImuInput standingImu(int64_t utime, double theta) { return drivingImu(utime, theta, 0.0, 0.0); }

struct Recorder {
  std::vector<std::pair<std::string, std::string>> events;
  std::vector<GateDecision> decisions;
  EngineOutputs outputs() {
    EngineOutputs o;
    o.on_event = [this](const EngineEvent& e) { events.emplace_back(eventName(e.kind), eventText(e)); };
    o.on_decision = [this](const std::string&, bool active, const GateDecision& d) {
      if (active) decisions.push_back(d);
    };
    return o;
  }
  bool hasEvent(const std::string& e) const {
    for (const auto& x : events)
      if (x.first == e) return true;
    return false;
  }
};

EngineInput input(const std::string& ch, int64_t seq, int64_t utime, decltype(EngineInput::payload) p) {
  EngineInput in;
  in.channel = ch;
  in.seq = seq;
  in.utime = utime;
  in.payload = std::move(p);
  return in;
}

/// Feeds n standing IMU samples and zero odometry at 100 Hz from utime t0.
/// n steps of 10 ms at heading theta, standing (speed 0) or driving straight at a constant speed
/// (the IMU reads the same).
void stand(FusionEngine& e, int64_t t0, int n, double theta, int64_t* seq, double speed = 0.0) {
  for (int k = 0; k < n; ++k) {
    const int64_t t = t0 + k * 10000;
    OdometryInput o;
    o.utime = t;
    o.delta_s = speed * 0.01;
    e.push(input("ODOMETRY", (*seq), t, o));
    e.push(input("IMU", (*seq)++, t, standingImu(t, theta)));
  }
}

}  // namespace

TEST(OdoInsFilter, RegisteredAndReportsPoseAndScale) {
  const auto types = filterTypes();
  EXPECT_NE(std::find(types.begin(), types.end(), "odo_ins"), types.end());
  EXPECT_NE(std::find(types.begin(), types.end(), "odo_ins_uncal"), types.end());
  auto f = makeFilter(insConfig(0.3), {});
  const FilterState s = f->state();
  ASSERT_EQ(s.x.size(), 11);
  EXPECT_EQ(s.names[3], "odo_scale_error");
  EXPECT_EQ(s.names[4], "v_east");
  EXPECT_EQ(s.names[10], "accel_bias_forward");
  EXPECT_NEAR(s.x[2], 0.3, 1e-12);
  EXPECT_EQ(s.status, FilterStatus::Uninitialized);  // no IMU sample yet
  EXPECT_NEAR(std::sqrt(s.P(3, 3)), 0.005 * std::sqrt(1 + 0.0003 * 0.0003 / 0.005 / 0.005), 1e-6);
  FilterConfig bad = insConfig();
  bad.ins.meas_vel_std = 0.0;
  EXPECT_THROW(makeFilter(bad, {}), std::invalid_argument);
}

// Hand-over while moving (a daemon taking over from the last POSE or a checkpoint, a hot swap
// between odo_ins filters): the state carries the INS velocity and the bias estimates, so the new
// filter drives on with the vehicle. From x, y, theta and the scale alone (what a state from
// dead_reckoning or a UKF carries) the velocity is unknown and the first odometer update sets
// it; from a forward "speed" (tvekf, ukf_gps) it starts at that speed along theta.
TEST(OdoInsFilter, HandOverWhileMovingKeepsVelocityAndBiases) {
  const double theta = 0.4;
  int64_t t = 1000000;
  auto step = [&](std::vector<Filter*> fs, double v, double a) {
    t += 10000;
    OdometryInput o;
    o.utime = t;
    o.delta_s = (v - 0.5 * a * 0.01) * 0.01;  // the distance over (t - 10 ms, t]
    for (Filter* f : fs) {
      f->predict(o);
      f->update(drivingImu(t, theta, v, a));
    }
  };
  auto a = makeFilter(insConfig(theta), {});
  double v = 0.0;
  for (int k = 0; k < 1000; ++k) step({a.get()}, v, 0.0);  // 10 s standing
  for (int k = 0; k < 1000; ++k) {                         // 10 s at 1 m/s^2
    v += 0.01;
    step({a.get()}, v, 1.0);
  }
  for (int k = 0; k < 1000; ++k) step({a.get()}, v, 0.0);  // 10 s at 10 m/s
  const FilterState handed = a->state();
  ASSERT_EQ(handed.names[4], "v_east");
  EXPECT_NEAR(handed.x[4], 10.0 * std::cos(theta), 0.05);
  EXPECT_NEAR(handed.x[5], 10.0 * std::sin(theta), 0.05);

  auto b = makeFilter(insConfig(theta), {});
  b->initialize(handed);
  const FilterState started = b->state();
  for (int i = 0; i < handed.x.size(); ++i) EXPECT_NEAR(started.x[i], handed.x[i], 1e-9) << handed.names[i];
  for (int i = 4; i < handed.x.size(); ++i)
    EXPECT_NEAR(started.P(i, i), handed.P(i, i), 1e-12 + 1e-9 * handed.P(i, i)) << handed.names[i];

  FilterState pose_only = handed;
  pose_only.x.conservativeResize(4);
  pose_only.P.conservativeResize(4, 4);
  pose_only.names.resize(4);
  auto c = makeFilter(insConfig(theta), {});
  c->initialize(pose_only);
  EXPECT_GT(c->state().P(4, 4), 100.0) << "velocity unknown";

  FilterState with_speed = pose_only;  // names and order as tvekf's
  with_speed.names = {"x", "y", "theta", "speed", "distance"};
  with_speed.x.conservativeResize(5);
  with_speed.x[3] = 10.0;
  with_speed.x[4] = 300.0;
  with_speed.P = Eigen::MatrixXd::Identity(5, 5) * 1e-4;
  with_speed.P.topLeftCorner<3, 3>() = pose_only.P.topLeftCorner<3, 3>();
  auto d = makeFilter(insConfig(theta), {});
  d->initialize(with_speed);
  EXPECT_NEAR(d->state().x[4], 10.0 * std::cos(with_speed.x[2]), 1e-9);
  EXPECT_NEAR(d->state().x[5], 10.0 * std::sin(with_speed.x[2]), 1e-9);

  for (int k = 0; k < 2000; ++k) step({a.get(), b.get(), c.get(), d.get()}, v, 0.0);  // 20 s on
  const FilterState sa = a->state(), sb = b->state(), sc = c->state(), sd = d->state();
  // b: the INS starts at the next IMU sample, the handed-over pose carried to it with the velocity.
  // (Started with the pose of the handed-over time, it was 0.10 m behind: 10 ms at 10 m/s.)
  EXPECT_LT(std::hypot(sb.x[0] - sa.x[0], sb.x[1] - sa.x[1]), 0.01);
  EXPECT_NEAR(std::hypot(sb.x[4], sb.x[5]), 10.0, 0.05);
  // c and d drive on with the vehicle (before they kept the INS's 0 m/s, 0.01 m/s sure, and
  // fell more than 10 m behind in these 20 s).
  for (const FilterState* s : {&sc, &sd}) {
    EXPECT_LT(std::hypot(s->x[0] - sa.x[0], s->x[1] - sa.x[1]), 0.5);
    EXPECT_NEAR(std::hypot(s->x[4], s->x[5]), 10.0, 0.05);
  }
}

TEST(OdoInsFilter, StandingStaysPutThroughTheEngine) {
  Recorder rec;
  EngineConfig ec;
  ec.filter = insConfig(0.7);
  ec.reorder_window_us = 0;
  FusionEngine e(ec, {}, rec.outputs());
  int64_t seq = 0;
  stand(e, 1000000, 6000, 0.7, &seq);  // 60 s
  e.flush();
  const FilterState s = e.activeState();
  EXPECT_EQ(s.status, FilterStatus::Ok);
  EXPECT_LT(std::hypot(s.x[0], s.x[1]), 0.01);
  EXPECT_NEAR(s.x[2], 0.7, 1e-4);
  EXPECT_TRUE(rec.events.empty());
}

TEST(OdoInsFilter, NanImuSampleRefusedStateUnchanged) {
  Recorder rec;
  EngineConfig ec;
  ec.filter = insConfig();
  ec.reorder_window_us = 0;
  FusionEngine e(ec, {}, rec.outputs());
  int64_t seq = 0;
  stand(e, 1000000, 100, M_PI / 2, &seq);
  const FilterState before = e.activeState();
  ImuInput bad = standingImu(2000000, M_PI / 2);
  bad.accel.x() = std::nan("");
  e.push(input("IMU", seq++, 2000000, bad));
  e.flush();
  EXPECT_TRUE(rec.hasEvent("bad_input"));
  EXPECT_EQ(e.activeState().x, before.x);
  // The filter itself refuses it too (when driven directly).
  auto f = makeFilter(insConfig(), {});
  f->update(standingImu(0, M_PI / 2));
  const auto d = f->update(bad);
  ASSERT_TRUE(d.has_value());
  EXPECT_EQ(d->reason, "bad_input");
  EXPECT_FALSE(d->accepted);
}

TEST(OdoInsFilter, ImuDropoutCoastsOnOdometryAndIsReported) {
  Recorder rec;
  EngineConfig ec;
  ec.filter = insConfig();
  ec.reorder_window_us = 0;
  std::vector<FilterStatus> statuses;
  EngineOutputs out = rec.outputs();
  out.on_state = [&](const std::string&, bool, const FilterState& s) { statuses.push_back(s.status); };
  FusionEngine e(ec, {}, out);
  int64_t seq = 0;
  stand(e, 1000000, 100, M_PI / 2, &seq);
  // 2 s of odometry without IMU samples.
  for (int k = 0; k < 200; ++k) {
    OdometryInput o;
    o.utime = 2000000 + k * 10000;
    e.push(input("ODOMETRY", seq++, o.utime, o));
  }
  EXPECT_EQ(e.activeState().status, FilterStatus::DeadReckoning);
  EXPECT_GE(e.activeState().utime, 3900000);
  stand(e, 4000000, 100, M_PI / 2, &seq);
  e.flush();
  int gaps = 0;
  for (const auto& d : rec.decisions)
    if (d.reason == "imu_gap") {
      ++gaps;
      ASSERT_EQ(d.innovation.size(), 1);
      EXPECT_NEAR(d.innovation[0], 2.0, 0.05);  // gap length [s]
    }
  EXPECT_EQ(gaps, 1);
  const FilterState s = e.activeState();
  EXPECT_EQ(s.status, FilterStatus::Ok);
  EXPECT_LT(std::hypot(s.x[0], s.x[1]), 0.05);
  EXPECT_TRUE(s.x.allFinite());
}

TEST(OdoInsFilter, ATimeJumpOfHoursIsNotBridgedStepByStep) {
  // Driving north at 10 m/s, then every input jumps 3 hours ahead (a clock set from relative to
  // absolute time, or corrupt stamps the time-jump guard takes once they go on for 0.2 s). Bridging
  // such a gap in 20 ms steps took CPU time in proportion (hours for years; SIGTERM waited). The
  // INS now moves its time across the gap with the state held and takes the speed from the next
  // odometer increment: the pose stays where it was and the drive goes on at 10 m/s.
  for (const int64_t jump : {int64_t{10800} * 1000000, int64_t{86400} * 1000000 * 365}) {
    Recorder rec;
    EngineConfig ec;
    ec.filter = insConfig(M_PI / 2);
    ec.reorder_window_us = 0;
    FusionEngine e(ec, {}, rec.outputs());
    int64_t seq = 0;
    stand(e, 1000000, 200, M_PI / 2, &seq, 10.0);
    e.flush();
    const FilterState before = e.activeState();
    EXPECT_NEAR(before.x[1], 19.8, 0.1);  // 1.98 s at 10 m/s
    stand(e, 3000000 + jump, 100, M_PI / 2, &seq, 10.0);
    e.flush();
    const FilterState after = e.activeState();
    ASSERT_TRUE(after.x.allFinite());
    EXPECT_TRUE(rec.hasEvent("time_jump"));
    EXPECT_NEAR(after.x[0], before.x[0], 0.05) << jump;
    EXPECT_NEAR(after.x[1] - before.x[1], 10.0, 0.2) << jump;  // the second after the gap, at 10 m/s
    EXPECT_NEAR(std::hypot(after.x[4], after.x[5]), 10.0, 0.05) << jump;
    EXPECT_LT(std::abs(after.x[3]), 0.01) << jump;  // the scale estimate undisturbed
  }
}

namespace {
std::map<int, Vec2> triangle(double side) {
  const double r = side / std::sqrt(3.0);
  std::map<int, Vec2> m;
  for (int i = 0; i < 3; ++i) {
    const double a = M_PI / 2 + i * 2 * M_PI / 3;
    m[i + 1] = Vec2(r * std::cos(a), r * std::sin(a));
  }
  return m;
}
/// Bearings (CCW from the body x axis) from pose (p, theta) to the landmarks.
BearingsInput bearingsFrom(const Vec2& p, double theta, const std::map<int, Vec2>& map, int64_t utime) {
  BearingsInput b;
  b.utime = utime;
  for (const auto& [id, lm] : map) {
    b.ids.push_back(id);
    b.bearings.push_back(wrapAngle(std::atan2(lm.y() - p.y(), lm.x() - p.x()) - theta));
  }
  b.bearing_std = 30.0 * ins::kArcSec;
  return b;
}
}  // namespace

TEST(OdoInsFilter, LandmarkFixThroughTheEngineReinitializes) {
  // The filter believes it is at (0, 0) heading north; the vehicle really stands 500 m east and
  // 500 m south of that, heading 30' further left (INS error (500, -500) m, -30').
  const auto map = triangle(1000.0);
  Recorder rec;
  EngineConfig ec;
  const Vec2 p_true(12.0, -7.0);
  const double theta_true = M_PI / 2 + 30.0 * ins::kArcMin;
  ec.filter = insConfig(M_PI / 2);
  ec.filter.initial_pose = Vec3(p_true.x() - 500.0, p_true.y() + 500.0, M_PI / 2);
  ec.reorder_window_us = 0;
  ec.landmarks = map;
  ec.fix_gate.probability = 0;  // as seeds/004: every fix re-initializes (the default gate refuses this one)
  FusionEngine e(ec, {}, rec.outputs());
  int64_t seq = 0;
  stand(e, 1000000, 100, M_PI / 2, &seq);
  const FilterState before = e.activeState();
  ASSERT_GT(std::hypot(before.x[0] - p_true.x(), before.x[1] - p_true.y()), 700.0);
  e.push(input("VISION", 0, 2000000, bearingsFrom(p_true, theta_true, map, 2000000)));
  e.flush();
  const FilterState after = e.activeState();
  EXPECT_NEAR(after.x[0], p_true.x(), 1e-3);
  EXPECT_NEAR(after.x[1], p_true.y(), 1e-3);
  EXPECT_NEAR(wrapAngle(after.x[2] - theta_true), 0.0, 1e-6);
  // Covariance of (x, y, theta) reset to the fix's (Cramér-Rao) covariance, heading sign flipped.
  const Mat3 crb = landmark::cramerRao(p_true, {map.at(1), map.at(2), map.at(3)}, 30.0 * ins::kArcSec);
  Mat3 J = Mat3::Identity();
  J(2, 2) = -1;
  const Mat3 expect = J * crb * J.transpose();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(after.P(i, j), expect(i, j), 1e-6 * expect.norm()) << i << "," << j;
  ASSERT_FALSE(rec.decisions.empty());
  EXPECT_EQ(rec.decisions.back().reason, "fix");
  EXPECT_TRUE(rec.decisions.back().accepted);
  EXPECT_TRUE(rec.hasEvent("fix"));
  // The INS keeps running from the fix: standing still, it stays there.
  stand(e, 2010000, 300, theta_true, &seq);
  e.flush();
  const FilterState later = e.activeState();
  EXPECT_LT(std::hypot(later.x[0] - p_true.x(), later.x[1] - p_true.y()), 0.05);
  EXPECT_NEAR(wrapAngle(later.x[2] - theta_true), 0.0, 1e-4);
}

/// An odo_ins engine with the landmark triangle as its map, inputs in arrival order.
EngineConfig landmarkEngineConfig(const std::map<int, Vec2>& map) {
  EngineConfig ec;
  ec.filter = insConfig();
  ec.reorder_window_us = 0;
  ec.landmarks = map;
  return ec;
}

TEST(OdoInsFilter, LandmarkFixGateRefusesAFixFarFromEachFilterUntilTheLockOut) {
  // Both filters stand at the origin heading north, 5 cm sigma. A fix of another place (the
  // bearings as seen 40 m east: a wrong association) is refused by each filter's gate and leaves
  // them where they are; a good fix is taken and clears the count; after two refused fixes in a
  // row the third is taken (the filters, not the landmarks, are then taken to be lost).
  const auto map = triangle(1000.0);
  Recorder rec;
  std::vector<std::pair<std::string, GateDecision>> all;
  EngineOutputs out = rec.outputs();
  auto active_decision = out.on_decision;
  out.on_decision = [&](const std::string& f, bool active, const GateDecision& d) {
    active_decision(f, active, d);
    all.emplace_back(f, d);
  };
  EngineConfig ec = landmarkEngineConfig(map);
  ec.filter.p0_diag = Vec3(0.05 * 0.05, 0.05 * 0.05, 1e-6);
  ec.shadow = {"odo_ins_uncal"};
  ASSERT_EQ(ec.fix_gate.lockout_rejections, 2);
  FusionEngine e(ec, {}, out);
  int64_t seq = 0, vision_seq = 0;
  stand(e, 1000000, 50, M_PI / 2, &seq);
  const Vec2 elsewhere(40.0, 0.0);
  auto fixAt = [&](const Vec2& p, int64_t utime) {
    all.clear();
    rec.events.clear();
    e.push(input("VISION", vision_seq++, utime, bearingsFrom(p, M_PI / 2, map, utime)));
    e.flush();
  };
  auto reasons = [&] {
    std::string r;
    for (const auto& [f, d] : all) r += f + ":" + d.reason + (d.accepted ? "+ " : "- ");
    return r;
  };

  fixAt(elsewhere, 1500000);
  EXPECT_EQ(reasons(), "odo_ins:gate- odo_ins_uncal:gate- ");
  for (const auto& [f, d] : all) {
    EXPECT_GT(d.mahalanobis, d.gate) << f;
    EXPECT_NEAR(d.gate, 21.108, 1e-3);  // chi-square 3 dof, 0.9999
    EXPECT_NEAR(d.innovation[0], 40.0, 0.01) << f;
  }
  EXPECT_TRUE(rec.hasEvent("fix_refused"));
  EXPECT_FALSE(rec.hasEvent("fix"));
  EXPECT_LT(e.activeState().x.head<2>().norm(), 0.01);

  fixAt(Vec2(0.0, 0.0), 1600000);  // the truth: taken
  EXPECT_EQ(reasons(), "odo_ins:fix+ odo_ins_uncal:fix+ ");
  EXPECT_TRUE(rec.hasEvent("fix"));
  fixAt(elsewhere, 1700000);
  EXPECT_EQ(reasons(), "odo_ins:gate- odo_ins_uncal:gate- ");  // the good fix cleared the count
  fixAt(elsewhere, 1800000);
  EXPECT_EQ(reasons(), "odo_ins:gate- odo_ins_uncal:gate- ");
  EXPECT_LT(e.activeState().x.head<2>().norm(), 0.01);
  fixAt(elsewhere, 1900000);
  EXPECT_EQ(reasons(), "odo_ins:fix_lockout+ odo_ins_uncal:fix_lockout+ ");
  EXPECT_TRUE(rec.hasEvent("fix_lockout"));
  EXPECT_TRUE(rec.hasEvent("fix"));
  EXPECT_NEAR(e.activeState().x[0], 40.0, 1e-3);
  fixAt(elsewhere, 2000000);  // now consistent with the filters
  EXPECT_EQ(reasons(), "odo_ins:fix+ odo_ins_uncal:fix+ ");
}

TEST(OdoInsFilter, LandmarkFixGateOffTakesEveryFixLockOutOffRefusesForever) {
  const auto map = triangle(1000.0);
  const Vec2 elsewhere(40.0, 0.0);
  for (const double probability : {0.0, 0.9999}) {
    std::vector<std::pair<std::string, GateDecision>> all;
    EngineOutputs out;
    out.on_decision = [&](const std::string& f, bool, const GateDecision& d) { all.emplace_back(f, d); };
    EngineConfig ec = landmarkEngineConfig(map);
    ec.filter.p0_diag = Vec3(0.05 * 0.05, 0.05 * 0.05, 1e-6);
    ec.fix_gate.probability = probability;
    ec.fix_gate.lockout_rejections = 0;  // never: a filter the fixes disagree with keeps refusing
    FusionEngine e(ec, {}, out);
    int64_t seq = 0;
    stand(e, 1000000, 50, M_PI / 2, &seq);
    for (int k = 0; k < 5; ++k) {
      all.clear();
      const int64_t t = 1500000 + k * 100000;
      e.push(input("VISION", k, t, bearingsFrom(k == 0 ? elsewhere : Vec2(0.0, 0.0), M_PI / 2, map, t)));
      e.flush();
      ASSERT_EQ(all.size(), 1u);
      // gate off: the first fix moves the filter 40 m, the others (of the origin) move it back.
      EXPECT_EQ(all[0].second.reason, probability == 0 || k > 0 ? "fix" : "gate") << probability << " " << k;
      EXPECT_EQ(std::isinf(all[0].second.gate), probability == 0);
      if (k == 0) {
        EXPECT_NEAR(e.activeState().x[0], probability == 0 ? 40.0 : 0.0, 0.01);
      }
    }
    FusionEngine lost(ec, {}, out);  // only ever sees fixes of another place
    stand(lost, 1000000, 50, M_PI / 2, &seq);
    all.clear();
    for (int k = 0; k < 6; ++k) {
      const int64_t t = 1500000 + k * 100000;
      lost.push(input("VISION", k, t, bearingsFrom(elsewhere, M_PI / 2, map, t)));
    }
    lost.flush();
    ASSERT_EQ(all.size(), 6u);
    for (const auto& [f, d] : all) EXPECT_EQ(d.reason, probability == 0 ? "fix" : "gate");
  }
  // A probability outside [0, 1) is a configuration error.
  EngineConfig bad = landmarkEngineConfig(map);
  bad.fix_gate.probability = 1.0;
  EXPECT_THROW(FusionEngine(bad, {}, EngineOutputs{}), std::invalid_argument);
}

TEST(OdoInsFilter, LandmarkFixRefusals) {
  const auto map = triangle(1000.0);
  Recorder rec;
  const EngineConfig ec = landmarkEngineConfig(map);
  FusionEngine e(ec, {}, rec.outputs());
  int64_t seq = 0;
  stand(e, 1000000, 50, M_PI / 2, &seq);
  const FilterState before = e.activeState();
  // Unknown landmark id.
  BearingsInput b = bearingsFrom(Vec2(0, 0), M_PI / 2, map, 1500000);
  b.ids[1] = 42;
  e.push(input("VISION", 1, 1500000, b));
  e.flush();
  ASSERT_FALSE(rec.decisions.empty());
  EXPECT_EQ(rec.decisions.back().reason, "bad_input");
  EXPECT_FALSE(rec.decisions.back().accepted);
  // NaN bearing.
  b = bearingsFrom(Vec2(0, 0), M_PI / 2, map, 1500000);
  b.bearings[0] = std::nan("");
  e.push(input("VISION", 2, 1500000, b));
  e.flush();
  EXPECT_EQ(rec.decisions.back().reason, "bad_input");
  // Vehicle on the danger circle (the circle through the three landmarks).
  const double r = 1000.0 / std::sqrt(3.0);
  const Vec2 on_circle(r * std::cos(0.3), r * std::sin(0.3));
  FusionEngine e2(ec, {}, rec.outputs());
  FilterState s = e2.activeState();
  s.x.head<2>() = on_circle;
  e2.initialize(s);
  e2.push(input("VISION", 3, 1600000, bearingsFrom(on_circle, M_PI / 2, map, 1600000)));
  e2.flush();
  EXPECT_EQ(rec.decisions.back().reason, "geometry");
  EXPECT_TRUE(rec.hasEvent("fix_refused"));
  EXPECT_EQ(e.activeState().x, before.x);
}

TEST(OdoInsFilter, FewerThanThreeLandmarksInViewIsADecisionWithoutAnEvent) {
  const auto map = triangle(1000.0);
  Recorder rec;
  FusionEngine e(landmarkEngineConfig(map), {}, rec.outputs());
  int64_t seq = 0;
  stand(e, 1000000, 50, M_PI / 2, &seq);
  const FilterState before = e.activeState();
  BearingsInput b = bearingsFrom(Vec2(0, 0), M_PI / 2, map, 1500000);
  b.ids.pop_back();
  b.bearings.pop_back();
  e.push(input("VISION", 1, 1500000, b));
  e.flush();
  ASSERT_FALSE(rec.decisions.empty());
  EXPECT_EQ(rec.decisions.back().reason, "too_few_landmarks");
  EXPECT_FALSE(rec.decisions.back().accepted);
  EXPECT_FALSE(rec.hasEvent("bad_input"));
  EXPECT_FALSE(rec.hasEvent("fix_refused"));
  EXPECT_EQ(e.activeState().x, before.x);
}

TEST(OdoInsFilter, DefaultApplyFixSetsPoseOfOtherFilters) {
  FilterConfig c;
  c.type = "dead_reckoning";
  auto f = makeFilter(c, {});
  PoseFix fix;
  fix.utime = 5;
  fix.pose = Vec3(3.0, 4.0, 0.5);
  fix.cov = Mat3::Identity() * 0.04;
  EXPECT_TRUE(f->applyFix(fix));
  const FilterState s = f->state();
  EXPECT_EQ(s.x.head<3>(), fix.pose);
  EXPECT_NEAR(s.P(0, 0), 0.04, 1e-12);
  fix.pose[0] = std::nan("");
  EXPECT_FALSE(f->applyFix(fix));
}

TEST(OdoInsFilter, SetPoseWhileMovingTurnsTheVelocityWithTheHeading) {
  // Driving east at 10 m/s; an operator's set_pose says the vehicle heads north at the same place.
  // The INS velocity must turn with the heading (before it kept pointing east: 1 s later the
  // estimate was 238 m off and 230 m/s fast).
  Recorder rec;
  EngineConfig ec;
  ec.filter = insConfig(0.0);
  ec.reorder_window_us = 0;
  FusionEngine e(ec, {}, rec.outputs());
  int64_t t = 1000000, seq = 0;
  auto drive = [&](double theta, double v, double a, int n) {
    for (int k = 0; k < n; ++k) {
      t += 10000;
      OdometryInput o;
      o.utime = t;
      o.delta_s = (v - 0.5 * a * 0.01) * 0.01;
      e.push(input("ODOMETRY", seq, t, o));
      e.push(input("IMU", seq++, t, drivingImu(t, theta, v, a)));
      v += a * 0.01;
    }
    return v;
  };
  drive(0.0, 0.0, 0.0, 100);
  const double v = drive(0.0, 0.0, 1.0, 1000);  // 10 s at 1 m/s^2 eastwards
  ASSERT_NEAR(v, 10.0, 1e-6);
  drive(0.0, v, 0.0, 100);
  const FilterState before = e.activeState();
  ASSERT_NEAR(before.x[4], 10.0, 0.05);  // v_east
  e.push(EngineInput{"FUSION_CONTROL", 1, t, ControlCommand(SetPose{Pose(before.x[0], before.x[1], M_PI / 2),
                                                                   Vec3(0.1, 0.1, 0.01)})});
  e.flush();
  const FilterState set = e.activeState();
  EXPECT_NEAR(set.x[2], M_PI / 2, 1e-3);  // (before: 0.59, the old heading mixed in)
  EXPECT_NEAR(set.x[4], 0.0, 0.05);   // v_east
  EXPECT_NEAR(set.x[5], 10.0, 0.05);  // v_north
  EXPECT_NEAR(set.P(0, 0), 0.01, 1e-6);
  drive(M_PI / 2, v, 0.0, 1);
  const FilterState moving = e.activeState();
  drive(M_PI / 2, v, 0.0, 100);  // 1 s northwards
  const FilterState after = e.activeState();
  EXPECT_NEAR(after.x[0] - moving.x[0], 0.0, 0.05);
  EXPECT_NEAR(after.x[1] - moving.x[1], 10.0, 0.05);
  EXPECT_NEAR(std::hypot(after.x[4], after.x[5]), 10.0, 0.05);
  EXPECT_NEAR(wrapAngle(after.x[2] - M_PI / 2), 0.0, 0.01);
}

TEST(OdoInsFilter, ALongImuDropoutHoldsTheLastSampleForMaxCoastOnly) {
  // Straight east at 10 m/s; the last IMU sample before a 15 s dropout reads a 0.2 rad/s yaw
  // rate (a bump). Held for the whole dropout (ins.max_coast was read from no configuration
  // and never applied), it kept turning the estimate; held for max_coast, then attitude and
  // velocity held, the estimate stops turning.
  auto run = [](double max_coast) {
    FilterConfig c = insConfig(0.0);
    c.ins.max_coast = max_coast;
    auto f = makeFilter(c, {});
    int64_t t = 1000000;
    double v = 0.0;
    auto step = [&](double a, bool imu, double yaw = 0.0) {
      t += 10000;
      OdometryInput o;
      o.utime = t;
      o.delta_s = (v + 0.5 * a * 0.01) * 0.01;
      v += a * 0.01;
      f->predict(o);
      if (imu) {
        ImuInput m = drivingImu(t, 0.0, v, a);
        m.gyro.z() += yaw;
        f->update(m);
      }
    };
    for (int k = 0; k < 100; ++k) step(0.0, true);
    for (int k = 0; k < 1000; ++k) step(1.0, true);  // to 10 m/s
    for (int k = 0; k < 100; ++k) step(0.0, true);
    step(0.0, true, 0.2);
    std::vector<double> theta{f->state().x[2]};  // theta[s]: s seconds into the dropout
    for (int s = 0; s < 15; ++s) {
      for (int k = 0; k < 100; ++k) step(0.0, false);
      theta.push_back(f->state().x[2]);
    }
    EXPECT_EQ(f->state().status, FilterStatus::DeadReckoning);
    EXPECT_TRUE(f->state().x.allFinite());
    return theta;
  };
  for (const double max_coast : {5.0, 2.0}) {
    const std::vector<double> th = run(max_coast);
    const int k = static_cast<int>(max_coast);
    EXPECT_GT(th[k] - th[0], 0.1 * max_coast) << max_coast;  // turned while the sample was held
    EXPECT_LT(std::abs(th[15] - th[k]), 0.1) << max_coast;  // and hardly after (0.054 rad measured)
  }
  const std::vector<double> held = run(1000.0);  // the sample held throughout
  EXPECT_GT(std::abs(wrapAngle(held[15] - held[5])), 1.0);
}

// An odometry gap (messages lost, the IMU going on): the INS bridges it with the IMU; the first
// odometer increment after it covers its own 10 ms only and must not read as a speed over the
// whole gap (0.1 m in 2 s: 0.05 m/s, with the odometer's 0.01 m/s sigma).
TEST(OdoInsFilter, AnOdometryGapIsBridgedByTheInsAndTheIncrementAfterItIsNoSpeed) {
  const double theta = 0.4, v = 10.0;
  for (const bool bridge : {true, false}) {
    EngineConfig ec;
    ec.filter = insConfig(theta);
    if (!bridge) ec.odometry_gap.max_gap_us = 0;
    std::vector<FilterState> states;
    std::vector<std::string> events;
    EngineOutputs o;
    o.on_state = [&](const std::string&, bool active, const FilterState& s) {
      if (active) states.push_back(s);
    };
    o.on_event = [&](const EngineEvent& e) { events.push_back(eventName(e.kind) + std::string(": ") + eventText(e)); };
    FusionEngine e(ec, {}, o);
    const int64_t t0 = 1000000;
    int64_t seq = 0;
    for (int k = 1; k <= 1200; ++k) {  // 12 s at 10 m/s; no odometry in (5 s, 7 s]
      const int64_t t = t0 + k * 10000;
      ++seq;
      if (k <= 500 || k > 700) {
        OdometryInput odo;
        odo.utime = t;
        odo.delta_s = v * 0.01;
        e.push(EngineInput{"ODOMETRY", seq, t, odo});
      }
      e.push(EngineInput{"IMU", k, t, drivingImu(t, theta, v, 0.0)});
    }
    e.flush();
    int gaps = 0;
    for (const auto& ev : events) gaps += ev.rfind("odometry_gap", 0) == 0;
    EXPECT_EQ(gaps, bridge ? 1 : 0);
    // the state 0.1 s after the gap: the INS speed
    const int64_t after = t0 + 710 * 10000;
    const FilterState* s = nullptr;
    for (const auto& st : states)
      if (st.utime >= after) { s = &st; break; }
    ASSERT_NE(s, nullptr);
    const double speed = std::hypot(s->x[4], s->x[5]);
    const FilterState& last = states.back();
    const double travelled = std::hypot(last.x[0], last.x[1]);  // from (0, 0), truth 11.99 s at 10 m/s
    if (bridge) {  // (measured: 10.000 m/s; -0.10 m, the 10 ms before the INS started)
      EXPECT_NEAR(speed, v, 0.02);
      EXPECT_NEAR(travelled, v * 11.99, 0.2);
    } else {  // without the gap handling (measured: 9.70 m/s, +0.71 m)
      EXPECT_LT(speed, v - 0.1);
      EXPECT_GT(std::abs(travelled - v * 11.99), 0.5);
    }
  }
}
