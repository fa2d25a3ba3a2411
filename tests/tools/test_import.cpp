// lcmloc-import (CSV directory -> log, map, config) and the magnet-grid import and replay.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <optional>
#include <random>

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include "lcmloc/app/config.hpp"
#include "lcmloc/core/angles.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/drivers/sim_convert.hpp"
#include "lcmloc/gate_decision_t.hpp"
#include "lcmloc/gps_fix_t.hpp"
#include "lcmloc/ground_truth_t.hpp"
#include "lcmloc/app/csv.hpp"
#include "lcmloc/logio/log_reader.hpp"
#include "lcmloc/import/checks.hpp"
#include "lcmloc/import/import.hpp"
#include "lcmloc/import/import_command.hpp"
#include "lcmloc/import/magnet_grid.hpp"
#include "lcmloc/landmark_obs_t.hpp"
#include "lcmloc/odometry_t.hpp"
#include "lcmloc/pose_t.hpp"
#include "lcmloc/replay/replay.hpp"
#include "run_command.hpp"
#include "temp_files.hpp"

using namespace lcmloc;
namespace fs = std::filesystem;

namespace {

fs::path tempDir(const std::string& name) { return freshTempDir("lcmloc_test_import_", name); }

void write(const fs::path& p, const std::string& text) { writeText(p, text); }

std::map<std::string, int64_t> channelCounts(const std::string& log) {
  std::map<std::string, int64_t> n;
  logio::scanLog(log, [&](const logio::RawEvent& e) { ++n[*e.channel]; });
  return n;
}

const import::FileReport* file(const import::ImportResult& r, const std::string& name) {
  for (const auto& f : r.files)
    if (fs::path(f.path).filename() == name) return &f;
  return nullptr;
}

bool refused(const import::ImportResult& r, const std::string& name, int64_t line, const std::string& what) {
  for (const auto& f : r.refusals)
    if (fs::path(f.file).filename() == name && f.line == line && f.reason.find(what) != std::string::npos) return true;
  return false;
}

/// A robot on a circle of radius 2 m about the origin at 0.5 m/s, 10 Hz, starting at (2, 0)
/// heading north; landmarks around it. Writes odometry (delta_s, delta_theta), landmarks with a
/// known id and with "unknown", ground truth and the map, times in seconds from 100 s.
void writeCircleRun(const fs::path& d, int steps) {
  const std::vector<std::array<double, 3>> lm{{1, 5, 0}, {2, 0, 5}, {3, -5, 0}, {4, 0, -5}};
  std::string map = "id,x,y\n", odo = "time,delta_s,delta_theta\n", obs = "time,landmark_id,range,bearing\n",
              truth = "time,x,y,heading\n";
  for (const auto& l : lm) map += fmt::format("{},{},{}\n", l[0], l[1], l[2]);
  double x = 2, y = 0, th = M_PI / 2;
  const double ds = 0.05, dth = ds / 2.0;
  truth += fmt::format("100.0,{},{},{}\n", x, y, th);
  for (int k = 1; k <= steps; ++k) {
    const double t = 100.0 + 0.1 * k;
    x += ds * std::cos(th + dth / 2);
    y += ds * std::sin(th + dth / 2);
    th = std::remainder(th + dth, 2 * M_PI);
    odo += fmt::format("{:.1f},{},{}\n", t, ds, dth);
    truth += fmt::format("{:.1f},{:.9f},{:.9f},{:.9f}\n", t, x, y, th);
    const auto& l = lm[static_cast<std::size_t>(k % 4)];
    const double r = std::hypot(l[1] - x, l[2] - y);
    const double b = std::remainder(std::atan2(l[2] - y, l[1] - x) - th, 2 * M_PI);
    obs += fmt::format("{:.1f},{},{:.9f},{:.9f}\n", t + 0.05, k % 2 ? fmt::format("{}", l[0]) : std::string("unknown"),
                       r, b);
  }
  write(d / "map.csv", map);
  write(d / "odometry.csv", odo);
  write(d / "landmarks.csv", obs);
  write(d / "truth.csv", truth);
}

}  // namespace

