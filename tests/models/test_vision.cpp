// Vision sensor model (bearings to landmarks, seeds/004 §III) and its hand-over to the
// three-landmark fix.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <stdexcept>

#include "lcmloc/core/landmark_fix.hpp"
#include "lcmloc/sim/vision_sensor.hpp"
#include "lcmloc/sim/world.hpp"

using namespace lcmloc;
using namespace lcmloc::sim;

namespace {
constexpr double kPi = 3.14159265358979323846;

VisionSensorConfig exact() {
  VisionSensorConfig c;
  c.bearing_std = 0.0;
  c.resolution = 0.0;
  return c;
}

double bearingOf(VisionSensor& s, double x, double y, double heading, int id) {
  const VisionSample v = s.observe(x, y, heading);
  for (std::size_t i = 0; i < v.ids.size(); ++i)
    if (v.ids[i] == id) return v.bearings[i];
  ADD_FAILURE() << "landmark " << id << " not observed";
  return NAN;
}
}  // namespace

TEST(VisionSensor, NoiseFreeBearingsAreExact) {
  // Landmarks east, north, west, south of the origin at 10 m.
  VisionSensor s(exact(), {{1, 10, 0}, {2, 0, 10}, {3, -10, 0}, {4, 0, -10}}, 1);
  // Heading east (body x along world X): bearings are the directions CCW from east.
  EXPECT_NEAR(bearingOf(s, 0, 0, 0.0, 1), 0.0, 1e-15);
  EXPECT_NEAR(bearingOf(s, 0, 0, 0.0, 2), kPi / 2, 1e-15);
  EXPECT_NEAR(bearingOf(s, 0, 0, 0.0, 3), kPi, 1e-15);  // behind: +pi, not -pi
  EXPECT_NEAR(bearingOf(s, 0, 0, 0.0, 4), -kPi / 2, 1e-15);
  // Heading north: the east landmark is on the right (-pi/2), the west one on the left.
  EXPECT_NEAR(bearingOf(s, 0, 0, kPi / 2, 1), -kPi / 2, 1e-15);
  EXPECT_NEAR(bearingOf(s, 0, 0, kPi / 2, 3), kPi / 2, 1e-15);
  // Off the origin: landmark 1 seen from (10, -10) heading north-east is 45 deg to the left.
  EXPECT_NEAR(bearingOf(s, 10, -10, kPi / 4, 1), kPi / 4, 1e-15);
  const VisionSample v = s.observe(3, 4, 0.3, 77);
  EXPECT_EQ(v.utime, 77);
  EXPECT_EQ(v.ids, (std::vector<int>{1, 2, 3, 4}));  // map order
  EXPECT_EQ(v.bearing_std, 0.0);
}

TEST(VisionSensor, QuantizedToTheResolution) {
  VisionSensorConfig c = exact();
  c.resolution = 14.0 * kArcSec;
  VisionSensor s(c, {{7, 1000, 0}}, 1);
  std::set<long long> steps;
  // Sweep the heading through 200" in 1" steps: every reading is a multiple of 14", within 7"
  // of the truth, and consecutive distinct readings differ by exactly one step.
  for (int k = 0; k <= 200; ++k) {
    const double h = -100.0 * kArcSec + k * kArcSec;
    const double b = bearingOf(s, 0, 0, h, 7);
    const double q = b / c.resolution;
    EXPECT_NEAR(q, std::round(q), 1e-6) << k;
    EXPECT_LE(std::abs(b - (-h)), 0.5 * c.resolution + 1e-12) << k;
    steps.insert(std::llround(q));
  }
  EXPECT_EQ(*steps.rbegin() - *steps.begin() + 1, static_cast<long long>(steps.size()));  // no gaps
  EXPECT_GE(steps.size(), 14u);  // 200" / 14"
  EXPECT_NEAR(VisionSensor::effectiveStd(c), 14.0 * kArcSec / std::sqrt(12.0), 1e-15);
}

