// The engine's parts on their own: the odometry-gap tracker, the filter bank, the landmark-fix
// stage and the commands.
#include <gtest/gtest.h>

#include <climits>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/commands.hpp"
#include "lcmloc/core/engine.hpp"
#include "lcmloc/core/filter_bank.hpp"
#include "lcmloc/core/fix_stage.hpp"
#include "lcmloc/core/odometry_gaps.hpp"
#include "lcmloc/core/output_decimation.hpp"

using namespace lcmloc::core;

namespace {

EngineInput odo(int64_t utime, int64_t seq, double ds, const std::string& channel = "ODOMETRY") {
  OdometryInput o;
  o.utime = utime;
  o.delta_s = ds;
  o.has_steering = true;
  return EngineInput{channel, seq, utime, o};
}
const OdometryInput& increment(const EngineInput& in) { return std::get<OdometryInput>(in.payload); }

/// Landmarks at the corners of an equilateral triangle of side 100 m around the origin.
std::map<int, Vec2> triangle() {
  const double r = 100.0 / std::sqrt(3.0);
  std::map<int, Vec2> m;
  for (int i = 0; i < 3; ++i) {
    const double a = M_PI / 2 + i * 2 * M_PI / 3;
    m[i + 1] = Vec2(r * std::cos(a), r * std::sin(a));
  }
  return m;
}
/// Bearings (CCW from the body x axis) from pose (x, y, theta) to the landmarks.
EngineInput bearingsFrom(const Vec3& pose, const std::map<int, Vec2>& map, int64_t utime, int64_t seq) {
  BearingsInput b;
  b.utime = utime;
  b.seq = seq;
  for (const auto& [id, lm] : map) {
    b.ids.push_back(id);
    b.bearings.push_back(wrapAngle(std::atan2(lm.y() - pose.y(), lm.x() - pose.x()) - pose.z()));
  }
  b.bearing_std = 1e-3;
  return EngineInput{"VISION", seq, utime, b};
}

/// The parts the engine wires, wired the same way, and what they emit.
struct Parts {
  struct Decision { std::string filter; bool active; GateDecision d; };
  std::vector<EngineEvent> events;
  std::vector<Decision> decisions;
  std::vector<std::string> states;  ///< filter names, in the order their states were published
  EngineConfig cfg;
  MarkerMap map;
  EngineOutputs out;
  EngineCounters counters;
  FilterBank bank;
  OutputDecimation decimation;
  OdometryGaps gaps;
  LandmarkFixStage fixes;
  Commands commands;

  explicit Parts(EngineConfig c)
      : cfg(std::move(c)), out(outputs()), bank(cfg.filter, cfg.shadow, map, out), decimation(cfg.output_every, bank),
        gaps(cfg.odometry_gap, bank, decimation, out), fixes(cfg, bank, out, counters), commands(bank, fixes, out) {}

  EngineOutputs outputs() {
    EngineOutputs o;
    o.on_event = [this](const EngineEvent& e) { events.push_back(e); };
    o.on_decision = [this](const std::string& f, bool a, const GateDecision& d) { decisions.push_back({f, a, d}); };
    o.on_state = [this](const std::string& f, bool, const FilterState&) { states.push_back(f); };
    return o;
  }
  int count(EventKind k) const {
    int n = 0;
    for (const auto& e : events) n += e.kind == k;
    return n;
  }
  std::string lastText() const { return events.empty() ? "" : eventText(events.back()); }
};

EngineConfig config(const std::string& type, std::vector<std::string> shadow = {}) {
  EngineConfig c;
  c.filter.type = type;
  c.shadow = std::move(shadow);
  c.odometry_gap.max_gap_us = 100000;
  c.landmarks = triangle();
  return c;
}

}  // namespace

// ---- odometry gaps ----

