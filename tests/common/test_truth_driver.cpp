// drivers::TruthDriver, the GROUND_TRUTH input every simulated sensor driver shares, over memq://:
// one rule (truthProblem) refuses unusable ground truth before any sensor model sees it, counts
// it ("bad_truth" in the heartbeat) and lets the samples after it through unharmed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "lcmloc/app/config.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/drivers/sim_convert.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/signals.hpp"
#include "lcmloc/drivers/truth_driver.hpp"
#include "lcmloc/ground_truth_t.hpp"
#include "lcmloc/heartbeat_t.hpp"
#include "lcmloc/sim/world.hpp"
#include "lcmloc/odometry_t.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

using namespace lcmloc;

namespace {

constexpr int64_t kMin = std::numeric_limits<int64_t>::min(), kMax = std::numeric_limits<int64_t>::max();
const double kNaN = std::numeric_limits<double>::quiet_NaN(), kInf = std::numeric_limits<double>::infinity();

/// Sample k of a straight drive along X at 1 m/s, 100 Hz of message time.
lcmloc::ground_truth_t truth(int64_t k) {
  lcmloc::ground_truth_t t{};
  t.utime = 1000000 + 10000 * k;
  t.seq = k;
  t.x = 0.01 * static_cast<double>(k);
  t.speed = 1.0;
  t.distance = t.x;
  return t;
}

void drain(bus::Bus& bus) {
  for (int i = 0; i < 100000 && bus.handle(0) > 0; ++i) {  // memq: published is queued
  }
}

/// Stops the driver (the stop flag stays set for the rest of this test process: every test
/// drives its driver by handling the bus itself) and returns the counters of its "stopping"
/// heartbeat.
std::map<std::string, int64_t> stop(bus::Bus& bus, drivers::TruthDriver& driver) {
  std::map<std::string, int64_t> counters;
  std::string state;
  bus.subscribe<lcmloc::heartbeat_t>("HEARTBEAT", [&](const std::string&, const lcmloc::heartbeat_t& m, int64_t) {
    state = m.state;
    for (int i = 0; i < m.num_counters; ++i) counters[m.counter_names[i]] = m.counters[i];
  });
  app::requestStop();
  EXPECT_EQ(driver.run([] { return std::string("nothing out"); }), app::kExitOk);
  drain(bus);
  EXPECT_EQ(state, "stopping");
  return counters;
}

}  // namespace

TEST(TruthProblem, AcceptsValidSamplesUpToTheEdgesOfTheRanges) {
  EXPECT_EQ(drivers::truthProblem(truth(0)), "");
  auto t = truth(3);
  t.utime = 0;
  EXPECT_EQ(drivers::truthProblem(t), "");
  t.utime = drivers::kTruthUtimeLimit - 1;
  EXPECT_EQ(drivers::truthProblem(t), "");
  t = truth(3);
  t.x = -drivers::kTruthLengthLimit;
  t.y = drivers::kTruthLengthLimit;
  t.distance = drivers::kTruthLengthLimit;
  t.speed = -drivers::kTruthSpeedLimit;
  t.heading = 100.0;  // the heading: finite is enough, the models wrap it
  t.steering = -1.5707;  // just inside -pi/2
  EXPECT_EQ(drivers::truthProblem(t), "");
}

TEST(TruthProblem, RefusesNonFiniteFieldsBadUtimesAndValuesNoVehicleReaches) {
  struct Field {
    const char* name;
    double lcmloc::ground_truth_t::*member;
  };
  const Field fields[] = {{"x", &lcmloc::ground_truth_t::x},           {"y", &lcmloc::ground_truth_t::y},
                          {"heading", &lcmloc::ground_truth_t::heading}, {"speed", &lcmloc::ground_truth_t::speed},
                          {"steering", &lcmloc::ground_truth_t::steering}, {"distance", &lcmloc::ground_truth_t::distance}};
  for (const auto& f : fields)
    for (const double v : {kNaN, kInf, -kInf}) {
      auto t = truth(5);
      t.*f.member = v;
      const std::string why = drivers::truthProblem(t);
      EXPECT_NE(why.find("non-finite"), std::string::npos) << f.name << " = " << v << ": '" << why << "'";
      EXPECT_NE(why.find(f.name), std::string::npos) << why;
    }
  auto t = truth(5);
  t.x = kNaN;
  EXPECT_EQ(drivers::truthProblem(t), "non-finite pose: x = nan");
  for (const int64_t u : {int64_t{-1}, kMin, kMax, kMax - 5, drivers::kTruthUtimeLimit}) {
    t = truth(5);
    t.utime = u;
    EXPECT_NE(drivers::truthProblem(t).find("utime"), std::string::npos) << u;
  }
  for (const double s : {M_PI / 2, -M_PI / 2, 1e308}) {
    t = truth(5);
    t.steering = s;
    EXPECT_NE(drivers::truthProblem(t).find("steering = "), std::string::npos) << s;
  }
  for (const double d : {1e300, -1e300, 1.0001e9}) {
    t = truth(5);
    t.distance = d;
    EXPECT_NE(drivers::truthProblem(t).find("distance"), std::string::npos) << d;
    t = truth(5);
    t.y = d;
    EXPECT_NE(drivers::truthProblem(t).find("y = "), std::string::npos) << d;
  }
  t = truth(5);
  t.speed = 1e300;
  EXPECT_NE(drivers::truthProblem(t).find("speed"), std::string::npos);
}