TEST(Import, TimeUnitAndBaseDetection) {
  using import::TimeUnit;
  EXPECT_EQ(import::detectTimeUnit({0.0, 0.01, 0.02, 0.03}), TimeUnit::Seconds);           // relative s, 100 Hz
  EXPECT_EQ(import::detectTimeUnit({1.7e9, 1.7e9 + 0.1, 1.7e9 + 0.2}), TimeUnit::Seconds);  // epoch s
  EXPECT_EQ(import::detectTimeUnit({0, 10000, 20000, 30000}), TimeUnit::Microseconds);     // relative us, 100 Hz
  EXPECT_EQ(import::detectTimeUnit({1.7e15, 1.7e15 + 1e5}), TimeUnit::Microseconds);        // epoch us
  EXPECT_EQ(import::detectTimeUnit({5000.0, 5000.05, 5000.1}), TimeUnit::Seconds);          // a lab clock in s
  EXPECT_EQ(import::detectTimeBase(1'700'000'000'000'000LL), import::TimeBase::Absolute);
  EXPECT_EQ(import::detectTimeBase(5'000'000'000LL), import::TimeBase::Relative);
  // One wrong time does not decide the unit (the largest |t| used to).
  EXPECT_EQ(import::detectTimeUnit({1000.0, 1000.05, 1e12, 1000.15, 1000.2}), TimeUnit::Seconds);
  EXPECT_EQ(import::detectTimeUnit({1.7e15, 1.7e15 + 1e5, 3.0, 1.7e15 + 3e5}), TimeUnit::Microseconds);
}

TEST(Import, TheTimeOrderRuleRefusesAnOutlierAloneAndKeepsTheEarlierOfTwoSwappedRows) {
  using V = import::TimeVerdict;
  auto kinds = [](const std::vector<std::optional<int64_t>>& t, bool strict) {
    std::string k;
    for (const auto& v : import::checkTimeOrder(t, strict))
      k += v.kind == V::Kept ? 'k' : v.kind == V::Backwards ? 'b' : 'a';
    return k;
  };
  const std::optional<int64_t> none;
  EXPECT_EQ(kinds({10, 20, 30, 40}, true), "kkkk");
  EXPECT_EQ(kinds({10, 20, 1000000, 30, 40}, true), "kkakk");    // far ahead: refused alone
  EXPECT_EQ(kinds({1000000, 10, 20, 30}, true), "akkk");         // also as the first row
  EXPECT_EQ(kinds({10, 20, 1, 30, 40}, true), "kkbkk");          // far back
  EXPECT_EQ(kinds({10, 20, 900, 901, 30, 40, 50}, true), "kkaakkk");  // two in a row
  EXPECT_EQ(kinds({10, 25, 20, 60}, true), "kkbk");              // swapped: the later is refused
  EXPECT_EQ(kinds({10, 10, 20}, true), "kbk");                   // repeated
  EXPECT_EQ(kinds({10, 10, 20}, false), "kkk");                  // landmarks, beacons: allowed
  EXPECT_EQ(kinds({10, none, 900, none, 30, 40}, true), "kkakkk");  // rows without a time take no part
  EXPECT_EQ(kinds({10, 20, 900, 30}, true), "kkkb");  // nothing after them to tell: the earlier is kept
  EXPECT_EQ(kinds({}, true), "");
  const std::vector<std::optional<int64_t>> t{10, 20, 1000000, 30, 40};
  const auto v = import::checkTimeOrder(t, true);
  EXPECT_EQ(v[2].prev, 1u);
  EXPECT_EQ(v[2].next, 3u);
  const auto why = import::timeOrderReason(t, 2, v[2], true, [&](std::size_t i) { return std::to_string(*t[i]); });
  EXPECT_NE(why.find("time 1000000 out of line: after the previous row's 20 but not before the next row's 30"),
            std::string::npos) << why;
}

TEST(Import, OneWrongTimeIsRefusedAloneAndTheRestImported) {
  // The audit: one odometry time of a 20 Hz file in seconds set to 1e12 made the whole file
  // microseconds and refused every row after it.
  const auto d = tempDir("outlier");
  std::string odo = "time,delta_s,delta_theta\n", truth = "time,x,y,heading\n";
  for (int k = 0; k < 200; ++k) {
    odo += fmt::format("{},0.02,0.0\n", k == 100 ? std::string("1e12") : fmt::format("{:.3f}", 1000.0 + 0.05 * k));
    truth += fmt::format("{},{},0,0\n", k == 50 ? std::string("5") : fmt::format("{:.3f}", 1000.0 + 0.05 * k), 0.02 * k);
  }
  write(d / "odometry.csv", odo);
  write(d / "truth.csv", truth);
  write(d / "late.csv", "time,x,y\n1000.0,0,0\n1e300,1,1\n1000.5,2,2\n1001.0,2,2\n1001.5,2,2\n");  // beyond the clock
  import::ImportOptions o;
  o.dir = d.string();
  o.start_at_zero = true;  // from the earliest kept time, not the wrong 5 s
  const auto r = import::importDirectory(o);
  ASSERT_EQ(r.refusals.size(), 3u) << r.refusals.back().reason;
  EXPECT_TRUE(refused(r, "odometry.csv", 102, "time 1e12 out of line: after the previous row's 1004.950 but not "
                                              "before the next row's 1005.050"));
  EXPECT_TRUE(refused(r, "truth.csv", 52, "time 5 not after the previous row's 1002.450 (time going backwards"));
  EXPECT_TRUE(refused(r, "late.csv", 3, "time 1e300 seconds out of range"));
  EXPECT_EQ(file(r, "odometry.csv")->unit, import::TimeUnit::Seconds);
  EXPECT_EQ(file(r, "odometry.csv")->base, import::TimeBase::Relative);
  EXPECT_EQ(file(r, "odometry.csv")->written, 199);
  EXPECT_EQ(file(r, "truth.csv")->written, 199);
  EXPECT_EQ(r.first_utime, 0);
  EXPECT_EQ(r.last_utime, 9950000);
}

TEST(Import, OverlappingFilesOfOneStreamAreRefusedLandmarksMayComeFromSeveral) {
  const auto d = tempDir("twice");
  writeCircleRun(d, 20);
  fs::copy_file(d / "odometry.csv", d / "odometry2.csv");  // the audit: merged into twice the motion
  import::ImportOptions o;
  o.dir = d.string();
  try {
    import::importDirectory(o);
    FAIL() << "two odometry files merged";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("two odometry files overlap in time"), std::string::npos) << what;
    EXPECT_NE(what.find((d / "odometry.csv").string()), std::string::npos) << what;
    EXPECT_NE(what.find((d / "odometry2.csv").string()), std::string::npos) << what;
  }
  fs::remove(d / "odometry2.csv");
  fs::copy_file(d / "truth.csv", d / "truth2.csv");
  EXPECT_THROW(import::importDirectory(o), std::runtime_error);
  fs::remove(d / "truth2.csv");
  // Pieces of one stream one after the other are joined, numbered in time order (this file's
  // name sorts before odometry.csv, its times after).
  write(d / "a_later_odometry.csv", "time,delta_s,delta_theta\n200.0,0.05,0\n200.1,0.05,0\n");
  // Measurements of several sensors at once (two cameras, two receivers): all imported, numbered
  // in time order on the channel.
  write(d / "landmarks_rear.csv", "time,landmark_id,range,bearing\n100.02,1,4.0,0.1\n100.52,unknown,4.0,0.1\n");
  write(d / "gps_a.csv", "time,x,y\n100.5,2.1,0.3\n101.5,2.1,0.3\n");
  write(d / "gps_b.csv", "time,latitude,longitude\n101.0,-33.883,151.195\n");
  o.out_dir = (d / "out").string();
  const auto r = import::importDirectory(o);
  EXPECT_TRUE(r.refusals.empty());
  EXPECT_EQ(file(r, "landmarks_rear.csv")->written, 2);
  std::map<std::string, std::vector<std::pair<int64_t, int64_t>>> seq;  // (utime, seq) per channel, in log order
  logio::scanLog(r.log_path, [&](const logio::RawEvent& e) {
    lcmloc::landmark_obs_t l;
    lcmloc::odometry_t m;
    lcmloc::gps_fix_t g;
    if (*e.channel == "LANDMARKS" && l.decode(e.data, 0, e.size) == e.size) seq[*e.channel].emplace_back(l.utime, l.seq);
    if (*e.channel == "ODOMETRY" && m.decode(e.data, 0, e.size) == e.size) seq[*e.channel].emplace_back(m.utime, m.seq);
    if (*e.channel == "GPS" && g.decode(e.data, 0, e.size) == e.size) seq[*e.channel].emplace_back(g.utime, g.seq);
  });
  ASSERT_EQ(seq["LANDMARKS"].size(), 22u);
  ASSERT_EQ(seq["ODOMETRY"].size(), 22u);
  ASSERT_EQ(seq["GPS"].size(), 3u);
  for (const auto& [ch, s] : seq)
    for (std::size_t i = 0; i < s.size(); ++i) EXPECT_EQ(s[i].second, static_cast<int64_t>(i)) << ch << ": no gap, no jump";
  EXPECT_EQ(seq["LANDMARKS"][0].first, 100020000);
  EXPECT_EQ(seq["ODOMETRY"][20].first, 200000000);
}

TEST(Import, OptionsBoundForTheConfigAreRefusedWithTheFlagAndNothingIsWritten) {
  const auto d = tempDir("options");
  writeCircleRun(d, 20);
  write(d / "odo_steer.csv", "time,speed,steering\n300.0,2.0,0.1\n300.5,2.0,0.1\n");
  fs::remove(d / "odometry.csv");
  import::ImportOptions o;
  o.dir = d.string();
  o.out_dir = (d / "out").string();
  auto refusedWith = [&](const std::string& flag) {
    try {
      import::importDirectory(o);
      ADD_FAILURE() << flag << ": accepted";
    } catch (const app::ConfigError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(flag + ":", 0), 0u) << e.what();
    }
    EXPECT_FALSE(fs::exists(d / "out")) << flag;
  };
  o.wheelbase = NAN;  // used to say "needs --wheelbase"
  refusedWith("--wheelbase");
  o.wheelbase = 50.0;  // beyond what config.yaml accepts
  refusedWith("--wheelbase");
  o.wheelbase = 2.0;
  o.initial_pose = core::Vec3(NAN, 0, 0);  // used to write initial_pose: [nan, ...]
  refusedWith("--initial-pose");
  o.initial_pose = core::Vec3(0, 0, 7.0);
  refusedWith("--initial-pose");
  o.initial_pose.reset();
  o.filter = "kalman";
  refusedWith("--filter");
  o.filter.clear();
  // The output directory is the input directory: map.csv would be overwritten.
  o.out_dir = d.string();
  const std::string map_before = [&] { std::ifstream in(d / "map.csv"); return std::string(std::istreambuf_iterator<char>(in), {}); }();
  refusedWith("--output");
  std::ifstream in(d / "map.csv");
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), map_before);
  EXPECT_FALSE(fs::exists(d / "run.lcmlog"));
  o.out_dir = (d / "out").string();
  EXPECT_TRUE(import::importDirectory(o).usable());
}