TEST(VisionSensor, WrappedToMinusPiPi) {
  VisionSensorConfig c;  // the paper's noise and resolution
  VisionSensor s(c, {{1, -1000, 0}}, 3);
  // Landmark straight behind: noise puts the reading on both sides of +-pi; all in (-pi, pi].
  int above = 0, below = 0;
  for (int k = 0; k < 2000; ++k) {
    const double b = s.observe(0, 0, 0.0).bearings.at(0);
    EXPECT_GT(b, -kPi);
    EXPECT_LE(b, kPi);
    (b > 0 ? above : below)++;
    EXPECT_LT(std::abs(std::remainder(b - kPi, 2 * kPi)), 6 * VisionSensor::effectiveStd(c));
  }
  EXPECT_GT(above, 500);
  EXPECT_GT(below, 500);
  EXPECT_DOUBLE_EQ(VisionSensor::quantize(kPi + 1e-9, 0.0), -kPi + 1e-9);
  EXPECT_DOUBLE_EQ(VisionSensor::quantize(-kPi, 0.0), kPi);
}

TEST(VisionSensor, NoiseHasTheConfiguredSigmaAndIsSeeded) {
  VisionSensorConfig c;  // 30" noise, 14" resolution
  VisionSensor a(c, {{1, 500, 200}}, 42), b(c, {{1, 500, 200}}, 42), d(c, {{1, 500, 200}}, 43);
  const double truth = VisionSensor::trueBearing(0, 0, 0.1, 500, 200);
  const int n = 20000;
  double sum = 0, sum2 = 0;
  int differ = 0;
  for (int k = 0; k < n; ++k) {
    const double x = a.observe(0, 0, 0.1).bearings[0];
    EXPECT_EQ(x, b.observe(0, 0, 0.1).bearings[0]);  // same seed, same numbers
    differ += x != d.observe(0, 0, 0.1).bearings[0];
    const double e = x - truth;
    sum += e;
    sum2 += e * e;
  }
  const double mean = sum / n, sd = std::sqrt(sum2 / n - mean * mean);
  EXPECT_LT(std::abs(mean), 4 * c.bearing_std / std::sqrt(n));
  EXPECT_NEAR(sd / VisionSensor::effectiveStd(c), 1.0, 0.03);  // 30.27"
  EXPECT_GT(differ, n / 2);
}

TEST(VisionSensor, RateAndMaxRange) {
  VisionSensorConfig c = exact();
  c.rate_hz = 2.0;
  c.max_range = 150.0;
  VisionSensor s(c, {{5, 100, 0}, {6, 0, 200}, {9, -50, 0}}, 1);
  std::vector<int64_t> when;
  for (int k = 0; k <= 200; ++k) {  // 100 Hz truth for 2 s
    TruthState t;
    t.utime = 1000000 + k * 10000;
    if (auto v = s.sample(t)) {
      when.push_back(v->utime);
      EXPECT_EQ(v->ids, (std::vector<int>{5, 9}));  // landmark 6 is 200 m away
    }
  }
  EXPECT_EQ(when, (std::vector<int64_t>{1000000, 1500000, 2000000, 2500000, 3000000}));
  TruthState nan_truth;
  nan_truth.utime = 9000000;
  nan_truth.x = NAN;
  EXPECT_FALSE(s.sample(nan_truth).has_value());  // non-finite truth: no observation
  nan_truth.x = 0;
  nan_truth.heading = INFINITY;
  EXPECT_FALSE(s.sample(nan_truth).has_value());
  nan_truth.heading = 0;
  EXPECT_TRUE(s.sample(nan_truth).has_value());
  VisionSensor far(c, {{6, 0, 200}}, 1);
  EXPECT_TRUE(far.observe(0, 0, 0).ids.empty());
}