// The audit's samples (NaN fields, INT64_MIN / INT64_MAX utimes, a 1e300 m distance) reached every
// sensor model: an odometer stuck at NaN, IMU messages and GPS fixes with NaN, a fault injected at
// the wrong place, signed overflow in the time arithmetic.
TEST(TruthDriver, BadGroundTruthIsRefusedCountedAndNeverReachesTheModel) {
  bus::Bus bus("memq://");
  const simconfig::SimSystemConfig cfg;  // GROUND_TRUTH, HEARTBEAT, fusion.max_time_jump 1 s
  std::vector<lcmloc::ground_truth_t> seen;
  int restarts = 0;
  drivers::TruthDriver driver(
      bus, cfg, "test-driver", [&](const std::string&, const lcmloc::ground_truth_t& m) { seen.push_back(m); },
      [&] { ++restarts; });
  std::map<int64_t, lcmloc::ground_truth_t> bad;  // by seq
  for (int64_t k = 0; k < 30; ++k) {
    auto t = truth(k);
    switch (k) {
      case 3: t.x = kNaN; break;
      case 5: t.utime = kMin; break;
      case 7: t.utime = kMax - 5; break;
      case 9: t.distance = 1e300; break;
      case 11: t.speed = kInf; break;
      case 13: t.utime = -1; break;
      case 15: t.steering = kNaN; break;
      case 17: t.distance = kNaN; break;
      case 19: t.heading = -kInf; break;
      default: break;
    }
    if (k % 2 == 1 && k >= 3 && k <= 19) bad[k] = t;
    bus.publish(cfg.channels.ground_truth, t);
  }
  drain(bus);
  EXPECT_EQ(driver.received(), 30);
  ASSERT_EQ(seen.size(), 30u - bad.size());
  for (std::size_t i = 0; i < seen.size(); ++i) {
    EXPECT_EQ(bad.count(seen[i].seq), 0u) << "seq " << seen[i].seq << " reached the model";
    EXPECT_EQ(seen[i].utime, truth(seen[i].seq).utime);
    EXPECT_EQ(seen[i].distance, truth(seen[i].seq).distance);
    if (i > 0) {
      EXPECT_GT(seen[i].seq, seen[i - 1].seq);
    }
  }
  EXPECT_EQ(restarts, 0);  // INT64_MIN or -1 is no restarted simulator
  EXPECT_EQ(driver.badTruth(), static_cast<int64_t>(bad.size()));
  auto c = stop(bus, driver);
  EXPECT_EQ(c["received"], 30);
  EXPECT_EQ(c["bad_truth"], static_cast<int64_t>(bad.size()));
  EXPECT_EQ(c["dropped"], 0);  // refused before the time guard: not a time jump
  EXPECT_EQ(c["gaps"], 0);
}

// End to end through the driver frame, as lcmloc-odometry runs it: one NaN distance made the
// odometer publish 9.2e15 m once and 0 ever after, with no log line and no counter.
TEST(TruthDriver, OdometryIncrementsAreRightAfterANaNDistance) {
  bus::Bus bus("memq://");
  simconfig::SimSystemConfig cfg;
  auto& oc = cfg.scenario.odometry;  // 100 Hz, 1 mm ticks
  oc.scale_error = 0.0;
  oc.slip_std = 0.0;
  std::optional<sim::OdometrySensor> sensor;
  auto start = [&] { sensor.emplace(oc, 2.5, 7); };
  start();
  std::vector<lcmloc::odometry_t> out;
  bus.subscribe<lcmloc::odometry_t>(cfg.channels.odometry,
                                    [&](const std::string&, const lcmloc::odometry_t& m, int64_t) { out.push_back(m); });
  drivers::TruthDriver driver(
      bus, cfg, "lcmloc-odometry",
      [&](const std::string&, const lcmloc::ground_truth_t& m) {
        if (auto s = sensor->sample(drivers::toCore(m)))
          bus.publish(cfg.channels.odometry, drivers::toLcm(*s, driver.nextSeq()));
      },
      start);
  for (int64_t k = 0; k < 200; ++k) {
    auto t = truth(k);
    if (k == 100) t.distance = kNaN;
    if (k == 150) t.distance = 1e300;
    bus.publish(cfg.channels.ground_truth, t);
    drain(bus);
  }
  ASSERT_EQ(out.size(), 197u);  // every sample but the first and the two refused
  double sum = 0.0;
  for (const auto& m : out) {
    EXPECT_GE(m.delta_s, 0.0) << "utime " << m.utime;
    EXPECT_LE(m.delta_s, 0.0211) << "utime " << m.utime;  // 1 cm a sample, 2 after a refused one
    sum += m.delta_s;
  }
  EXPECT_NEAR(sum, 1.99, oc.tick_length);
  EXPECT_NEAR(out.back().delta_s, 0.01, oc.tick_length + 1e-9);
  const auto c = stop(bus, driver);
  EXPECT_EQ(c.at("bad_truth"), 2);
  EXPECT_EQ(c.at("published"), 197);
}