TEST(Import, GoodFilesOfEveryKindBecomeALogMapAndConfig) {
  const auto d = tempDir("good");
  writeCircleRun(d, 20);
  write(d / "gps_local.csv", "time,x,y,position_std\n100.5,2.1,0.3,0.5\n101.5,1.9,0.9,0.5\n");
  write(d / "gps_geo.csv", "time_s,latitude,longitude\n100.7,-33.883,151.195\n");
  write(d / "beacons.csv", "time_us,beacon_id,range\n100100000,1,3.0\n100200000,2,4.5\n");
  write(d / "odo_speed.csv", "time,speed,yaw_rate\n200.0,1.0,0.1\n200.5,1.0,0.1\n201.0,1.0,0.0\n");
  write(d / "odo_steer.csv", "time,speed,steering\n300.0,2.0,0.1\n300.5,2.0,0.1\n");
  write(d / "notes.txt", "what,ever\n1,2\n");  // not a *.csv file: not read
  import::ImportOptions o;
  o.dir = d.string();
  o.out_dir = (d / "out").string();
  o.wheelbase = 2.0;
  const auto r = import::importDirectory(o);
  EXPECT_TRUE(r.refusals.empty()) << r.refusals.front().file << ":" << r.refusals.front().line << " "
                                  << r.refusals.front().reason;
  EXPECT_EQ(r.map_size, 4);
  EXPECT_TRUE(r.skipped.empty());
  ASSERT_TRUE(file(r, "odometry.csv"));
  EXPECT_EQ(file(r, "odometry.csv")->kind, "odometry");
  EXPECT_EQ(file(r, "odometry.csv")->written, 20);
  EXPECT_EQ(file(r, "odometry.csv")->unit, import::TimeUnit::Seconds);
  EXPECT_EQ(file(r, "odometry.csv")->base, import::TimeBase::Relative);
  EXPECT_EQ(file(r, "landmarks.csv")->written, 20);
  EXPECT_EQ(file(r, "truth.csv")->kind, "ground_truth");
  EXPECT_EQ(file(r, "beacons.csv")->unit, import::TimeUnit::Microseconds);  // time_us header
  EXPECT_EQ(file(r, "beacons.csv")->first_utime, 100100000);
  EXPECT_EQ(file(r, "gps_local.csv")->written, 2);
  EXPECT_EQ(file(r, "gps_geo.csv")->written, 1);
  EXPECT_EQ(r.first_utime, 100000000);
  EXPECT_EQ(r.last_utime, 301000000 - 500000);
  EXPECT_EQ(r.filter, "ukf_landmarks");
  const auto n = channelCounts(r.log_path);
  EXPECT_EQ(n.at("ODOMETRY"), 20 + 3 + 2);
  EXPECT_EQ(n.at("LANDMARKS"), 20);
  EXPECT_EQ(n.at("BEACONS"), 2);
  EXPECT_EQ(n.at("GPS"), 3);
  EXPECT_EQ(n.at("GROUND_TRUTH"), 21);
  // speed,yaw_rate: the row's speed and rate hold until the next row (0.5 m, 0.05 rad)
  std::vector<lcmloc::odometry_t> odo;
  logio::scanLog(r.log_path, [&](const logio::RawEvent& e) {
    lcmloc::odometry_t m;
    if (*e.channel == "ODOMETRY" && m.decode(e.data, 0, e.size) == e.size && m.utime >= 200000000) odo.push_back(m);
  });
  ASSERT_EQ(odo.size(), 5u);
  EXPECT_DOUBLE_EQ(odo[0].delta_s, 0.0);
  EXPECT_NEAR(odo[1].delta_s, 0.5, 1e-12);
  EXPECT_NEAR(odo[1].delta_theta, 0.05, 1e-12);
  EXPECT_TRUE(odo[4].has_steering);
  EXPECT_NEAR(odo[4].delta_theta, 1.0 * std::tan(0.1) / 2.0, 1e-12);
  // local GPS x,y go out as lat/lon about the datum and come back as x,y in the fusion
  const bus::LocalFrame frame(o.datum);
  std::vector<core::GpsInput> fixes;
  logio::scanLog(r.log_path, [&](const logio::RawEvent& e) {
    lcmloc::gps_fix_t m;
    if (*e.channel == "GPS" && m.decode(e.data, 0, e.size) == e.size)
      if (auto in = bus::toCore(m, "GPS", frame)) fixes.push_back(*in);
  });
  ASSERT_EQ(fixes.size(), 3u);
  EXPECT_NEAR(fixes[0].x, 2.1, 1e-6);
  EXPECT_NEAR(fixes[0].y, 0.3, 1e-6);
  EXPECT_DOUBLE_EQ(fixes[0].position_std, 0.5);
  const auto cfg = app::loadSystemConfig(r.config_path);
  EXPECT_EQ(cfg.fusion.filter.type, "ukf_landmarks");
  EXPECT_EQ(app::csv::loadMap(cfg.fusion.map_file).size(), 4u);
  EXPECT_NEAR(cfg.fusion.filter.initial_pose[0], 2.0, 1e-9);  // first ground-truth row
}

