// lcmloc-vision as a process: GROUND_TRUTH in, landmark_bearings_t on VISION out, over udpm on
// loopback with a port of its own.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <map>

#include <nlohmann/json.hpp>

#include "process_fixture.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/ground_truth_t.hpp"
#include "lcmloc/landmark_bearings_t.hpp"

using namespace std::chrono_literals;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kArcSec = kPi / 180.0 / 3600.0;

class VisionProcess : public ProcessFixture {
 protected:
  /// Publishes ground truth at 100 Hz of message time (a pose per sample from pose(k)) until
  /// `want` VISION messages arrived or the time runs out; returns the truth sent, by utime.
  std::map<int64_t, lcmloc::ground_truth_t> drive(lcmloc::bus::Bus& bus, std::vector<lcmloc::landmark_bearings_t>& got,
                                                 std::size_t want,
                                                 const std::function<void(int, lcmloc::ground_truth_t&)>& pose) {
    std::map<int64_t, lcmloc::ground_truth_t> sent;
    const auto deadline = std::chrono::steady_clock::now() + 20s;
    for (int k = 0; got.size() < want && std::chrono::steady_clock::now() < deadline; ++k) {
      lcmloc::ground_truth_t t{};
      t.utime = 1000000 + int64_t{k} * 10000;
      t.seq = k;
      pose(k, t);
      sent[t.utime] = t;
      bus.publish("GROUND_TRUTH", t);
      bus.handle(5);
    }
    const auto until = std::chrono::steady_clock::now() + 500ms;
    while (std::chrono::steady_clock::now() < until) bus.handle(20);
    return sent;
  }
};

}  // namespace

TEST_F(VisionProcess, GroundTruthInBearingsOut) {
  // Noise-free sensor at 10 Hz; landmark 9 is beyond max_range.
  const std::string cfg = writeFile("vision.yaml", R"(
vision: {rate_hz: 10, bearing_std: 0, resolution: 0, max_range: 2000}
landmarks:
  - {id: 4, x: 1000, y: 0}
  - {id: 2, x: 0, y: 1000}
  - {id: 7, x: -700, y: -700}
  - {id: 9, x: 5000, y: 5000}
)");
  lcmloc::bus::Bus bus(url_);
  std::vector<lcmloc::landmark_bearings_t> got;
  bus.subscribe<lcmloc::landmark_bearings_t>(
      "VISION", [&](const std::string&, const lcmloc::landmark_bearings_t& m, int64_t) { got.push_back(m); });
  Child vision(LCMLOC_VISION, {"--config", cfg, "--lcm-url", url_}, path("vision.log"));
  const auto sent = drive(bus, got, 8, [](int k, lcmloc::ground_truth_t& t) {
    t.x = 3.0 * k;
    t.y = -1.5 * k;
    t.heading = std::remainder(0.05 * k - 2.0, 2 * kPi);
    t.speed = 3.0;
    if (k % 25 == 20) t.x = NAN;  // bad truth: skipped, the next sample observed instead
  });
  ASSERT_GE(got.size(), 8u) << vision.output();
  for (std::size_t i = 0; i < got.size(); ++i) {
    const auto& m = got[i];
    if (i > 0) {
      EXPECT_EQ(m.seq, got[i - 1].seq + 1);
      // 10 Hz of message time on the grid of the first sample; after a skipped (non-finite)
      // sample the observation comes one truth period (10 ms) late.
      EXPECT_GE(m.utime - got[i - 1].utime, 90000);
      EXPECT_LE(m.utime - got[i - 1].utime, 110000);
    }
    ASSERT_EQ(m.count, 3);
    EXPECT_EQ(m.landmark_ids, (std::vector<int32_t>{4, 2, 7}));
    EXPECT_EQ(m.bearing_std, 0.0);
    const auto it = sent.find(m.utime);
    ASSERT_NE(it, sent.end()) << "utime " << m.utime << " was not a ground-truth time";
    const auto& t = it->second;
    EXPECT_TRUE(std::isfinite(t.x)) << "observation from a non-finite pose at utime " << m.utime;
    const double lx[3] = {1000, 0, -700}, ly[3] = {0, 1000, -700};
    for (int j = 0; j < 3; ++j) {
      const double want = std::remainder(std::atan2(ly[j] - t.y, lx[j] - t.x) - t.heading, 2 * kPi);
      EXPECT_NEAR(m.bearings[j], want, 1e-12) << "landmark " << m.landmark_ids[j] << " utime " << m.utime;
      EXPECT_GT(m.bearings[j], -kPi);
      EXPECT_LE(m.bearings[j], kPi);
    }
  }
  vision.signal(SIGINT);
  EXPECT_EQ(vision.wait(5s).value_or(-1), 0) << vision.output();
  EXPECT_NE(vision.output().find("non-finite pose"), std::string::npos) << vision.output();
}

