// Input ordering (InputOrder: the time-jump guard and the reorder window), canonical ranks, and
// the words of typed events.
#include <gtest/gtest.h>

#include <climits>
#include <string>
#include <vector>

#include "lcmloc/core/engine_events.hpp"
#include "lcmloc/core/engine_input.hpp"
#include "lcmloc/core/input_order.hpp"

using namespace lcmloc::core;

namespace {

EngineInput odo(int64_t utime, int64_t seq, const std::string& channel = "ODOMETRY") {
  OdometryInput o;
  o.utime = utime;
  return EngineInput{channel, seq, utime, o};
}

/// Records what the ordering hands on, one line per call.
struct Client : InputOrder::Client {
  std::vector<std::string> log;
  InputOrder* order = nullptr;  ///< reset on a time base behind, as the engine does
  static std::string name(const EngineInput& in) { return in.channel + "#" + std::to_string(in.seq); }
  void process(const EngineInput& in) override { log.push_back("process " + name(in)); }
  void late(const EngineInput& in, bool duplicate, int64_t processed) override {
    log.push_back("late " + name(in) + (duplicate ? " duplicate" : " after " + std::to_string(processed)));
  }
  void releasedEarly(const EngineInput& in) override { log.push_back("early " + name(in)); }
  void outlier(const EngineInput& in, bool ahead, int64_t newest) override {
    log.push_back("outlier " + name(in) + (ahead ? " ahead of " : " behind ") + std::to_string(newest));
  }
  void commandAhead(const EngineInput& in, int64_t newest) override {
    log.push_back("command ahead " + name(in) + " of " + std::to_string(newest));
  }
  void timeJumped(const EngineInput& first, int64_t newest, bool back) override {
    log.push_back(std::string(back ? "back " : "ahead ") + name(first) + " after " + std::to_string(newest));
    if (back && order) order->reset();
  }
};

}  // namespace

TEST(CanonicalRank, EachKindOfInputHasItsOwnRankInTheDocumentedOrder) {
  static_assert(kCanonicalRank<ControlCommand> < kCanonicalRank<OdometryInput>);
  static_assert(kCanonicalRank<OdometryInput> < kCanonicalRank<RulerDetection>);
  static_assert(kCanonicalRank<RulerDetection> < kCanonicalRank<ImuInput>);
  static_assert(kCanonicalRank<ImuInput> < kCanonicalRank<GpsInput>);
  static_assert(kCanonicalRank<GpsInput> < kCanonicalRank<LandmarkObservation>);
  static_assert(kCanonicalRank<LandmarkObservation> < kCanonicalRank<BeaconRange>);
  static_assert(kCanonicalRank<BeaconRange> < kCanonicalRank<BearingsInput>);
  EngineInput in = odo(5, 1);
  EXPECT_EQ(canonicalRank(in), kCanonicalRank<OdometryInput>);
  in.payload = BearingsInput{};
  EXPECT_EQ(canonicalRank(in), kCanonicalRank<BearingsInput>);
  // The key: utime first, then the rank of the kind, whatever the channel's hash.
  EXPECT_LT(canonicalKey(EngineInput{"Z", 9, 5, ControlCommand(ResetFilter{})}), canonicalKey(odo(5, 0, "A")));
  EXPECT_LT(canonicalKey(EngineInput{"Z", 9, 4, BearingsInput{}}), canonicalKey(odo(5, 0, "A")));
}

TEST(InputOrder, AtEqualTimeInputsComeOutByTheRankOfTheirKind) {
  Client c;
  InputOrder order(1000, 0, c);
  const int64_t t = 100;
  // Pushed in the reverse of the canonical order, all at one utime.
  ASSERT_TRUE(order.push(EngineInput{"VISION", 1, t, BearingsInput{}}));
  ASSERT_TRUE(order.push(EngineInput{"BEACONS", 1, t, BeaconRange{}}));
  ASSERT_TRUE(order.push(EngineInput{"LANDMARKS", 1, t, LandmarkObservation{}}));
  ASSERT_TRUE(order.push(EngineInput{"GPS", 1, t, GpsInput{}}));
  ASSERT_TRUE(order.push(EngineInput{"IMU", 1, t, ImuInput{}}));
  ASSERT_TRUE(order.push(EngineInput{"MAGRULER", 1, t, RulerDetection{}}));
  ASSERT_TRUE(order.push(odo(t, 1)));
  ASSERT_TRUE(order.push(EngineInput{"FUSION_CONTROL", 1, t, ControlCommand(ResetFilter{})}));
  EXPECT_TRUE(c.log.empty());  // all inside the window
  order.flush();
  EXPECT_EQ(c.log, (std::vector<std::string>{"process FUSION_CONTROL#1", "process ODOMETRY#1", "process MAGRULER#1",
                                             "process IMU#1", "process GPS#1", "process LANDMARKS#1",
                                             "process BEACONS#1", "process VISION#1"}));
}