TEST(Import, BadRowsAreRefusedWithFileLineAndReason) {
  const auto d = tempDir("bad");
  write(d / "map.csv", "id,x,y\n1,5,0\n2,0,5\n");
  write(d / "odometry.csv",
        "time,delta_s,delta_theta\n"
        "1.0,0.1,0.0\n"      // 2 ok
        "1.1,0.1\n"          // 3 wrong column count
        "1.2,abc,0.0\n"      // 4 non-numeric
        "1.3,nan,0.0\n"      // 5 NaN
        "0.95,0.1,0.0\n"     // 6 time backwards (before line 2, the last accepted row)
        "1.4,0.1,0.0\n"      // 7 ok
        "1.5,0x10,0.0\n");   // 8 C hexadecimal (strtod reads 16)
  write(d / "landmarks.csv",
        "time,landmark_id,range,bearing\n"
        "1.0,1,5.0,0.1\n"    // 2 ok
        "1.1,7,5.0,0.1\n"    // 3 not in the map
        "1.2,unknown,4.0,0.2\n"  // 4 ok
        "1.2,two,4.0,0.2\n"  // 5 not an id
        "1.1,2,4.0,0.2\n"    // 6 backwards
        "1.3,2,4.0,45\n");   // 7 bearing in degrees
  write(d / "beacons.csv", "time,beacon_id,range\n1.0,3,2.0\n1.1,1,-1\n1.2,1,2.0\n");
  write(d / "truth.csv", "time,x,y,heading\n1.0,0,0,0\n1.0,0,0,0\n");
  import::ImportOptions o;
  o.dir = d.string();
  const auto r = import::importDirectory(o);
  EXPECT_TRUE(refused(r, "odometry.csv", 3, "expected 3 columns, got 2"));
  EXPECT_TRUE(refused(r, "odometry.csv", 4, "not a number: 'abc'"));
  EXPECT_TRUE(refused(r, "odometry.csv", 5, "not finite: 'nan'"));
  EXPECT_TRUE(refused(r, "odometry.csv", 6, "time going backwards"));
  EXPECT_TRUE(refused(r, "odometry.csv", 8, "not a number: '0x10'"));
  EXPECT_TRUE(refused(r, "landmarks.csv", 3, "landmark id 7 not in the map"));
  EXPECT_TRUE(refused(r, "landmarks.csv", 5, "not a number: 'two'"));
  EXPECT_TRUE(refused(r, "landmarks.csv", 6, "before the previous row"));
  EXPECT_TRUE(refused(r, "landmarks.csv", 7, "radians expected"));
  EXPECT_TRUE(refused(r, "beacons.csv", 2, "beacon id 3 not in the map"));
  EXPECT_TRUE(refused(r, "beacons.csv", 3, "negative range"));
  EXPECT_TRUE(refused(r, "truth.csv", 3, "not after"));
  EXPECT_EQ(r.refusals.size(), 12u);
  EXPECT_EQ(file(r, "odometry.csv")->rows, 7);
  EXPECT_EQ(file(r, "odometry.csv")->refused, 5);
  EXPECT_EQ(file(r, "odometry.csv")->written, 2);
  EXPECT_EQ(file(r, "landmarks.csv")->written, 2);
  EXPECT_EQ(r.messages, 2 + 2 + 1 + 1);
  EXPECT_TRUE(r.usable());
}

TEST(Import, TheSummaryListsAtMostShowRefusedRowsAndTheOptionRefusesANegativeCount) {
  const auto d = tempDir("show_refused");
  write(d / "odometry.csv", "time,delta_s,delta_theta\n1.0,0.1,0\n1.1,x,0\n1.2,y,0\n1.3,z,0\n1.4,0.1,0\n");
  import::ImportOptions o;
  o.dir = d.string();
  const auto r = import::importDirectory(o);
  ASSERT_EQ(r.refusals.size(), 3u);
  auto count = [](const std::string& text, const std::string& what) {
    std::size_t n = 0;
    for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
  };
  std::string s = import::importSummary(r, 2);
  EXPECT_EQ(count(s, "\nrefused "), 2u) << s;
  EXPECT_NE(s.find("... and 1 more refused rows"), std::string::npos) << s;
  s = import::importSummary(r, 3);
  EXPECT_EQ(count(s, "\nrefused "), 3u) << s;
  EXPECT_EQ(s.find("more refused rows"), std::string::npos) << s;
  for (int max : {0, -1, std::numeric_limits<int>::min()}) {  // -1 used to wrap: "... and 4 more"
    s = import::importSummary(r, max);
    EXPECT_EQ(count(s, "\nrefused "), 0u) << max << "\n" << s;
    EXPECT_NE(s.find("... and 3 more refused rows"), std::string::npos) << max << "\n" << s;
  }
  // The command line refuses a negative count (exit 2, the option named); 0 lists none.
  auto run = [&](const std::string& n) { return runCommand(LCMLOC_IMPORT_BIN, d.string() + " --show-refused " + n, d); };
  auto [code, text] = run("-1");
  EXPECT_EQ(code, 2) << text;
  EXPECT_NE(text.find("--show-refused"), std::string::npos) << text;
  std::tie(code, text) = run("0");
  EXPECT_EQ(code, 3) << text;  // rows refused, the rest imported: damaged input
  EXPECT_NE(text.find("... and 3 more refused rows"), std::string::npos) << text;
  fs::remove_all(d);
}