TEST(VisionSensor, BadMapOrConfigRefused) {
  try {
    VisionSensor s(exact(), {{1, 0, 0}, {2, 5, 5}, {1, 3, 3}}, 1);
    FAIL() << "duplicate id accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("landmarks[2]: duplicate landmark id 1"), std::string::npos) << e.what();
  }
  try {
    VisionSensor s(exact(), {{1, 0, 0}, {2, NAN, 5}}, 1);
    FAIL() << "NaN accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("landmarks[1]: position of landmark 2 is not finite"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(landmarkMap({{3, INFINITY, 0}}), std::invalid_argument);
  VisionSensorConfig c = exact();
  c.rate_hz = 0;
  EXPECT_THROW(VisionSensor(c, {}, 1), std::invalid_argument);
  c = exact();
  c.bearing_std = -1;
  EXPECT_THROW(VisionSensor(c, {}, 1), std::invalid_argument);
}

TEST(VisionSensor, FixConventionMatchesTheCoreModel) {
  // toFixBearings/toFixHeading turn this project's CCW-from-east frame into the fix's
  // clockwise-from-north one: the core's predicted bearings equal the converted measurements.
  const std::vector<Landmark> lms{{1, 300, 800}, {2, -700, -100}, {3, 600, -500}};
  VisionSensor s(exact(), lms, 1);
  for (double h : {0.0, 0.7, -2.0, 3.1}) {
    const auto b = toFixBearings(s.observe(20, -40, h));
    ASSERT_EQ(b.size(), 3u);
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(b[i].landmark_id, lms[i].id);
      const double pred = core::landmark::predictBearing(Eigen::Vector2d(20, -40), toFixHeading(h),
                                                         Eigen::Vector2d(lms[i].x, lms[i].y));
      EXPECT_NEAR(std::remainder(b[i].alpha - pred, 2 * kPi), 0.0, 1e-12) << h;
    }
    EXPECT_NEAR(toFixHeading(toFixHeading(h)), h, 1e-15);
  }
  // The fix on these bearings recovers the pose in the fix's convention.
  const auto map = landmarkMap(lms);
  const auto r = core::landmark::triangleFix(map, toFixBearings(s.observe(20, -40, 0.7)), Eigen::Vector2d(400, -500),
                                             toFixHeading(0.7) + 0.01);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_LT((r.position - Eigen::Vector2d(20, -40)).norm(), 1e-6);
  EXPECT_NEAR(toFixHeading(r.heading), 0.7, 1e-9);
}

TEST(VisionSensor, FixRefusesUnknownLandmarkAndDangerCircle) {
  // The sensor sees a landmark the fix's map does not have: refused, naming it.
  const std::vector<Landmark> seen{{1, 0, 577.35}, {2, 500, -288.675}, {4, -500, -288.675}};
  VisionSensor s(exact(), seen, 1);
  auto map = landmarkMap({{1, 0, 577.35}, {2, 500, -288.675}, {3, -500, -288.675}});
  const auto b = toFixBearings(s.observe(0, 0, 1.0));
  for (const auto& r : {core::landmark::triangleFix(map, b, {0, 0}, toFixHeading(1.0)),
                        core::landmark::leastSquaresFix(map, b, {0, 0}, toFixHeading(1.0))}) {
    EXPECT_FALSE(r.ok);
    EXPECT_NE(r.error.find("landmark 4 is not in the map"), std::string::npos) << r.error;
  }
  // Vehicle 0.5 m and 10 m inside the circle through the three landmarks (radius 577.35 m;
  // position std 95 m and 4.7 m there), INS 28 m off, the paper's noise: refused from the
  // condition number, with the reason. 100 m inside (std 0.4 m) it is accepted.
  VisionSensor noisy(VisionSensorConfig{}, {{1, 0, 577.35}, {2, 500, -288.675}, {3, -500, -288.675}}, 9);
  for (double inside : {0.5, 10.0, 100.0}) {
    const double a = 2.0, rr = 577.35 - inside;
    const Eigen::Vector2d p(rr * std::cos(a), rr * std::sin(a)), p_ins = p + Eigen::Vector2d(20, -20);
    const auto bn = toFixBearings(noisy.observe(p.x(), p.y(), 0.2));
    for (const auto& r : {core::landmark::triangleFix(map, bn, p_ins, toFixHeading(0.2) + 0.005),
                          core::landmark::leastSquaresFix(map, bn, p_ins, toFixHeading(0.2) + 0.005)}) {
      if (inside > 50) {
        EXPECT_TRUE(r.ok) << r.error;
        EXPECT_LT((r.position - p).norm(), 3.0);
        continue;
      }
      EXPECT_FALSE(r.ok) << inside;
      EXPECT_NE(r.error.find("danger circle"), std::string::npos) << r.error;
      EXPECT_GT(r.condition, core::landmark::FixOptions{}.max_condition);
    }
  }
}