TEST(OdometryGaps, AnIncrementWhoseSeqFollowsCoversAnyIntervalButLostMessagesAreAGap) {
  Parts p(config("dead_reckoning"));
  int64_t t = 1000000, seq = 0;
  for (int k = 0; k < 10; ++k) {
    EngineInput in = odo(t += 10000, ++seq, 0.1);
    ASSERT_FALSE(p.gaps.detect(in, increment(in)));
  }
  // 2 s later, but the next seq: the sender was slow, its increment covers the interval.
  EngineInput slow = odo(t += 2000000, ++seq, 0.1);
  EXPECT_FALSE(p.gaps.detect(slow, increment(slow)));
  for (int k = 0; k < 10; ++k) {
    EngineInput in = odo(t += 10000, ++seq, 0.1);
    ASSERT_FALSE(p.gaps.detect(in, increment(in)));
  }
  // 0.5 s later with 49 seqs missing: a gap at the recent 10 m/s, up to one period before it.
  const int64_t before = t;
  EngineInput next = odo(t += 500000, seq += 50, 0.1);
  const auto gap = p.gaps.detect(next, increment(next));
  ASSERT_TRUE(gap.has_value());
  EXPECT_FALSE(gap->resume);
  EXPECT_EQ(gap->previous_seq, seq - 50);
  EXPECT_EQ(gap->gap.from_utime, before);
  EXPECT_EQ(gap->gap.next_utime, t);
  EXPECT_EQ(gap->gap.to_utime, t - 10000);
  EXPECT_NEAR(gap->gap.speed, 10.0, 1e-9);
  EXPECT_NEAR(gap->gap.seconds, 0.49, 1e-12);
  EXPECT_NE(eventText({EventKind::OdometryGap, t, *gap}).find("messages lost"), std::string::npos);
  EngineInput after = odo(t += 10000, ++seq, 0.1);
  EXPECT_FALSE(p.gaps.detect(after, increment(after)));
}

TEST(OdometryGaps, ChannelsAreTrackedApartAndAMissingOdometryIsSeenByItsAge) {
  Parts p(config("dead_reckoning"));
  int64_t t = 1000000;
  for (int k = 1; k <= 20; ++k) {
    t += 10000;
    EngineInput a = odo(t, k, 0.1, "ODO_A"), b = odo(t + 5000, 100 + k, 0.1, "ODO_B");
    ASSERT_FALSE(p.gaps.detect(a, increment(a))) << k;  // each channel's seqs follow
    ASSERT_FALSE(p.gaps.detect(b, increment(b))) << k;
  }
  EXPECT_EQ(p.gaps.lastOdometryUtime(), t + 5000);
  EXPECT_FALSE(p.gaps.odometryMissing(t + 5000 + 100000));  // at the limit, not beyond
  EXPECT_TRUE(p.gaps.odometryMissing(t + 5000 + 100001));
  // ODO_A resumes after 1 s with seqs lost: a gap of ODO_A; ODO_B is not involved.
  EngineInput late = odo(t + 1000000, 40, 0.1, "ODO_A");
  const auto gap = p.gaps.detect(late, increment(late));
  ASSERT_TRUE(gap.has_value());
  EXPECT_EQ(gap->input.channel, "ODO_A");
  EXPECT_EQ(gap->gap.from_utime, t);
}

TEST(OdometryGaps, TheFirstOdometryLongAfterTheResumeStateIsAGapAtItsOwnSpeed) {
  EngineConfig c = config("dead_reckoning");
  c.odometry_gap.resume_period_us = 20000;
  Parts p(c);
  p.gaps.resumeFrom(1000000);
  EngineInput first = odo(3000000, 77, 0.2);
  const auto gap = p.gaps.detect(first, increment(first));
  ASSERT_TRUE(gap.has_value());
  EXPECT_TRUE(gap->resume);
  EXPECT_EQ(gap->gap.from_utime, 1000000);
  EXPECT_EQ(gap->gap.to_utime, 3000000 - 20000);
  EXPECT_NEAR(gap->gap.speed, 10.0, 1e-9);  // 0.2 m over its sender's 20 ms
  // Only the first one after the state; within the limit, none.
  EngineInput second = odo(3020000, 80, 0.2);
  EXPECT_FALSE(p.gaps.detect(second, increment(second)));
  p.gaps.resumeFrom(5000000);
  EngineInput near = odo(5050000, 81, 0.2);
  EXPECT_FALSE(p.gaps.detect(near, increment(near)));
}

TEST(OdometryGaps, ResetForgetsEveryChannelAndTheResumeState) {
  Parts p(config("dead_reckoning"));
  p.gaps.resumeFrom(0);
  for (int k = 1; k <= 5; ++k) {
    EngineInput in = odo(k * 10000, k, 0.1);
    p.gaps.detect(in, increment(in));
  }
  p.gaps.reset();
  EXPECT_EQ(p.gaps.lastOdometryUtime(), INT64_MIN);
  EXPECT_FALSE(p.gaps.odometryMissing(100000000));
  // Seq 90 after seq 5, 10 s later: the first of its channel since the reset, not a gap.
  EngineInput in = odo(10000000, 90, 0.1);
  EXPECT_FALSE(p.gaps.detect(in, increment(in)));
}