TEST(Import, NothingUsableMixedClocksAndBadMapAreErrors) {
  const auto d = tempDir("none");
  write(d / "odometry.csv", "time,delta_s,delta_theta\nx,1,2\n");
  import::ImportOptions o;
  o.dir = d.string();
  EXPECT_FALSE(import::importDirectory(o).usable());
  write(d / "truth.csv", "time,x,y,heading\n1700000000.0,0,0,0\n");
  write(d / "gps.csv", "time,x,y\n10.0,0,0\n");
  EXPECT_THROW(import::importDirectory(o), std::runtime_error);  // absolute and relative
  o.base = import::TimeBase::Relative;                           // forced: one clock
  EXPECT_TRUE(import::importDirectory(o).usable());
  write(d / "map.csv", "id,x,y\n1,0,0\n1,2,2\n");
  EXPECT_THROW(import::importDirectory(o), std::runtime_error);  // duplicate id
  o.dir = (d / "missing").string();
  EXPECT_THROW(import::importDirectory(o), std::runtime_error);
  const auto e = tempDir("steer");
  write(e / "odo.csv", "time,speed,steering\n1,2,0.1\n2,2,0.1\n");
  o.dir = e.string();
  o.base = import::TimeBase::Auto;
  EXPECT_THROW(import::importDirectory(o), std::runtime_error);  // speed,steering without --wheelbase
}

TEST(Import, AByteOrderMarkIsSkippedAndADirectoryIsListedAsSkipped) {
  const auto d = tempDir("bom");
  // Spreadsheet programs start a UTF-8 CSV with a byte-order mark (EF BB BF): the header was
  // "none of the formats" and the file skipped.
  write(d / "odometry.csv", "\xEF\xBB\xBFtime,delta_s,delta_theta\r\n1.0,0.1,0\r\n2.0,0.1,0\r\n");
  write(d / "gps.csv", "\xEF\xBB\xBFtime,x,y\n1.5,2.0,3.0\n");
  // A directory named like a CSV file: listed as skipped with the reason (it was left out unsaid).
  fs::create_directory(d / "map.csv");
  import::ImportOptions o;
  o.dir = d.string();
  const auto r = import::importDirectory(o);
  ASSERT_NE(file(r, "odometry.csv"), nullptr);
  EXPECT_EQ(file(r, "odometry.csv")->header, "time,delta_s,delta_theta");
  EXPECT_EQ(file(r, "odometry.csv")->written, 2);
  ASSERT_NE(file(r, "gps.csv"), nullptr);
  EXPECT_EQ(file(r, "gps.csv")->written, 1);
  EXPECT_TRUE(r.refusals.empty());
  ASSERT_EQ(r.skipped.size(), 1u);
  EXPECT_EQ(r.skipped[0], "'" + (d / "map.csv").string() + "': is a directory");
  // The map file too (it was skipped, and the run imported without its map).
  fs::remove(d / "map.csv");
  write(d / "map.csv", "\xEF\xBB\xBFid,x,y\r\n1,2.0,3.0\r\n");
  EXPECT_EQ(import::importDirectory(o).map_size, 1);
  fs::remove_all(d);
}

TEST(Import, MicrosecondsAreDetectedAndStartAtZeroShifts) {
  const auto d = tempDir("us");
  write(d / "odometry.csv", "time,delta_s,delta_theta\n1700000000000000,0.1,0\n1700000000100000,0.1,0\n");
  import::ImportOptions o;
  o.dir = d.string();
  auto r = import::importDirectory(o);
  EXPECT_EQ(r.files.at(0).unit, import::TimeUnit::Microseconds);
  EXPECT_EQ(r.files.at(0).base, import::TimeBase::Absolute);
  EXPECT_EQ(r.first_utime, 1700000000000000);
  o.start_at_zero = true;
  r = import::importDirectory(o);
  EXPECT_EQ(r.first_utime, 0);
  EXPECT_EQ(r.last_utime, 100000);
  o.start_at_zero = false;
  o.unit = import::TimeUnit::Seconds;  // forced: 1.7e15 s would be nonsense but is what was asked
  r = import::importDirectory(o);
  EXPECT_EQ(r.files.at(0).unit, import::TimeUnit::Seconds);
}

TEST(Import, ImportedLandmarkRunReplaysToTheTruth) {
  const auto d = tempDir("replay");
  writeCircleRun(d, 200);
  import::ImportOptions o;
  o.dir = d.string();
  o.out_dir = (d / "out").string();
  o.initial_pose = core::Vec3(2.2, -0.2, M_PI / 2 + 0.05);  // off the truth
  const auto r = import::importDirectory(o);
  ASSERT_TRUE(r.usable());
  auto cfg = app::loadSystemConfig(r.config_path);
  cfg.fusion.filter.p0_diag = core::Vec3(0.1, 0.1, 0.01);
  replay::ReplayOptions ro;
  ro.input = r.log_path;
  ro.output = (d / "out" / "est.lcmlog").string();
  replay::replayLog(cfg, ro);
  lcmloc::pose_t last;
  logio::scanLog(ro.output, [&](const logio::RawEvent& e) {
    if (*e.channel == "POSE") last.decode(e.data, 0, e.size);
  });
  // truth after 200 steps of 0.05 m on the 2 m circle
  const double a = 200 * 0.05 / 2.0;
  EXPECT_LT(std::hypot(last.state[0] - 2 * std::cos(a), last.state[1] - 2 * std::sin(a)), 0.02);
}

// The ECN magnet-grid runs are in the shared data directory (CMake LCMLOC_SHARED_DIR), outside
// the repository: without them the tests below are skipped, saying where they looked.
#define SKIP_WITHOUT_MAGNET_GRID_RUN(file)                                                              \
  if (!fs::exists(std::string(LCMLOC_MAGNET_GRID_DIR) + "/" + (file)))                                  \
  GTEST_SKIP() << "magnet-grid run " << (file) << " not found in " << LCMLOC_MAGNET_GRID_DIR            \
               << " (CMake LCMLOC_SHARED_DIR)"

TEST(MagnetGrid, SmallRunImportsAndTheGatedFilterAcceptsTheMagnetPasses) {
  SKIP_WITHOUT_MAGNET_GRID_RUN("line2magnets.txt");
  const std::string data = LCMLOC_MAGNET_GRID_DIR;
  const auto d = tempDir("magnet");
  import::MagnetGridOptions mo;
  mo.input = data + "/line2magnets.txt";
  mo.out_dir = (d / "line2magnets").string();
  mo.name = "line2magnets";
  import::MagnetGridImport imp;
  const auto rep = import::runMagnetGrid(mo, &imp);
  EXPECT_EQ(imp.rows, 197);
  EXPECT_EQ(imp.refused, 0);
  EXPECT_EQ(imp.odometry, 197);
  // about 0.55 m straight over two rows of magnets 55 mm apart: ~10 passes per row
  EXPECT_NEAR(imp.distance_m, 0.55, 0.03);
  EXPECT_GE(rep.detections, 18);
  EXPECT_LE(rep.detections, 22);
  EXPECT_GE(rep.accepted, rep.detections - 1);
  EXPECT_GE(rep.distinct_magnets, 18);  // every pass its own magnet: no double association
  EXPECT_GT(rep.nis_mean, 0.05);
  EXPECT_LT(rep.nis_mean, 2.0);
  EXPECT_GE(rep.within_gate, 0.95);
  // the reed row's position is known far better than half the magnet spacing before each pass
  EXPECT_GT(rep.max_prior_sigma, 0.0);
  EXPECT_LT(rep.max_prior_sigma, 0.0275 / 2);
  EXPECT_TRUE(fs::exists(d / "line2magnets" / "report.json"));
  // the lateral offsets: two rows of magnets about 55 mm apart, symmetric about the axis
  double lo = 1, hi = -1;
  for (const auto& m : imp.detections) {
    lo = std::min(lo, m.lateral);
    hi = std::max(hi, m.lateral);
  }
  EXPECT_NEAR(hi - lo, 0.06, 0.011);
}

