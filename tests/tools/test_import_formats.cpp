// lcmloc-import's formats (docs/import_formats.md): files that are none of them, unknown
// columns, beacons without an id, per-row sigma columns, ground truth of position only, IMU rows,
// bad rows through the command line, and the written config read back by the replay's loader
// and replayed by lcmloc-replay.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/beacon_range_t.hpp"
#include "lcmloc/eval/trajectory.hpp"
#include "lcmloc/gate_decision_t.hpp"
#include "lcmloc/gps_fix_t.hpp"
#include "lcmloc/ground_truth_t.hpp"
#include "lcmloc/imu_t.hpp"
#include "lcmloc/import/import.hpp"
#include "lcmloc/landmark_obs_t.hpp"
#include "lcmloc/logio/log_reader.hpp"
#include "lcmloc/odometry_t.hpp"
#include "lcmloc/pose_t.hpp"
#include "run_command.hpp"
#include "temp_files.hpp"

using namespace lcmloc;
namespace fs = std::filesystem;

namespace {

fs::path tempDir(const std::string& name) { return freshTempDir("lcmloc_test_import_formats_", name); }

void write(const fs::path& p, const std::string& text) { writeText(p, text); }

/// Every message of type T on channel ch, in log order.
template <typename T>
std::vector<T> messages(const std::string& log, const std::string& ch) {
  std::vector<T> out;
  logio::scanLog(log, [&](const logio::RawEvent& e) {
    T m;
    if (*e.channel == ch && m.decode(e.data, 0, e.size) == e.size) out.push_back(m);
  });
  return out;
}

bool refused(const import::ImportResult& r, const std::string& name, int64_t line, const std::string& what) {
  for (const auto& f : r.refusals)
    if (fs::path(f.file).filename() == name && f.line == line && f.reason.find(what) != std::string::npos) return true;
  return false;
}

/// The message of the UsageError importDirectory throws for o ("" when it does not throw one).
std::string usageError(const import::ImportOptions& o) {
  try {
    import::importDirectory(o);
  } catch (const app::UsageError& e) {
    return e.what();
  }
  return "";
}

#define EXPECT_HAS(text, part) EXPECT_NE((text).find(part), std::string::npos) << "no '" << (part) << "' in:\n" << (text)

}  // namespace

TEST(ImportFormats, AFileThatIsNoneOfTheFormatsIsAnErrorNamingItTheFormatsAndItsColumns) {
  const auto d = tempDir("unknown_file");
  write(d / "odometry.csv", "time,delta_s,delta_theta\n1,0.1,0\n2,0.1,0\n");
  write(d / "notes.csv", "what,ever\n1,2\n");
  write(d / "README.md", "not a CSV file: not read\n");
  import::ImportOptions o;
  o.dir = d.string();
  o.out_dir = (d / "out").string();
  std::string what = usageError(o);
  EXPECT_HAS(what, "1 of the *.csv files is none of the import formats");
  EXPECT_HAS(what, "'" + (d / "notes.csv").string() + "': header 'what,ever' (2 columns: 'what', 'ever')");
  EXPECT_HAS(what, "the first column is 'what', not time, time_s or time_us");
  // the formats it could have been, with their columns
  for (const char* f : {"time,delta_s,delta_theta", "time,speed,yaw_rate", "time,speed,steering",
                        "time,landmark_id,range,bearing[,range_std][,bearing_std]", "time,beacon_id,range[,range_std]",
                        "time,x,y[,position_std]", "time,latitude,longitude[,position_std]", "time,x,y,heading",
                        "time,truth_x,truth_y[,truth_heading]",
                        "time,accel_x,accel_y,accel_z,gyro_x,gyro_y,gyro_z[,mag_x,mag_y,mag_z]", "id,x,y"})
    EXPECT_HAS(what, f);
  EXPECT_FALSE(fs::exists(d / "out"));  // nothing written
  // An empty file and a header of no format with a time column: both named, in one message.
  write(d / "empty.csv", "");
  write(d / "pose.csv", "time,east,north\n1,2,3\n");
  what = usageError(o);
  EXPECT_HAS(what, "3 of the *.csv files are none of the import formats");
  EXPECT_HAS(what, "'" + (d / "empty.csv").string() + "': no columns: no header row");
  EXPECT_HAS(what, "'" + (d / "pose.csv").string() + "': header 'time,east,north'");
  EXPECT_HAS(what, "none of the formats");
  // The command line: exit 2 (usage), the file named, nothing written.
  auto [code, text] = runCommand(LCMLOC_IMPORT_BIN, d.string() + " -o " + (d / "out").string(), d);
  EXPECT_EQ(code, 2) << text;
  EXPECT_HAS(text, (d / "notes.csv").string());
  EXPECT_FALSE(fs::exists(d / "out"));
  // Without the three the directory imports (README.md is not a *.csv file: not read).
  for (const char* f : {"notes.csv", "empty.csv", "pose.csv"}) fs::remove(d / f);
  std::tie(code, text) = runCommand(LCMLOC_IMPORT_BIN, d.string() + " -o " + (d / "out").string(), d);
  EXPECT_EQ(code, 0) << text;
  fs::remove_all(d);
}