TEST(OdometryGaps, EveryFilterBridgesTheGapAndTheEventSaysHowEach) {
  Parts p(config("ukf_gated", {"dead_reckoning"}));
  int64_t t = 1000000, seq = 0;
  for (int k = 0; k < 10; ++k) {
    EngineInput in = odo(t += 10000, ++seq, 0.1);
    p.gaps.odometry(in, increment(in));
    p.bank.forEach([&](Filter& f, bool) { f.predict(increment(in)); });
  }
  ASSERT_TRUE(p.events.empty());
  const double sigma_before = positionSigma(p.bank.active().state());
  std::map<std::string, double> y_before;
  p.bank.forEach([&](Filter& f, bool) { y_before[f.name()] = f.state().x[1]; });
  EngineInput in = odo(t += 2000000, seq += 100, 0.1);
  p.gaps.odometry(in, increment(in));
  ASSERT_EQ(p.count(EventKind::OdometryGap), 1);
  const auto& e = std::get<events::GapBridged>(p.events.back().fields);
  ASSERT_EQ(e.bridged.size(), 2u);  // the active filter and the shadow
  EXPECT_EQ(e.bridged[0].rfind("ukf_gated: bridged", 0), 0u) << e.bridged[0];
  EXPECT_EQ(e.bridged[1].rfind("dead_reckoning: bridged", 0), 0u) << e.bridged[1];
  EXPECT_EQ(p.events.back().utime, t);
  // The pose moved on at 10 m/s (north; the UKF's mean a little less, its heading uncertain) and
  // its uncertainty grew.
  p.bank.forEach([&](Filter& f, bool) {
    EXPECT_NEAR(f.state().x[1] - y_before[f.name()], 10.0 * e.gap.seconds, 0.02 * 10.0 * e.gap.seconds) << f.name();
  });
  EXPECT_GT(positionSigma(p.bank.active().state()), sigma_before);
  EXPECT_TRUE(p.gaps.afterGap());
  EXPECT_NEAR(p.gaps.spread(), 3.0 * positionSigma(p.bank.active().state()), 1e-12);
  p.gaps.accepted();
  EXPECT_FALSE(p.gaps.afterGap());
}

// ---- filter bank ----

TEST(FilterBank, ASwitchCarriesTheActiveStateOverAndKeepsTheShadows) {
  Parts p(config("ukf_gated", {"dead_reckoning"}));
  FilterState s = p.bank.active().state();
  s.x.head<3>() = Vec3(5, 6, 0.3);
  s.utime = 2000000;
  p.bank.initialize(s);
  FilterConfig to = p.cfg.filter;
  to.type = "ukf";
  const FilterBank::Switched r = p.bank.switchTo(to, 2500000);
  EXPECT_TRUE(r.error.empty());
  EXPECT_EQ(r.previous, "ukf_gated");
  EXPECT_TRUE(r.note.empty());
  EXPECT_EQ(p.bank.active().name(), "ukf");
  EXPECT_EQ(p.bank.activeConfig().type, "ukf");
  EXPECT_EQ(Vec3(p.bank.active().state().x.head<3>()), Vec3(5, 6, 0.3));
  EXPECT_EQ(p.bank.active().state().utime, 2500000);  // the later of the state's and the command's
  std::vector<std::string> order;
  p.bank.forEach([&](Filter& f, bool is_active) { order.push_back(FilterBank::key(f, is_active)); });
  EXPECT_EQ(order, (std::vector<std::string>{"active ukf", "shadow dead_reckoning"}));
}

TEST(FilterBank, AnInvalidSwitchChangesNothing) {
  Parts p(config("ukf_gated"));
  FilterConfig to = p.cfg.filter;
  to.type = "no_such_filter";
  const FilterBank::Switched r = p.bank.switchTo(to, 0);
  EXPECT_FALSE(r.error.empty());
  EXPECT_EQ(p.bank.active().name(), "ukf_gated");
  EXPECT_EQ(p.bank.activeConfig().type, "ukf_gated");
}