TEST(MagnetGrid, OneWrongTimeIsRefusedAloneAndBadFlagsAreNamed) {
  SKIP_WITHOUT_MAGNET_GRID_RUN("line2magnets.txt");
  const auto d = tempDir("magnet_outlier");
  std::ifstream in(std::string(LCMLOC_MAGNET_GRID_DIR) + "/line2magnets.txt");
  std::string text, line;
  for (int n = 1; std::getline(in, line); ++n) {
    if (n == 50) {  // the time column (4th) set to 1e12 s; it used to refuse the 148 rows after it
      std::istringstream ss(line);
      std::string a, b, c, t;
      ss >> a >> b >> c >> t;
      line = a + " " + b + " " + c + " 1e12";
    }
    text += line + "\n";
  }
  write(d / "run.txt", text);
  import::MagnetGridOptions mo;
  mo.input = (d / "run.txt").string();
  auto imp = import::importMagnetGrid(mo);
  EXPECT_EQ(imp.rows, 197);
  ASSERT_EQ(imp.refused, 1);
  EXPECT_EQ(imp.refusals[0].first, 50);
  EXPECT_NE(imp.refusals[0].second.find("time 1000000000000 s out of line"), std::string::npos)
      << imp.refusals[0].second;
  EXPECT_EQ(imp.odometry, 196);
  // Values bound for config.yaml and map.csv: refused with the flag's name, nothing written.
  mo.out_dir = (d / "out").string();
  auto refusedWith = [&](const import::MagnetGridOptions& bad, const std::string& flag) {
    try {
      import::importMagnetGrid(bad);
      ADD_FAILURE() << flag << ": accepted";
    } catch (const app::ConfigError& e) {
      EXPECT_EQ(std::string(e.what()).rfind(flag + ":", 0), 0u) << e.what();
    }
    EXPECT_FALSE(fs::exists(d / "out")) << flag;
  };
  auto bad = mo;
  bad.pv_diag = core::Vec2(-1e-5, 1e-3);
  refusedWith(bad, "--pv-diag");
  bad = mo;
  bad.pw_diag = core::Vec3(1e-5, -1.0, 1e-3);
  refusedWith(bad, "--pw-diag");
  bad = mo;
  bad.pw_turn = -1;
  refusedWith(bad, "--pw-turn");
  bad = mo;
  bad.grid_angle = NAN;  // used to write a map of NaN
  refusedWith(bad, "--grid-angle");
  bad = mo;
  bad.pv_diag = core::Vec2(NAN, 0);
  refusedWith(bad, "--pv-diag");
  // The run file as the output's map.csv: refused, the run kept.
  bad = mo;
  bad.out_dir = d.string();
  fs::copy_file(d / "run.txt", d / "map.csv");
  bad.input = (d / "map.csv").string();
  EXPECT_THROW(import::importMagnetGrid(bad), app::ConfigError);
  EXPECT_EQ(fs::file_size(d / "map.csv"), fs::file_size(d / "run.txt"));
  EXPECT_EQ(import::importMagnetGrid(mo).odometry, 196);
}

TEST(MagnetGrid, TwoRunsOfOneNameAreRefusedBeforeAnythingIsWritten) {
  SKIP_WITHOUT_MAGNET_GRID_RUN("line2magnets.txt");
  // --run line2magnets and --run DIR/line2magnets.txt both wrote OUT/line2magnets, the second over
  // the first, and summary.json kept the second only (exit 0).
  const auto d = tempDir("magnet_same_name");
  fs::copy_file(std::string(LCMLOC_MAGNET_GRID_DIR) + "/line2magnets.txt", d / "line2magnets.txt");
  auto run = [&](const std::string& args) {
    return runCommand(LCMLOC_MAGNET_GRID_BIN, "--data " + d.string() + " " + args, d);
  };
  const std::string other = (d / "line2magnets.txt").string();
  for (const std::string flags : {"", "--import-only "}) {
    auto [code, text] = run(flags + "--run line2magnets --run " + other + " -o " + (d / "out").string());
    EXPECT_EQ(code, 2) << text;
    EXPECT_NE(text.find("--run: 'line2magnets' and '" + other + "' are both run 'line2magnets'"), std::string::npos)
        << text;
    EXPECT_FALSE(fs::exists(d / "out")) << flags;
  }
  auto [code, text] = run("--import-only --run line2magnets -o " + (d / "out").string());
  EXPECT_EQ(code, 0) << text;
  EXPECT_TRUE(fs::exists(d / "out" / "line2magnets" / "run.lcmlog"));
  fs::remove_all(d);
}

TEST(MagnetGrid, TheReedBitOrderIsTheOneTheLoopDataSupports) {
  SKIP_WITHOUT_MAGNET_GRID_RUN("oneloop.txt");
  const std::string data = LCMLOC_MAGNET_GRID_DIR;
  const auto d = tempDir("bits");
  import::MagnetGridOptions mo;
  mo.input = data + "/oneloop.txt";
  mo.name = "oneloop";
  mo.out_dir = (d / "right").string();
  const auto right = import::runMagnetGrid(mo);
  mo.bit0 = "left";
  mo.out_dir = (d / "left").string();
  const auto left = import::runMagnetGrid(mo);
  EXPECT_GE(right.accepted, right.detections - 2);
  EXPECT_GT(right.accepted, left.accepted + 5);
  EXPECT_GT(right.nis_mean, 1.0);  // the noise model is neither far too wide ...
  EXPECT_LT(right.nis_mean, 3.0);  // ... nor far too narrow (dof 2)
}