TEST(ImportFormats, AnUnknownColumnIsAnErrorNamingItAndTheFormatItWouldBe) {
  const auto d = tempDir("unknown_column");
  write(d / "truth.csv", "time,x,y,heading,quality\n1,0,0,0,5\n");
  import::ImportOptions o;
  o.dir = d.string();
  std::string what = usageError(o);
  EXPECT_HAS(what, "(5 columns: 'time', 'x', 'y', 'heading', 'quality')");
  EXPECT_HAS(what, "unknown column 'quality' for ground_truth (time,x,y,heading)");
  write(d / "truth.csv", "time,landmark_id,range,bearing,range_sd,bearing_sd\n1,1,2,0\n");
  what = usageError(o);
  EXPECT_HAS(what, "unknown columns 'range_sd', 'bearing_sd' for landmarks");
  write(d / "truth.csv", "time,x,y,x\n1,0,0,0\n");
  EXPECT_HAS(usageError(o), "column 'x' twice");
  write(d / "truth.csv", "time,accel_x,accel_y,accel_z,gyro_x,gyro_y,gyro_z,mag_x\n1,0,0,9.8,0,0,0,0.2\n");
  EXPECT_HAS(usageError(o), "mag_x, mag_y, mag_z are all three there or none");
  // Named columns in any order: read by name.
  write(d / "truth.csv", "time,heading,y,x\n1,0.5,2,3\n");
  write(d / "odometry.csv", "time,delta_theta,delta_s\n1,0.01,0.2\n2,0.02,0.3\n");
  o.out_dir = (d / "out").string();
  const auto r = import::importDirectory(o);
  ASSERT_TRUE(r.usable());
  const auto truth = messages<lcmloc::ground_truth_t>(r.log_path, "GROUND_TRUTH");
  ASSERT_EQ(truth.size(), 1u);
  EXPECT_EQ(truth[0].x, 3.0);
  EXPECT_EQ(truth[0].y, 2.0);
  EXPECT_EQ(truth[0].heading, 0.5);
  const auto odo = messages<lcmloc::odometry_t>(r.log_path, "ODOMETRY");
  ASSERT_EQ(odo.size(), 2u);
  EXPECT_EQ(odo[1].delta_s, 0.3);
  EXPECT_EQ(odo[1].delta_theta, 0.02);
  fs::remove_all(d);
}