TEST(FilterBank, ResetStartsEveryFilterAfreshAndKeepsTheActiveType) {
  Parts p(config("ukf_gated", {"dead_reckoning"}));
  FilterConfig to = p.cfg.filter;
  to.type = "ukf";
  p.bank.switchTo(to, 0);
  FilterState s = p.bank.active().state();
  s.x.head<3>() = Vec3(50, 60, 1.0);
  p.bank.initialize(s);
  p.bank.reset();
  EXPECT_EQ(p.bank.active().name(), "ukf");
  p.bank.forEach([&](Filter& f, bool) {
    EXPECT_EQ(Vec3(f.state().x.head<3>()), p.cfg.filter.initial_pose) << f.name();
  });
}

TEST(FilterBank, ANonFiniteStateIsNeverPublishedTheFilterRestarts) {
  Parts p(config("dead_reckoning", {"ukf"}));
  const uint64_t emitted = p.bank.activeStatesEmitted();
  OdometryInput o;
  o.utime = 1000;
  o.delta_s = 1e300;
  p.bank.active().predict(o);
  p.bank.forEach([&](Filter& f, bool is_active) { p.bank.emitState(f, is_active); });
  EXPECT_EQ(p.bank.activeStatesEmitted(), emitted + 1);  // the shadow's state does not count
  EXPECT_EQ(p.states, (std::vector<std::string>{"dead_reckoning", "ukf"}));
  ASSERT_EQ(p.count(EventKind::Restarted), 1);
  EXPECT_EQ(p.lastText(), "dead_reckoning: its state became non-finite: started from its configured initial state");
  EXPECT_TRUE(p.bank.active().state().x.allFinite());
}

// ---- landmark fix stage ----

TEST(LandmarkFixStage, AFixThatAgreesIsTakenByEveryFilter) {
  Parts p(config("ukf_gated", {"dead_reckoning"}));
  const EngineInput in = bearingsFrom(p.cfg.filter.initial_pose, p.cfg.landmarks, 1000, 1);
  p.fixes.process(in, std::get<BearingsInput>(in.payload));
  ASSERT_EQ(p.decisions.size(), 2u);
  EXPECT_EQ(p.decisions[0].d.reason, "fix");
  EXPECT_TRUE(p.decisions[0].d.accepted);
  EXPECT_EQ(p.decisions[1].filter, "dead_reckoning");
  EXPECT_EQ(p.count(EventKind::Fix), 1);
  EXPECT_EQ(p.counters.accepted, 1);
}

TEST(LandmarkFixStage, TheGateRefusesAFarFixUntilTheLockoutTakesIt) {
  EngineConfig c = config("ukf_gated");
  c.fix_gate.lockout_rejections = 2;
  Parts p(c);
  const Vec3 there(10, -5, M_PI / 2);  // where the bearings say the vehicle is: 11 m off
  const std::string key = "active ukf_gated";
  for (int k = 1; k <= 2; ++k) {
    const EngineInput in = bearingsFrom(there, c.landmarks, 1000 * k, k);
    p.fixes.process(in, std::get<BearingsInput>(in.payload));
    EXPECT_EQ(p.decisions.back().d.reason, "gate");
    EXPECT_FALSE(p.decisions.back().d.accepted);
    EXPECT_EQ(p.events.back().kind, EventKind::FixRefused);
    EXPECT_EQ(std::get<events::FixGated>(p.events.back().fields).in_a_row, k);
    EXPECT_EQ(p.fixes.refusedInARow(key), k);
    EXPECT_EQ(Vec3(p.bank.active().state().x.head<3>()), c.filter.initial_pose);  // not moved
  }
  EXPECT_EQ(p.counters.rejected, 2);
  const EngineInput third = bearingsFrom(there, c.landmarks, 3000, 3);
  p.fixes.process(third, std::get<BearingsInput>(third.payload));
  EXPECT_EQ(p.decisions.back().d.reason, "fix_lockout");
  EXPECT_TRUE(p.decisions.back().d.accepted);
  EXPECT_EQ(p.count(EventKind::FixLockout), 1);
  EXPECT_EQ(p.events.back().kind, EventKind::Fix);
  EXPECT_EQ(p.fixes.refusedInARow(key), 0);
  EXPECT_NEAR(p.bank.active().state().x[0], 10.0, 0.1);
  EXPECT_NEAR(p.bank.active().state().x[1], -5.0, 0.1);
}