TEST(Import, ConfigKeysForLandmarksAndTheMapFile) {
  const auto cfg = app::parseSystemConfig(
      "fusion:\n  map_file: map.csv\n  filter:\n    type: ukf_landmarks\n    pw_turn: 0.01\n"
      "    landmarks: {range_std: 0.2, bearing_std: 0.03, beacon_std: 0.3}\n"
      "channels: {landmarks: CAM, beacons: UWB}\n",
      "/some/dir/run.yaml");
  EXPECT_EQ(cfg.fusion.map_file, "/some/dir/map.csv");  // relative to the config file
  EXPECT_EQ(cfg.fusion.filter.pw_turn, 0.01);
  EXPECT_EQ(cfg.fusion.filter.landmarks.bearing_std, 0.03);
  EXPECT_EQ(cfg.fusion.filter.landmarks.beacon_std, 0.3);
  EXPECT_EQ(cfg.channels.landmarks, "CAM");
  EXPECT_EQ(cfg.channels.beacons, "UWB");
  try {
    app::parseSystemConfig("fusion:\n  filter:\n    landmarks: {range_sd: 0.2}\n", "x.yaml");
    FAIL() << "unknown key accepted";
  } catch (const app::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("fusion.filter.landmarks.range_sd"), std::string::npos) << e.what();
  }
}

TEST(Import, CommandExitsNonzeroWhenNothingIsUsable) {
  const auto d = tempDir("cli");
  write(d / "odometry.csv", "time,delta_s,delta_theta\nx,1,2\n");
  const std::string bin = LCMLOC_IMPORT_BIN;
  const std::string log = (d / "cli.log").string();
  EXPECT_NE(std::system((bin + " " + d.string() + " -o " + (d / "out").string() + " > " + log + " 2>&1").c_str()), 0);
  std::ifstream in(log);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("odometry.csv:2: column 1: not a number: 'x'"), std::string::npos) << text;
  write(d / "odometry.csv", "time,delta_s,delta_theta\n1,0.1,0\n2,0.1,0\n");
  EXPECT_EQ(std::system((bin + " " + d.string() + " -o " + (d / "out").string() + " > " + log + " 2>&1").c_str()), 0);
  EXPECT_TRUE(fs::exists(d / "out" / "run.lcmlog"));
  EXPECT_TRUE(fs::exists(d / "out" / "config.yaml"));
}

// lcmloc-import's command as a library (its main is the command line): the options parsed into
// an ImportCommand and run in-process write the log on the config's channel names, the map and a
// config with the given initial pose; an existing output is refused without --overwrite and left
// as it was; nothing usable is exit 1.
TEST(Import, TheCommandRunsInProcessAndRefusesAnExistingOutputWithoutOverwrite) {
  const auto d = tempDir("command");
  writeCircleRun(d, 20);
  const std::string out = (d / "out").string();
  import::ImportCommand c;
  CLI::App app;
  import::addImportOptions(app, c);
  app.parse(d.string() + " -o " + out + " --initial-pose 1 2 0.5 --show-refused 0", false);
  app::SystemConfig cfg;
  cfg.channels.odometry = "WHEELS";
  ASSERT_EQ(import::runImport(cfg, c), app::kExitOk);
  const auto n = channelCounts(out + "/run.lcmlog");
  EXPECT_EQ(n.count("ODOMETRY"), 0u);
  EXPECT_EQ(n.at("WHEELS"), 20);
  EXPECT_EQ(n.at("LANDMARKS"), 20);
  EXPECT_EQ(n.at("GROUND_TRUTH"), 21);
  EXPECT_EQ(app::csv::loadMap(out + "/map.csv").size(), 4u);
  const auto written = app::loadSystemConfig(out + "/config.yaml");
  EXPECT_DOUBLE_EQ(written.fusion.filter.initial_pose[0], 1.0);
  EXPECT_DOUBLE_EQ(written.fusion.filter.initial_pose[1], 2.0);
  EXPECT_DOUBLE_EQ(written.fusion.filter.initial_pose[2], 0.5);

  // Again without --overwrite: refused (exit 2) before anything is read or written.
  write(d / "odometry.csv", "time,delta_s,delta_theta\n100.1,0.05,0.025\n");
  EXPECT_THROW(import::runImport(cfg, c), app::UsageError);
  EXPECT_EQ(channelCounts(out + "/run.lcmlog").at("WHEELS"), 20);
  c.overwrite = true;
  ASSERT_EQ(import::runImport(cfg, c), app::kExitOk);
  EXPECT_EQ(channelCounts(out + "/run.lcmlog").at("WHEELS"), 1);

  const auto bad = tempDir("command_bad");
  write(bad / "odometry.csv", "time,delta_s,delta_theta\nx,1,2\n");
  import::ImportCommand nothing;
  nothing.io.dir = bad.string();
  EXPECT_EQ(import::runImport(cfg, nothing), app::kExitRuntimeError);
}

TEST(Import, LandmarkAndBeaconMessagesAreValidatedOnTheWayIn) {
  lcmloc::landmark_obs_t m{};
  m.utime = 1;
  m.landmark_id = -1;
  m.range = 3.0;
  m.bearing = 0.5;
  std::string why;
  auto o = bus::toCore(m, "CAM", &why);
  ASSERT_TRUE(o);
  EXPECT_EQ(o->sensor, "CAM");
  EXPECT_EQ(o->landmark_id, -1);
  m.range = NAN;
  EXPECT_FALSE(bus::toCore(m, "CAM", &why));
  EXPECT_NE(why.find("range is NaN"), std::string::npos);
  m.range = 3.0;
  m.bearing = 4.0;
  EXPECT_FALSE(bus::toCore(m, "CAM", &why));
  m.bearing = 0.5;
  m.landmark_id = -2;
  EXPECT_FALSE(bus::toCore(m, "CAM", &why));
  lcmloc::beacon_range_t b{};
  b.utime = 1;
  b.beacon_id = 4;
  b.range = -0.1;
  EXPECT_FALSE(bus::toCore(b, "UWB", &why));
  b.range = 2.0;
  ASSERT_TRUE(bus::toCore(b, "UWB", &why));
  EXPECT_EQ(bus::toCore(b, "UWB", &why)->beacon_id, 4);
}