// Beacons without an id: a row with `unknown` in the id column is imported with beacon_id -1
// (the filter associates it with the map); a file without the id column says how to give one; a
// beacon range without a map is refused.
TEST(ImportFormats, BeaconRowsWithoutAnIdAreImportedAsUnknown) {
  const auto d = tempDir("beacon_no_id");
  write(d / "map.csv", "id,x,y\n1,0,0\n");
  write(d / "uwb.csv", "time,range\n1,2.5\n");
  import::ImportOptions o;
  o.dir = d.string();
  EXPECT_HAS(usageError(o), "ranges without a beacon_id column: give the column");
  write(d / "uwb.csv", "time,beacon_id,range\n1,1,2.5\n2,unknown,2.5\n3,1,2.6\n4,7,2.6\n");
  o.out_dir = (d / "out").string();
  const auto r = import::importDirectory(o);
  EXPECT_TRUE(refused(r, "uwb.csv", 5, "beacon id 7 not in the map")) << (r.refusals.empty() ? "" : r.refusals[0].reason);
  EXPECT_EQ(r.refusals.size(), 1u);
  const auto b = messages<lcmloc::beacon_range_t>(r.log_path, "BEACONS");
  ASSERT_EQ(b.size(), 3u);
  EXPECT_EQ(b[0].beacon_id, 1);
  EXPECT_EQ(b[1].beacon_id, -1);
  EXPECT_EQ(b[1].range, 2.5);
  fs::remove(d / "map.csv");
  fs::remove_all(d / "out");
  o.out_dir.clear();
  const auto no_map = import::importDirectory(o);
  EXPECT_TRUE(refused(no_map, "uwb.csv", 3, "a beacon range: no map file (id,x,y) in the directory"));
  fs::remove_all(d);
}

TEST(ImportFormats, SigmaColumnsAreCarriedIntoTheMessagesAndBadSigmasAreRefusedByLine) {
  const auto d = tempDir("sigma");
  write(d / "map.csv", "id,x,y\n1,5,0\n2,0,5\n");
  write(d / "beacons.csv",
        "time,beacon_id,range,range_std\n"
        "1.0,1,5.0,0.25\n"   // 2
        "1.1,2,5.1,nan\n"    // 3 NaN
        "1.2,1,5.0,-0.1\n"   // 4 negative
        "1.3,2,5.0,0\n"      // 5 zero
        "1.4,2,5.2,0.05\n");  // 6
  write(d / "landmarks.csv", "time,bearing_std,landmark_id,range_std,range,bearing\n1.0,0.02,1,0.3,5.0,0.1\n"
                             "1.1,inf,1,0.3,5.0,0.1\n");
  write(d / "gps.csv", "time,x,y,position_std\n1.0,1,2,1.5\n2.0,1,2,\n3.0,1,2,0\n");
  import::ImportOptions o;
  o.dir = d.string();
  o.out_dir = (d / "out").string();
  const auto r = import::importDirectory(o);
  EXPECT_TRUE(refused(r, "beacons.csv", 3, "column 4: not finite: 'nan'"));
  EXPECT_TRUE(refused(r, "beacons.csv", 4, "column 4: range_std must be > 0, got -0.1"));
  EXPECT_TRUE(refused(r, "beacons.csv", 5, "column 4: range_std must be > 0, got 0"));
  EXPECT_TRUE(refused(r, "landmarks.csv", 3, "column 2: not finite: 'inf'"));
  EXPECT_TRUE(refused(r, "gps.csv", 3, "column 4: empty"));
  EXPECT_TRUE(refused(r, "gps.csv", 4, "column 4: position_std must be > 0, got 0"));
  EXPECT_EQ(r.refusals.size(), 6u);
  const auto beacons = messages<lcmloc::beacon_range_t>(r.log_path, "BEACONS");
  ASSERT_EQ(beacons.size(), 2u);
  EXPECT_EQ(beacons[0].range_std, 0.25);
  EXPECT_EQ(beacons[1].range_std, 0.05);
  EXPECT_EQ(beacons[1].range, 5.2);
  const auto landmarks = messages<lcmloc::landmark_obs_t>(r.log_path, "LANDMARKS");
  ASSERT_EQ(landmarks.size(), 1u);
  EXPECT_EQ(landmarks[0].range_std, 0.3);
  EXPECT_EQ(landmarks[0].bearing_std, 0.02);
  EXPECT_EQ(landmarks[0].range, 5.0);
  EXPECT_EQ(landmarks[0].bearing, 0.1);
  const auto fixes = messages<lcmloc::gps_fix_t>(r.log_path, "GPS");
  ASSERT_EQ(fixes.size(), 1u);
  EXPECT_EQ(fixes[0].position_std, 1.5);
  // Without the column: 0 in the message, the filter's default.
  write(d / "beacons.csv", "time,beacon_id,range\n1.0,1,5.0\n");
  fs::remove(d / "landmarks.csv");
  fs::remove(d / "gps.csv");
  fs::remove_all(d / "out");
  const auto plain = import::importDirectory(o);
  const auto b = messages<lcmloc::beacon_range_t>(plain.log_path, "BEACONS");
  ASSERT_EQ(b.size(), 1u);
  EXPECT_EQ(b[0].range_std, 0.0);
  fs::remove_all(d);
}