TEST(InputOrder, TheWindowReleasesOldInputsAndRefusesLateAndDuplicateOnes) {
  Client c;
  InputOrder order(1000, 0, c);
  ASSERT_TRUE(order.push(odo(100, 1)));
  ASSERT_TRUE(order.push(odo(50, 2, "ODO_B")));   // out of order, inside the window
  ASSERT_FALSE(order.push(odo(50, 2, "ODO_B")));  // the same key again
  ASSERT_TRUE(order.push(odo(1200, 3)));          // releases what is older than 1200 - 1000
  EXPECT_EQ(c.log, (std::vector<std::string>{"late ODO_B#2 duplicate", "process ODO_B#2", "process ODOMETRY#1"}));
  c.log.clear();
  EXPECT_FALSE(order.push(odo(90, 4)));  // older than what was processed
  EXPECT_EQ(c.log, (std::vector<std::string>{"late ODOMETRY#4 after 100"}));
  EXPECT_EQ(order.queued(), 1u);
}

TEST(InputOrder, ACommandNeitherReleasesInputsNorWaitsForATimeBeyondTheGuard) {
  Client c;
  InputOrder order(1000, 1000000, c);
  ASSERT_TRUE(order.push(odo(100, 1)));
  // 0.5 s ahead: waits; it does not carry the window's time (ODOMETRY#1 stays queued).
  ASSERT_TRUE(order.push(EngineInput{"FUSION_CONTROL", 1, 500100, ControlCommand(ResetFilter{})}));
  EXPECT_TRUE(c.log.empty());
  // More than the guard (1 s) ahead of the newest input: refused.
  EXPECT_FALSE(order.push(EngineInput{"FUSION_CONTROL", 2, 2000000, ControlCommand(ResetFilter{})}));
  EXPECT_EQ(c.log, (std::vector<std::string>{"command ahead FUSION_CONTROL#2 of 100"}));
  c.log.clear();
  ASSERT_TRUE(order.push(odo(600000, 2)));
  EXPECT_EQ(c.log, (std::vector<std::string>{"process ODOMETRY#1", "process FUSION_CONTROL#1"}));
}

TEST(InputOrder, OneInputFarAheadIsAnOutlierWhenItsTimeBaseDoesNotGoOn) {
  Client c;
  InputOrder order(0, 1000000, c);
  ASSERT_TRUE(order.push(odo(1000000, 1)));
  ASSERT_TRUE(order.push(odo(900000000, 2)));  // held
  ASSERT_TRUE(order.push(odo(1010000, 3)));    // the old time base goes on
  EXPECT_EQ(c.log, (std::vector<std::string>{"outlier ODOMETRY#2 ahead of 1000000", "process ODOMETRY#1"}));
  c.log.clear();
  ASSERT_TRUE(order.push(odo(5000, 4)));  // more than 1 s behind: held, then dropped at the end
  order.flush();
  EXPECT_EQ(c.log, (std::vector<std::string>{"outlier ODOMETRY#4 behind 1010000", "process ODOMETRY#3"}));
}

TEST(InputOrder, InputsThatConfirmATimeBaseAheadAreAllTaken) {
  Client c;
  InputOrder order(0, 1000000, c);
  ASSERT_TRUE(order.push(odo(1000000, 1)));
  const int64_t t = 50000000;
  for (int k = 0; k < 3; ++k) ASSERT_TRUE(order.push(odo(t + k * order.confirmSpan(), 2 + k)));
  EXPECT_EQ(c.log, (std::vector<std::string>{"ahead ODOMETRY#2 after 1000000", "process ODOMETRY#1",
                                             "process ODOMETRY#2", "process ODOMETRY#3"}));
  EXPECT_EQ(order.newest(), t + 2 * order.confirmSpan());
}