TEST(LandmarkFixStage, ResetAndForgetStartTheCountsAgain) {
  EngineConfig c = config("ukf_gated", {"ukf"});
  c.fix_gate.lockout_rejections = 2;
  Parts p(c);
  const EngineInput in = bearingsFrom(Vec3(10, -5, M_PI / 2), c.landmarks, 1000, 1);
  p.fixes.process(in, std::get<BearingsInput>(in.payload));
  EXPECT_EQ(p.fixes.refusedInARow("active ukf_gated"), 1);
  EXPECT_EQ(p.fixes.refusedInARow("shadow ukf"), 1);
  p.fixes.forget("active ukf_gated");
  EXPECT_EQ(p.fixes.refusedInARow("active ukf_gated"), 0);
  EXPECT_EQ(p.fixes.refusedInARow("shadow ukf"), 1);
  p.fixes.reset();
  EXPECT_EQ(p.fixes.refusedInARow("shadow ukf"), 0);
}

TEST(LandmarkFixStage, TooFewLandmarksIsADecisionAndAnUnknownOneABadInput) {
  Parts p(config("ukf_gated"));
  EngineInput in = bearingsFrom(p.cfg.filter.initial_pose, p.cfg.landmarks, 1000, 1);
  auto& b = std::get<BearingsInput>(in.payload);
  b.ids.pop_back();
  b.bearings.pop_back();
  p.fixes.process(in, b);
  EXPECT_EQ(p.decisions.back().d.reason, "too_few_landmarks");
  EXPECT_TRUE(p.events.empty());
  b.ids.push_back(42);
  b.bearings.push_back(0.1);
  p.fixes.process(in, b);
  EXPECT_EQ(p.decisions.back().d.reason, "bad_input");
  ASSERT_EQ(p.count(EventKind::BadInput), 1);
  EXPECT_EQ(p.lastText(), "VISION seq 1: landmark fix refused: landmark 42 not in the map");
}

// ---- commands ----

TEST(Commands, ASwitchIsAnsweredAndTheNewActiveFilterCountsFixesAfresh) {
  EngineConfig c = config("ukf_gated", {"ukf"});
  c.fix_gate.lockout_rejections = 5;
  Parts p(c);
  const EngineInput far = bearingsFrom(Vec3(10, -5, M_PI / 2), c.landmarks, 1000, 1);
  p.fixes.process(far, std::get<BearingsInput>(far.payload));
  ASSERT_EQ(p.fixes.refusedInARow("shadow ukf"), 1);
  SwitchFilter sw{c.filter};
  sw.config.type = "ukf";
  p.commands.apply(EngineInput{"FUSION_CONTROL", 4, 2000, ControlCommand(sw)}, ControlCommand(sw));
  ASSERT_EQ(p.events.back().kind, EventKind::Ack);
  EXPECT_EQ(p.lastText(), "FUSION_CONTROL seq 4: switched ukf_gated -> ukf");
  EXPECT_EQ(p.bank.active().name(), "ukf");
  EXPECT_EQ(p.fixes.refusedInARow("active ukf"), 0);
  sw.config.type = "warp_drive";
  p.commands.apply(EngineInput{"FUSION_CONTROL", 5, 2000, ControlCommand(sw)}, ControlCommand(sw));
  ASSERT_EQ(p.events.back().kind, EventKind::Refused);
  EXPECT_EQ(p.lastText().rfind("FUSION_CONTROL seq 5: switch to 'warp_drive': ", 0), 0u) << p.lastText();
  EXPECT_EQ(p.bank.active().name(), "ukf");
}

TEST(Commands, SetPoseIsCheckedThenMovesEveryFilter) {
  Parts p(config("ukf_gated", {"dead_reckoning"}));
  const ControlCommand zero = SetPose{Pose(1, 2, 0.1), Vec3(0.1, 0.0, 0.1)};
  p.commands.apply(EngineInput{"CTL", 1, 1000, zero}, zero);
  ASSERT_EQ(p.events.back().kind, EventKind::Refused);
  EXPECT_EQ(p.lastText(), "CTL seq 1: set_pose: stddev must be > 0");
  const ControlCommand nan = SetPose{Pose(std::nan(""), 2, 0.1), Vec3(0.1, 0.1, 0.1)};
  p.commands.apply(EngineInput{"CTL", 2, 1000, nan}, nan);
  ASSERT_EQ(p.events.back().kind, EventKind::Refused);
  EXPECT_NE(p.lastText().find("(pose and stddev must be finite, stddev > 0)"), std::string::npos) << p.lastText();
  p.bank.forEach([&](Filter& f, bool) { EXPECT_EQ(Vec3(f.state().x.head<3>()), p.cfg.filter.initial_pose); });
  const ControlCommand ok = SetPose{Pose(1, 2, 0.1), Vec3(0.1, 0.1, 0.1)};
  p.commands.apply(EngineInput{"CTL", 3, 1000, ok}, ok);
  ASSERT_EQ(p.events.back().kind, EventKind::Ack);
  EXPECT_EQ(p.lastText(), "CTL seq 3: set_pose");
  p.bank.forEach([&](Filter& f, bool) { EXPECT_EQ(Vec3(f.state().x.head<3>()), Vec3(1, 2, 0.1)) << f.name(); });
}