TEST(ImportFormats, ImuRowsBecomeImuMessagesAndAnImuWithoutMagnetometerTurnsItOff) {
  const auto d = tempDir("imu");
  std::string imu = "time,accel_x,accel_y,accel_z,gyro_x,gyro_y,gyro_z\n";
  for (int k = 0; k < 10; ++k) imu += fmt::format("{:.2f},0.1,{},9.81,0,0,{}\n", 1.0 + 0.01 * k, 0.01 * k, 0.2);
  imu += "1.10,0.1,0,9.81,0,0,150\n";  // line 12: a gyro beyond what the fusion takes
  write(d / "imu.csv", imu);
  write(d / "odometry.csv", "time,speed,yaw_rate\n1.0,1,0.2\n1.05,1,0.2\n1.1,1,0.2\n");
  import::ImportOptions o;
  o.dir = d.string();
  o.out_dir = (d / "out").string();
  auto r = import::importDirectory(o);
  EXPECT_TRUE(refused(r, "imu.csv", 12, "gyro[2]")) << (r.refusals.empty() ? "" : r.refusals[0].reason);
  EXPECT_EQ(r.refusals.size(), 1u);
  auto m = messages<lcmloc::imu_t>(r.log_path, "IMU");
  ASSERT_EQ(m.size(), 10u);
  EXPECT_EQ(m[3].accel[1], 0.03);
  EXPECT_EQ(m[3].accel[2], 9.81);
  EXPECT_EQ(m[3].gyro[2], 0.2);
  EXPECT_EQ(m[3].mag[0], 0.0);
  for (std::size_t i = 0; i < m.size(); ++i) EXPECT_EQ(m[i].seq, static_cast<int64_t>(i));
  auto cfg = app::loadSystemConfig(r.config_path);
  EXPECT_FALSE(cfg.fusion.filter.gnss.use_magnetometer);  // mag 0 must not be read as a heading
  // With a magnetometer: its values, and the config leaves it on; a filter that takes the
  // magnetometer makes a gate decision on every IMU row in the replay.
  std::string with_mag = "time,gyro_z,gyro_y,gyro_x,accel_z,accel_y,accel_x,mag_x,mag_y,mag_z\n";
  for (int k = 0; k < 10; ++k) with_mag += fmt::format("{:.2f},0.2,0,0,9.81,0,0.1,0.2,0.01,-0.4\n", 1.0 + 0.01 * k);
  write(d / "imu.csv", with_mag);
  write(d / "gps.csv", "time,x,y\n1.0,0,0\n1.1,0.1,0\n");
  fs::remove_all(d / "out");
  o.filter = "ukf_gps";
  r = import::importDirectory(o);
  EXPECT_TRUE(r.refusals.empty());
  m = messages<lcmloc::imu_t>(r.log_path, "IMU");
  ASSERT_EQ(m.size(), 10u);
  EXPECT_EQ(m[0].mag[1], 0.01);
  EXPECT_EQ(m[0].mag[2], -0.4);
  EXPECT_EQ(m[0].accel[0], 0.1);
  cfg = app::loadSystemConfig(r.config_path);
  EXPECT_TRUE(cfg.fusion.filter.gnss.use_magnetometer);
  const fs::path est = d / "out" / "est.lcmlog";
  auto [code, text] = runCommand(LCMLOC_REPLAY_BIN,
                                 r.log_path + " --config " + r.config_path + " -o " + est.string(), d);
  ASSERT_EQ(code, 0) << text;
  int imu_decisions = 0;
  for (const auto& g : messages<lcmloc::gate_decision_t>(est.string(), "GATE")) imu_decisions += g.sensor == "IMU";
  EXPECT_EQ(imu_decisions, 10);
  // Two IMU files that overlap in time are one stream twice: refused, as odometry.
  fs::copy_file(d / "imu.csv", d / "imu2.csv");
  EXPECT_THROW(import::importDirectory(o), std::runtime_error);
  fs::remove_all(d);
}