TEST(InputOrder, TimeGoingBackProcessesTheOldBaseFirstThenStartsOver) {
  Client c;
  InputOrder order(100000, 1000000, c);
  c.order = &order;
  const int64_t t = 100000000;
  ASSERT_TRUE(order.push(odo(t, 1)));
  ASSERT_TRUE(order.push(odo(t + 10000, 2)));  // both queued in the window
  // The sources start over at utime 1000: three inputs spanning the confirmation span.
  for (int k = 0; k < 3; ++k) ASSERT_TRUE(order.push(odo(1000 + k * order.confirmSpan(), 10 + k)));
  ASSERT_GE(c.log.size(), 3u);
  EXPECT_EQ(c.log[0], "process ODOMETRY#1");  // what was queued of the old base goes first
  EXPECT_EQ(c.log[1], "process ODOMETRY#2");
  EXPECT_EQ(c.log[2], "back ODOMETRY#10 after " + std::to_string(t + 10000));
  // The new base's inputs are taken afresh: none is "late" against the old base's time.
  for (const auto& line : c.log) EXPECT_EQ(line.find("late"), std::string::npos) << line;
  EXPECT_EQ(order.newest(), 1000 + 2 * order.confirmSpan());
  order.flush();
  EXPECT_EQ(c.log.back(), "process ODOMETRY#12");
}

TEST(InputOrder, ResetForgetsWhatWasProcessedAndWhatWasHeld) {
  Client c;
  InputOrder order(0, 1000000, c);
  ASSERT_TRUE(order.push(odo(5000000, 1)));
  ASSERT_TRUE(order.push(odo(100000000, 2)));  // held
  order.reset();
  EXPECT_EQ(order.newest(), INT64_MIN);
  ASSERT_TRUE(order.push(odo(1000, 3)));  // older than ODOMETRY#1, but time started over
  order.flush();
  // Both forgotten: ODOMETRY#1 queued, ODOMETRY#2 held (not even an outlier).
  EXPECT_EQ(c.log, (std::vector<std::string>{"process ODOMETRY#3"}));
}

TEST(EngineEvents, KindsHaveTheirStatusNames) {
  EXPECT_STREQ(eventName(EventKind::TooOld), "too_old");
  EXPECT_STREQ(eventName(EventKind::TooNew), "too_new");
  EXPECT_STREQ(eventName(EventKind::OdometryGap), "odometry_gap");
  EXPECT_STREQ(eventName(EventKind::FixRefused), "fix_refused");
  EXPECT_STREQ(eventName(EventKind::ImuSaturated), "imu_saturated");
  EXPECT_STREQ(eventName(EventKind::Ack), "ack");
}

TEST(EngineEvents, TextIsTheStatusDetail) {
  const InputRef in{"MAGRULER", 7, 2500000};
  EXPECT_EQ(eventText({EventKind::TooOld, 0, events::Late{in, false, 3000000}}),
            "MAGRULER seq 7 utime 2500000: older than already processed utime 3000000");
  EXPECT_EQ(eventText({EventKind::TooOld, 0, events::Late{in, true, 0}}), "MAGRULER seq 7 utime 2500000: duplicate");
  EXPECT_EQ(eventText({EventKind::TooNew, 0, events::Outlier{in, true, 500000, 400000}}),
            "MAGRULER seq 7 utime 2500000: 2 s ahead of the newest input (utime 500000), not followed by its time "
            "base; no odometry for 2.100 s before it (the last at utime 400000): the odometry is missing, nothing "
            "places this input");
  EXPECT_EQ(eventText({EventKind::TooOld, 0, events::Outlier{in, false, 9000000, INT64_MIN}}),
            "MAGRULER seq 7 utime 2500000: 6 s behind the newest input (utime 9000000), not followed by its time base");
  EXPECT_EQ(eventText({EventKind::TimeJump, 0, events::TimeJump{in, 9000000, 200000, true, "ukf_gated"}}),
            "MAGRULER seq 7: time went back 6 s (utime 2500000 after 9000000, confirmed by the inputs of 200 ms in a "
            "row): the sources started over; ukf_gated restarted from the configured initial state");
  using C = events::Answer::Command;
  const InputRef cmd{"FUSION_CONTROL", 3, 100};
  EXPECT_EQ(eventText({EventKind::Ack, 100, events::Answer{cmd, C::Switch, "ukf", "ukf_gated", ""}}),
            "FUSION_CONTROL seq 3: switched ukf_gated -> ukf");
  EXPECT_EQ(eventText({EventKind::Refused, 100, events::Answer{cmd, C::Switch, "nope", "", "unknown type"}}),
            "FUSION_CONTROL seq 3: switch to 'nope': unknown type");
  EXPECT_EQ(eventText({EventKind::Refused, 100, events::Answer{cmd, C::SetPose, "", "", "stddev must be > 0"}}),
            "FUSION_CONTROL seq 3: set_pose: stddev must be > 0");
  EXPECT_EQ(eventText({EventKind::Ack, 100, events::Answer{cmd, C::SetPose, "", "", ""}}), "FUSION_CONTROL seq 3: set_pose");
  EXPECT_EQ(eventText({EventKind::Recovered, 0, events::Recovered{"ukf", true}}),
            "ukf: measurement accepted again after the odometry gap");
}