TEST(Import, TheDocumentedExampleDirectoryImportsAndScores) {
  // docs/examples/csv_square: a square driven twice with turns in place, landmarks (known and
  // unknown id), beacons, ground truth; measurement noise as the config's defaults.
  const auto d = tempDir("example");
  import::ImportOptions o;
  o.dir = LCMLOC_EXAMPLE_DIR;
  o.out_dir = (d / "out").string();
  const auto r = import::importDirectory(o);
  EXPECT_TRUE(r.refusals.empty());
  EXPECT_EQ(r.map_size, 9);
  EXPECT_EQ(r.filter, "ukf_landmarks");
  const auto cfg = app::loadSystemConfig(r.config_path);
  replay::ReplayOptions ro;
  ro.input = r.log_path;
  ro.output = (d / "out" / "est.lcmlog").string();
  ro.with_inputs = true;
  replay::replayLog(cfg, ro);
  std::vector<std::array<double, 3>> truth;  // t, x, y
  std::vector<lcmloc::pose_t> poses;
  lcmloc::ground_truth_t truth_msg;
  int64_t landmarks = 0, landmarks_ok = 0, beacons = 0, beacons_ok = 0;
  double nis_landmarks = 0, nis_beacons = 0;
  logio::scanLog(ro.output, [&](const logio::RawEvent& e) {
    if (*e.channel == "GROUND_TRUTH") {
      // (decoded into a message that lives outside the lambda: LCM 1.3.1's generated decode
      // writes doubles through int64_t pointers, and a value-initialised local let the compiler
      // keep the zeros)
      if (truth_msg.decode(e.data, 0, e.size) == e.size)
        truth.push_back({static_cast<double>(truth_msg.utime), truth_msg.x, truth_msg.y});
    } else if (*e.channel == "POSE") {
      lcmloc::pose_t p;
      if (p.decode(e.data, 0, e.size) == e.size) poses.push_back(p);
    } else if (*e.channel == "GATE") {
      lcmloc::gate_decision_t g;
      if (g.decode(e.data, 0, e.size) != e.size) return;
      if (g.sensor == "LANDMARKS") { ++landmarks; landmarks_ok += g.accepted; nis_landmarks += g.mahalanobis; }
      if (g.sensor == "BEACONS") { ++beacons; beacons_ok += g.accepted; nis_beacons += g.mahalanobis; }
    }
  });
  ASSERT_GT(poses.size(), 3000u);
  double sq = 0;
  int n = 0;
  for (const auto& p : poses) {
    const double t = static_cast<double>(p.utime);
    auto it = std::lower_bound(truth.begin(), truth.end(), t,
                               [](const std::array<double, 3>& a, double v) { return a[0] < v; });
    if (it == truth.begin() || it == truth.end()) continue;
    const auto& a = *(it - 1);
    const auto& b = *it;
    const double w = (t - a[0]) / (b[0] - a[0]);
    const double ex = p.state[0] - (a[1] + w * (b[1] - a[1])), ey = p.state[1] - (a[2] + w * (b[2] - a[2]));
    sq += ex * ex + ey * ey;
    ++n;
  }
  const double rmse = std::sqrt(sq / n);
  EXPECT_LT(rmse, 0.04);  // measured 0.018 m
  EXPECT_EQ(landmarks, 1040);
  EXPECT_GE(landmarks_ok, 1020);
  EXPECT_EQ(beacons, 208);
  EXPECT_GE(beacons_ok, 200);
  // innovations as their chi-square distributions say (2 and 1 dof): measured 1.78 and 1.05
  EXPECT_NEAR(nis_landmarks / landmarks, 2.0, 0.6);
  EXPECT_NEAR(nis_beacons / beacons, 1.0, 0.4);
}

// With a ground truth, config.yaml gets the noise fitted against it: a robot on a circle seeing
// two landmarks with a range noise of 0.3 m and a bearing noise of 0.05 rad (far from the
// filter's defaults of 0.1 m and 0.02 rad) gets those back; --no-noise-fit keeps the defaults.
TEST(Import, TheConfigGetsTheNoiseFittedAgainstTheTruth) {
  const auto d = tempDir("noisefit");
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  std::string odo = "time,speed,yaw_rate\n", truth = "time,x,y,heading\n", obs = "time,landmark_id,range,bearing\n",
              gps = "time,x,y\n";
  const double lx[2] = {6.0, -6.0}, ly[2] = {0.0, 0.0};
  for (int k = 0; k <= 3000; ++k) {  // 300 s at 10 Hz, radius 3 m at 0.3 m/s
    const double t = 100.0 + 0.1 * k, th = 0.1 * 0.1 * k;
    const double x = 3.0 * std::sin(th), y = 3.0 - 3.0 * std::cos(th);
    odo += fmt::format("{:.1f},0.3,0.1\n", t);
    truth += fmt::format("{:.1f},{},{},{}\n", t, x, y, core::wrapAngle(th));
    if (k % 10 == 0) gps += fmt::format("{:.1f},{},{}\n", t, x + 1.5 * n(rng), y + 1.5 * n(rng));  // 1 Hz, 1.5 m
    if (k % 2) continue;
    for (int i = 0; i < 2; ++i)
      obs += fmt::format("{:.1f},{},{},{}\n", t, i + 1, std::hypot(lx[i] - x, ly[i] - y) + 0.3 * n(rng),
                         core::wrapAngle(std::atan2(ly[i] - y, lx[i] - x) - th + 0.05 * n(rng)));
  }
  write(d / "odometry.csv", odo);
  write(d / "truth.csv", truth);
  write(d / "landmarks.csv", obs);
  write(d / "gps.csv", gps);
  write(d / "map.csv", "id,x,y\n1,6,0\n2,-6,0\n");
  import::ImportOptions o;
  o.dir = d.string();
  o.out_dir = (d / "out").string();
  const auto r = import::importDirectory(o);
  ASSERT_FALSE(r.noise_fit.empty());
  EXPECT_NE(r.noise_fit[0].find("landmark range"), std::string::npos) << r.noise_fit[0];
  const auto cfg = app::loadSystemConfig(r.config_path);
  EXPECT_NEAR(cfg.fusion.filter.landmarks.range_std, 0.3, 0.03);
  EXPECT_NEAR(cfg.fusion.filter.landmarks.bearing_std, 0.05, 0.005);
  EXPECT_NEAR(cfg.fusion.filter.gnss.gps_std, 1.5, 0.15);
  EXPECT_NE(import::importSummary(r, 0).find("noise fit: landmark bearing"), std::string::npos);

  o.out_dir = (d / "plain").string();
  o.fit_noise = false;
  const auto plain = import::importDirectory(o);
  EXPECT_TRUE(plain.noise_fit.empty());
  const auto defaults = app::loadSystemConfig(plain.config_path);
  EXPECT_EQ(defaults.fusion.filter.landmarks.range_std, core::FilterConfig{}.landmarks.range_std);
  EXPECT_EQ(defaults.fusion.filter.pw_diag, core::FilterConfig{}.pw_diag);
  EXPECT_EQ(defaults.fusion.filter.gnss.gps_std, core::FilterConfig{}.gnss.gps_std);
}