// Ground truth of position only: its messages carry a NaN heading, the config's initial heading
// is the truth's direction of travel, and lcmloc-evaluate scores the position alone (no heading
// error, no NEES over x, y, theta; NEES over x, y).
TEST(ImportFormats, AGroundTruthOfPositionOnlyIsScoredOnThePosition) {
  const auto d = tempDir("truth_position");
  std::string odo = "time,delta_s,delta_theta\n", truth = "time,truth_x,truth_y\n";
  const double th0 = 2.0;  // heading, radians: not in the truth file
  for (int k = 0; k <= 200; ++k) {
    const double t = 10.0 + 0.1 * k, s = 0.05 * k;
    if (k > 0) odo += fmt::format("{:.1f},0.05,0\n", t);
    truth += fmt::format("{:.1f},{:.12f},{:.12f}\n", t, 1.0 + s * std::cos(th0), -2.0 + s * std::sin(th0));
  }
  write(d / "odometry.csv", odo);
  write(d / "truth.csv", truth);
  import::ImportOptions o;
  o.dir = d.string();
  o.out_dir = (d / "out").string();
  const auto r = import::importDirectory(o);
  ASSERT_TRUE(r.refusals.empty());
  const auto gt = messages<lcmloc::ground_truth_t>(r.log_path, "GROUND_TRUTH");
  ASSERT_EQ(gt.size(), 201u);
  EXPECT_TRUE(std::isnan(gt[5].heading));
  EXPECT_NEAR(gt[5].x, 1.0 + 0.25 * std::cos(th0), 1e-9);
  const auto cfg = app::loadSystemConfig(r.config_path);
  EXPECT_NEAR(cfg.fusion.filter.initial_pose[0], 1.0, 1e-12);
  EXPECT_NEAR(cfg.fusion.filter.initial_pose[1], -2.0, 1e-12);
  EXPECT_NEAR(cfg.fusion.filter.initial_pose[2], th0, 1e-9);  // direction of travel
  const fs::path est = d / "out" / "est.lcmlog";
  auto [code, text] = runCommand(LCMLOC_REPLAY_BIN,
                                 r.log_path + " --config " + r.config_path + " --with-inputs -o " + est.string(), d);
  ASSERT_EQ(code, 0) << text;
  const auto log = eval::readTrajectoryLog(est.string(), eval::TrajectoryLogOptions{});
  ASSERT_EQ(log.truth.size(), 201u);
  EXPECT_FALSE(log.truth[0].has_heading);
  EXPECT_TRUE(log.issues.empty()) << log.issues.front().what;
  const auto score = eval::scoreTrack(log.tracks.at(0), log.truth, eval::EvaluateOptions{});
  EXPECT_GT(score.scored, 150);
  EXPECT_FALSE(score.has_heading);
  EXPECT_EQ(score.nees3.samples, 0);
  EXPECT_EQ(score.nees2.samples, score.scored);
  EXPECT_LT(score.position.max, 0.01);  // exact odometry from the right start
  // The command line's report says the same.
  std::tie(code, text) = runCommand(LCMLOC_EVALUATE_BIN, est.string() + " -o " + (d / "eval").string(), d);
  ASSERT_EQ(code, 0) << text;
  std::ifstream in(d / "eval" / "report.json");
  const std::string report((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_HAS(report, "\"has_heading\": false");
  EXPECT_HAS(report, "\"heading_error_rad\": null");
  fs::remove_all(d);
}

// Bad rows through the command line: an id missing from the map, time going backwards, an
// unknown landmark id: each refused and listed with file, line and reason, counted, and the
// rest imported (exit 3: damaged input, the work done with its intact part).
TEST(ImportFormats, BadRowsAreListedAndCountedByTheCommandAndTheRestImported) {
  const auto d = tempDir("bad_rows");
  write(d / "map.csv", "id,x,y\n1,5,0\n");
  write(d / "landmarks.csv", "time,landmark_id,range,bearing\n1.0,1,5,0\n1.1,9,5,0\n1.2,1,5,0\n1.05,1,5,0\n1.3,1,5,0\n");
  write(d / "odometry.csv", "time,delta_s,delta_theta\n1.0,0.1,0\n1.1,0.1,0\n0.9,0.1,0\n1.2,0.1,0\n");
  const fs::path out = d / "out";
  auto [code, text] = runCommand(LCMLOC_IMPORT_BIN, d.string() + " -o " + out.string(), d);
  ASSERT_EQ(code, app::kExitInputDamaged) << text;
  EXPECT_HAS(text, "3 row(s) refused (listed above): the rest is imported; exit 3 (damaged input)");
  EXPECT_HAS(text, (d / "landmarks.csv").string() + ":3: landmark id 9 not in the map");
  EXPECT_HAS(text, (d / "landmarks.csv").string() + ":5: time 1.05 before the previous row's 1.2");
  EXPECT_HAS(text, (d / "odometry.csv").string() + ":4: time 0.9 not after the previous row's 1.1");
  EXPECT_HAS(text, "5 rows read, 2 refused, 3 messages");
  EXPECT_HAS(text, "4 rows read, 1 refused, 3 messages");
  EXPECT_HAS(text, "3 rows refused");
  EXPECT_EQ(messages<lcmloc::landmark_obs_t>((out / "run.lcmlog").string(), "LANDMARKS").size(), 3u);
  EXPECT_EQ(messages<lcmloc::odometry_t>((out / "run.lcmlog").string(), "ODOMETRY").size(), 3u);
  fs::remove_all(d);
}

// The written config always passes the replay's checks: recordings generated with an initial
// heading of exactly pi and -pi, just inside and just outside pi (as written in the file),
// heading from travel along -x (atan2 gives pi), positions near the bound of initial_pose and
// the wheelbase at both bounds; each config read back with the replay's loader and the log
// replayed by lcmloc-replay.
TEST(ImportFormats, TheWrittenConfigIsReadBackByTheReplaysLoaderAndReplays) {
  struct Case {
    std::string name;
    std::string heading;  ///< as written in the truth file ("" = position-only truth)
    double x0, y0;
    double expected_heading;
    double wheelbase;     ///< > 0: speed,steering odometry
  };
  const double pi = M_PI;
  const std::vector<Case> cases{
      {"pi", fmt::format("{}", pi), 0, 0, pi, 0},
      {"minus_pi", fmt::format("{}", -pi), 3, 4, pi, 0},  // -pi wraps to pi: (-pi, pi]
      {"pi_6_digits", "3.141593", 0, 0, 3.141593 - 2 * pi, 0},  // just over pi as written: wrapped
      {"just_below_pi", fmt::format("{}", std::nextafter(pi, 0.0)), 0, 0, std::nextafter(pi, 0.0), 0},
      {"just_above_minus_pi", fmt::format("{}", std::nextafter(-pi, 0.0)), 0, 0, std::nextafter(-pi, 0.0), 0},
      {"travel_minus_x", "", 10, 0, pi, 0},
      {"far_east", "-3.1415926", 9999990.25, -9999990.125, -3.1415926, 20.0},
      {"small_wheelbase", "0", -9999999.5, 0.5, 0.0, 0.1},
  };
  std::mt19937 rng(35);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const auto d = tempDir("roundtrip_" + c.name);
    // a vehicle driving straight along its heading (position-only: along -x) at 0.5 m/s, 10 Hz
    const double th = c.heading.empty() ? pi : std::stod(c.heading);
    std::string truth = c.heading.empty() ? "time,truth_x,truth_y\n" : "time,x,y,heading\n";
    std::string odo = c.wheelbase > 0 ? "time,speed,steering\n" : "time,delta_s,delta_theta\n";
    std::string gps = "time,x,y,position_std\n";
    for (int k = 0; k <= 100; ++k) {
      const double t = 5.0 + 0.1 * k, s = 0.05 * k;
      const double x = c.x0 + s * std::cos(th), y = c.y0 + s * std::sin(th);
      truth += c.heading.empty() ? fmt::format("{:.1f},{},{}\n", t, x, y)
                                 : fmt::format("{:.1f},{},{},{}\n", t, x, y, c.heading);
      if (c.wheelbase > 0) odo += fmt::format("{:.1f},0.5,0\n", t);
      else if (k > 0) odo += fmt::format("{:.1f},0.05,0\n", t);
      if (k % 10 == 5 && std::abs(c.x0) < 1e5) gps += fmt::format("{:.1f},{},{},0.5\n", t, x + noise(rng), y + noise(rng));
    }
    write(d / "truth.csv", truth);
    write(d / "odometry.csv", odo);
    write(d / "gps.csv", gps);
    import::ImportOptions o;
    o.dir = d.string();
    o.out_dir = (d / "out").string();
    o.wheelbase = c.wheelbase;
    const auto r = import::importDirectory(o);
    ASSERT_TRUE(r.usable());
    EXPECT_TRUE(r.refusals.empty()) << r.refusals.front().reason;
    app::SystemConfig cfg;
    ASSERT_NO_THROW(cfg = app::loadSystemConfig(r.config_path));
    EXPECT_DOUBLE_EQ(cfg.fusion.filter.initial_pose[2], c.expected_heading);
    EXPECT_LE(std::abs(cfg.fusion.filter.initial_pose[2]), pi);
    EXPECT_EQ(cfg.fusion.filter.initial_pose[0], c.x0);  // read back exactly
    EXPECT_EQ(cfg.fusion.filter.initial_pose[1], c.y0);
    if (c.wheelbase > 0) {
      EXPECT_EQ(cfg.fusion.filter.wheelbase, c.wheelbase);
    }
    const fs::path est = d / "out" / "est.lcmlog";
    auto [code, text] = runCommand(LCMLOC_REPLAY_BIN,
                                   r.log_path + " --config " + r.config_path + " -o " + est.string(), d);
    ASSERT_EQ(code, 0) << text;
    const auto poses = messages<lcmloc::pose_t>(est.string(), "POSE");
    ASSERT_FALSE(poses.empty());
    // the last pose 5 m further along the heading, from exact odometry
    const auto& last = poses.back();
    EXPECT_NEAR(last.state[0], c.x0 + 5.0 * std::cos(th), 0.05);
    EXPECT_NEAR(last.state[1], c.y0 + 5.0 * std::sin(th), 0.05);
    fs::remove_all(d);
  }
  // A truth position beyond the bound of initial_pose (1e7 m) is refused by line, not written
  // into a config the replay would refuse.
  const auto d = tempDir("roundtrip_beyond");
  write(d / "truth.csv", "time,x,y,heading\n1,10000000.5,0,0\n2,0,0,0\n");
  write(d / "odometry.csv", "time,delta_s,delta_theta\n1,0,0\n2,0,0\n");
  import::ImportOptions o;
  o.dir = d.string();
  o.out_dir = (d / "out").string();
  const auto r = import::importDirectory(o);
  EXPECT_TRUE(refused(r, "truth.csv", 2, "more than 10000 km from the origin"));
  EXPECT_NO_THROW(app::loadSystemConfig(r.config_path));
  fs::remove_all(d);
}

// A recording whose every landmark observation is a distractor (no identity, nothing in the map
// where it was seen): the import warns that the run can only be dead reckoning, writes every
// observation (nothing lost), and the replay keeps the estimate on the odometry: no distractor is
// taken for a landmark.
TEST(ImportFormats, ARecordingOfNothingButDistractorsIsImportedWholeWarnedAboutAndNeverMovesTheEstimate) {
  const auto d = tempDir("distractors");
  write(d / "map.csv", "id,x,y\n1,10,10\n2,-10,10\n3,10,-10\n4,-10,-10\n");
  std::string odo = "time,delta_s,delta_theta\n", truth = "time,x,y,heading\n",
              lm = "time,landmark_id,range,bearing\n";
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k <= 600; ++k) {  // 60 s along +x at 0.5 m/s
    const double t = 1.0 + 0.1 * k, x = 0.05 * k;
    if (k > 0) odo += fmt::format("{:.1f},0.05,0\n", t);
    truth += fmt::format("{:.1f},{:.12f},0,0\n", t, x);
    // Something seen 1-3 m away, in front: never near a map landmark (all 10 m off the path).
    if (k % 2 == 0) lm += fmt::format("{:.1f},unknown,{:.6f},{:.6f}\n", t, 2.0 + u(rng), 0.7 * u(rng));
  }
  write(d / "odometry.csv", odo);
  write(d / "truth.csv", truth);
  write(d / "landmarks.csv", lm);
  const fs::path out = d / "out";
  auto [code, text] = runCommand(LCMLOC_IMPORT_BIN, d.string() + " -o " + out.string(), d);
  ASSERT_EQ(code, 0) << text;
  EXPECT_HAS(text, "warning: every one of the 301 landmark observations is without identity");
  EXPECT_HAS(text, "301 rows read, 0 refused, 301 messages");
  const std::string run = (out / "run.lcmlog").string(), config = (out / "config.yaml").string();
  EXPECT_EQ(messages<lcmloc::landmark_obs_t>(run, "LANDMARKS").size(), 301u);
  const fs::path est = d / "est.lcmlog";
  std::tie(code, text) = runCommand(LCMLOC_REPLAY_BIN, run + " --config " + config + " --with-inputs -o " + est.string(), d);
  ASSERT_EQ(code, 0) << text;
  const auto log = eval::readTrajectoryLog(est.string(), eval::TrajectoryLogOptions{});
  int64_t accepted = 0;
  for (const auto& g : log.gates) accepted += g.accepted;
  EXPECT_EQ(log.gates.size(), 301u);
  EXPECT_EQ(accepted, 0);
  // The same log without its observations gives the same estimates: the distractors changed nothing.
  const fs::path odo_only = d / "odometry_only.lcmlog", est2 = d / "est2.lcmlog";
  std::tie(code, text) = runCommand(LCMLOC_LOG_BIN, "cut " + run + " -c 'ODOMETRY|GROUND_TRUTH' -o " + odo_only.string(), d);
  ASSERT_EQ(code, 0) << text;
  std::tie(code, text) =
      runCommand(LCMLOC_REPLAY_BIN, odo_only.string() + " --config " + config + " --with-inputs -o " + est2.string(), d);
  ASSERT_EQ(code, 0) << text;
  const auto dr = eval::readTrajectoryLog(est2.string(), eval::TrajectoryLogOptions{});
  // (a state after every odometry message and after every decision: the last one at each time)
  std::map<int64_t, eval::Estimate> with, without;
  for (const auto& p : log.tracks.at(0).poses) with[p.utime] = p;
  for (const auto& p : dr.tracks.at(0).poses) without[p.utime] = p;
  ASSERT_EQ(with.size(), 601u);
  ASSERT_EQ(without.size(), 600u);  // (no decision at the first time, before the first odometry)
  for (const auto& [t, b] : without) {
    const auto& a = with.at(t);
    ASSERT_EQ(a.x, b.x) << t;
    ASSERT_EQ(a.y, b.y) << t;
    ASSERT_EQ(a.theta, b.theta) << t;
  }
  fs::remove_all(d);
}