TEST(Commands, ResetStartsEveryFilterFromItsConfigurationAndClearsTheFixCounts) {
  EngineConfig c = config("ukf_gated", {"dead_reckoning"});
  c.fix_gate.lockout_rejections = 5;
  Parts p(c);
  const ControlCommand pose = SetPose{Pose(1, 2, 0.1), Vec3(0.1, 0.1, 0.1)};
  p.commands.apply(EngineInput{"CTL", 1, 1000, pose}, pose);
  const EngineInput far = bearingsFrom(Vec3(30, 20, M_PI / 2), c.landmarks, 1500, 2);
  p.fixes.process(far, std::get<BearingsInput>(far.payload));
  ASSERT_EQ(p.fixes.refusedInARow("active ukf_gated"), 1);
  const ControlCommand reset = ResetFilter{};
  p.commands.apply(EngineInput{"CTL", 3, 2000, reset}, reset);
  ASSERT_EQ(p.events.back().kind, EventKind::Ack);
  EXPECT_EQ(p.lastText(), "CTL seq 3: reset ukf_gated");
  EXPECT_EQ(p.fixes.refusedInARow("active ukf_gated"), 0);
  p.bank.forEach([&](Filter& f, bool) {
    EXPECT_EQ(Vec3(f.state().x.head<3>()), c.filter.initial_pose) << f.name();
    EXPECT_EQ(f.state().utime, 2000) << f.name();
  });
}

// ---- the engine: a new time base resets every part ----

TEST(EngineParts, TimeGoingBackStartsEveryPartAfresh) {
  EngineConfig c = config("ukf_gated");
  c.fix_gate.lockout_rejections = 2;
  c.reorder_window_us = 0;
  c.max_time_jump_us = 1000000;
  std::vector<EngineEvent> events;
  EngineOutputs out;
  out.on_event = [&](const EngineEvent& e) { events.push_back(e); };
  FusionEngine e(c, {}, out);
  const Vec3 far(10, -5, M_PI / 2);
  int64_t t = 100000000;
  ASSERT_TRUE(e.push(odo(t, 1, 0.0)));
  ASSERT_TRUE(e.push(bearingsFrom(far, c.landmarks, t += 10000, 1)));
  ASSERT_TRUE(e.push(odo(t += 10000, 2, 0.0)));
  ASSERT_TRUE(e.push(bearingsFrom(far, c.landmarks, t += 10000, 2)));
  ASSERT_TRUE(e.push(odo(t += 10000, 3, 0.0)));
  // The sources start over at utime 1000.
  for (int k = 0; k < 3; ++k) ASSERT_TRUE(e.push(odo(1000 + k * 200000, 1 + k, 0.0)));
  ASSERT_TRUE(e.push(bearingsFrom(far, c.landmarks, 500000, 3)));
  ASSERT_TRUE(e.push(odo(600000, 4, 0.0)));
  e.flush();
  std::vector<std::string> seen;
  for (const auto& ev : events) {
    std::string s = eventName(ev.kind);
    if (const auto* g = std::get_if<events::FixGated>(&ev.fields)) s += " " + std::to_string(g->in_a_row);
    seen.push_back(s);
  }
  // The third far fix is refused as the first of the new time base, not taken by the lockout
  // the old base's two refusals would have made of it.
  EXPECT_EQ(seen, (std::vector<std::string>{"fix_refused 1", "fix_refused 2", "time_jump", "fix_refused 1"}));
  EXPECT_EQ(Vec3(e.activeState().x.head<3>()), c.filter.initial_pose);
}