TEST_F(VisionProcess, PaperSensorNoiseAndResolution) {
  const std::string cfg = writeFile("vision.yaml", R"(
vision: {rate_hz: 100, seed: 3}
landmarks: [{id: 1, x: 0, y: 577.35}, {id: 2, x: 500, y: -288.675}, {id: 3, x: -500, y: -288.675}]
)");
  lcmloc::bus::Bus bus(url_);
  std::vector<lcmloc::landmark_bearings_t> got;
  bus.subscribe<lcmloc::landmark_bearings_t>(
      "VISION", [&](const std::string&, const lcmloc::landmark_bearings_t& m, int64_t) { got.push_back(m); });
  Child vision(LCMLOC_VISION, {"--config", cfg, "--lcm-url", url_}, path("vision.log"));
  drive(bus, got, 60, [](int, lcmloc::ground_truth_t& t) { t.heading = kPi / 2; });  // at the centre, north
  ASSERT_GE(got.size(), 60u) << vision.output();
  const double truth[3] = {0.0, -2 * kPi / 3, 2 * kPi / 3};  // CCW from the body axis
  double se = 0;
  int n = 0;
  for (const auto& m : got) {
    ASSERT_EQ(m.count, 3);
    EXPECT_NEAR(m.bearing_std / kArcSec, std::sqrt(900.0 + 196.0 / 12.0), 1e-6);
    for (int j = 0; j < 3; ++j) {
      const double e = std::remainder(m.bearings[j] - truth[j], 2 * kPi);
      EXPECT_LT(std::abs(e), 6 * 30 * kArcSec);
      const double q = m.bearings[j] / (14 * kArcSec);
      EXPECT_NEAR(q, std::round(q), 1e-6);  // multiples of the 14" resolution
      se += e * e;
      ++n;
    }
  }
  const double rms = std::sqrt(se / n) / kArcSec;
  EXPECT_GT(rms, 20.0);  // 30.3" expected; n >= 180
  EXPECT_LT(rms, 40.0);
  vision.signal(SIGINT);
  EXPECT_EQ(vision.wait(5s).value_or(-1), 0) << vision.output();
}

TEST_F(VisionProcess, HelpAndBadConfig) {
  Child help(LCMLOC_VISION, {"--help"}, path("help.log"));
  EXPECT_EQ(help.wait(5s).value_or(-1), 0);
  EXPECT_NE(help.output().find("--config"), std::string::npos);
  const std::pair<const char*, const char*> cases[] = {
      {"landmarks: [{id: 1, x: 0, y: 0}, {id: 1, x: 5, y: 5}]\n", "landmarks[1].id: duplicate landmark id 1"},
      {"landmarks: [{id: 1, x: .nan, y: 0}]\n", "landmarks[0].x: expected a finite number"},
      {"vision: {rate_hz: 1}\n", "landmarks: 0 landmark(s): the three-landmark fix needs at least 3"},
      // one landmark: every VISION message went unused; two at one place: "landmark 2 used twice"
      {"landmarks: [{id: 1, x: 0, y: 0}]\n", "landmarks: 1 landmark(s): the three-landmark fix needs at least 3"},
      {"landmarks: [{id: 1, x: 0, y: 0}, {id: 2, x: 5, y: 5}, {id: 3, x: 0.0001, y: 0}]\n",
       "landmarks[2]: landmark 3 is at the place of landmark 1 (landmarks[0]), less than 1 mm apart"},
      {"vision: {rate_hz: 0}\nlandmarks: [{id: 1, x: 0, y: 0}]\n", "vision.rate_hz"}};
  for (const auto& [yaml, want] : cases) {
    const std::string bad = writeFile("bad.yaml", yaml);
    Child b(LCMLOC_VISION, {"--config", bad, "--lcm-url", url_}, path("bad.log"));
    EXPECT_EQ(b.wait(5s).value_or(-1), 2) << b.output();
    EXPECT_NE(b.output().find(want), std::string::npos) << b.output();
    EXPECT_NE(b.output().find("bad.yaml"), std::string::npos) << b.output();
  }
}

TEST_F(VisionProcess, RecordedSystemRunSolvedAtTheBound) {
  // lcmloc-launcher runs sim -> vision -> logger (config/landmark_system.yaml) on the paper's
  // path near the centre of a triangle of landmarks 1000 m apart; the experiment solves every
  // recorded VISION observation with the INS error of §III.
  const std::string log = path("run.lcmlog");
  const std::string scenario = writeFile("scenario.yaml", R"(
scenario: {name: landmark_paper, seed: 5, realtime_factor: 10}
vision: {rate_hz: 5, seed: 5}
landmarks:
  - {id: 1, x: 0.0, y: 577.350}
  - {id: 2, x: 500.0, y: -288.675}
  - {id: 3, x: -500.0, y: -288.675}
logger: {output: )" + log + "}\n");
  Child launcher(LCMLOC_LAUNCHER, {"--system", LCMLOC_LANDMARK_SYSTEM_YAML, "--config", scenario, "--lcm-url", url_},
                 path("launcher.out"));
  const auto rc = launcher.wait(90s);
  ASSERT_TRUE(rc.has_value()) << launcher.output();
  ASSERT_EQ(*rc, 0) << launcher.output();
  Child exp(LCMLOC_LANDMARK_EXPERIMENT, {"--log", log, "--config", scenario, "-o", path("report")},
            path("experiment.out"));
  ASSERT_EQ(exp.wait(30s).value_or(-1), 0) << exp.output();
  std::printf("%s", exp.output().c_str());
  EXPECT_NE(exp.output().find(" without, 0 bad messages"), std::string::npos) << exp.output();
  std::ifstream in(path("report/report.json"));
  ASSERT_TRUE(in.good());
  const auto j = nlohmann::json::parse(in);
  const auto& c = j["cases"][0];
  const int n = j["options"]["runs"];
  EXPECT_GE(n, 100) << "42 m at 1.5 m/s, 5 Hz";
  for (const char* m : {"triangle", "least_squares"}) {
    EXPECT_EQ(c["methods"][m]["ok"], n) << m;
    EXPECT_NEAR(c["methods"][m]["position_rms_over_crb"].get<double>(), 1.0, 0.25) << m;
    EXPECT_NEAR(c["methods"][m]["heading_std_over_crb"].get<double>(), 1.0, 0.3) << m;
  }
  EXPECT_NEAR(c["crb"]["position_rms_m"].get<double>(), 0.098, 0.005);
}
