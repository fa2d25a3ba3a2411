// lcmloc-convert: public data sets -> the CSV import format. Small fixtures in the data sets'
// own layouts, and the real recordings of ../shared/data when they are there.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "lcmloc/convert/convert.hpp"

namespace fs = std::filesystem;
using namespace lcmloc;

namespace {

const char* kHeader = "# UTIAS Multi-Robot Cooperative Localization and Mapping Dataset\n# a comment\n";

class ConvertTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("lcmloc_test_convert_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "in");
    fs::create_directories(dir_ / "out");
  }
  void TearDown() override { fs::remove_all(dir_); }
  void write(const std::string& name, const std::string& text) { std::ofstream(dir_ / "in" / name) << text; }
  std::string read(const std::string& name) const {
    std::ifstream f(dir_ / "out" / name);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
  }
  std::string in() const { return (dir_ / "in").string(); }
  std::string out() const { return (dir_ / "out").string(); }
  /// Runs a command line, output to a file; returns its exit status.
  int run(const std::string& args) {
    const std::string cmd = args + " > " + (dir_ / "cmd.txt").string() + " 2>&1";
    const int rc = std::system(cmd.c_str());
    std::ifstream f(dir_ / "cmd.txt");
    std::stringstream s;
    s << f.rdbuf();
    output_ = s.str();
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
  }
  fs::path dir_;
  std::string output_;

  /// A small MRCLAM directory: two landmarks, robot 2 seen once, a barcode of no subject.
  void writeMrclam() {
  write("Barcodes.dat", std::string(kHeader) + "  1 \t 5\n  2 \t 14\n  6 \t 63\n  7 \t 25\n");
  write("Landmark_Groundtruth.dat", std::string(kHeader) + "  6 \t 0.5 \t -4.25 \t 0.0001 \t 0.0002\n"
                                                           "  7 \t 1.5 \t 3.0 \t 0.0001 \t 0.0002\n");
  write("Robot1_Odometry.dat", std::string(kHeader) + "1248444187.156 \t 0.086 \t -0.398\n1248444187.171 \t 0.1 \t 0\n");
  // Landmark 6 (barcode 63), robot 2 (barcode 14), landmark 7 (barcode 25), a barcode no table has (99).
  write("Robot1_Measurement.dat", std::string(kHeader) + "1248444189.599 \t 63 \t 3.787 \t -0.257\n"
                                                         "1248444189.599 \t 14 \t 1.5 \t 0.25\n"
                                                         "1248444190.0 \t 25 \t 2.0 \t 0.5\n"
                                                         "1248444190.5 \t 99 \t 2.0 \t 0.5\n");
  write("Robot1_Groundtruth.dat", std::string(kHeader) + "1248444175.103 \t 1.4127729 \t -3.8910776 \t 2.2696\n");
}
};

}  // namespace

TEST_F(ConvertTest, MrclamLandmarksByIdOtherRobotsWithoutIdentity) {
  writeMrclam();
  const auto c = convert::convertMrclam(in(), 1, out());
  ASSERT_EQ(c.files.size(), 4u);
  EXPECT_EQ(read("map.csv"), "id,x,y\n6,0.5,-4.25\n7,1.5,3\n");
  EXPECT_EQ(read("odometry.csv"), "time,speed,yaw_rate\n1248444187.156,0.086,-0.398\n1248444187.171,0.1,0\n");
  EXPECT_EQ(read("landmarks.csv"),
            "time,landmark_id,range,bearing\n1248444189.599,6,3.787,-0.257\n1248444189.599,unknown,1.5,0.25\n"
            "1248444190,7,2,0.5\n");
  EXPECT_EQ(read("truth.csv"), "time,x,y,heading\n1248444175.103,1.4127729,-3.8910776,2.2696\n");
  ASSERT_EQ(c.notes.size(), 2u);
  EXPECT_NE(c.notes[0].find("1 observations of other robots"), std::string::npos) << c.notes[0];
  EXPECT_NE(c.notes[1].find("1 measurements of a barcode"), std::string::npos) << c.notes[1];
}

TEST_F(ConvertTest, MrclamMalformedLineIsAnErrorNamingFileAndLine) {
  writeMrclam();
  write("Robot1_Odometry.dat", std::string(kHeader) + "1248444187.156 \t 0.086 \t -0.398\n1248444187.171 \t nan \t 0\n");
  try {
    convert::convertMrclam(in(), 1, out());
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("Robot1_Odometry.dat:4: column 2: not a finite number: 'nan'"),
              std::string::npos) << e.what();
  }
  write("Robot1_Odometry.dat", std::string(kHeader) + "1248444187.156 \t 0.086\n");
  EXPECT_THROW(convert::convertMrclam(in(), 1, out()), std::runtime_error);  // a column missing
  EXPECT_THROW(convert::convertMrclam(in(), 6, out()), std::invalid_argument);
  EXPECT_THROW(convert::convertMrclam(in(), 2, out()), std::runtime_error);  // no Robot2 files
}

TEST_F(ConvertTest, UwbLabyrinthRangesSigmaMapOdometryAndPositionOnlyTruth) {
  write("Indoor_UWB_Input.txt",
        "range2 0.125 2.5 0.01 -0.02 -0.01 105 0 \n"
        "odom2diff 0.125 0 0 0 0.0785 0.0001 0.0001 0.0001\n"
        "range2 0.25 1.5 0.04 -0.02 2.365 107 0 \n"
        "odom2diff 0.25 0.5 0.25 0 0.125 0.0001 0.0001 0.0001\n"
        "range2 0.375 2.25 0.01 -0.02 -0.01 105 0 \n");
  write("Indoor_UWB_GT.txt", "point2 0.125 1.625 2.25 0 0 0 0 \npoint2 0.25 1.75 2.25 0 0 0 0 \n");
  const auto c = convert::convertUwbLabyrinth(in(), out());
  EXPECT_EQ(c.files.size(), 4u);
  EXPECT_EQ(read("beacons.csv"), "time,beacon_id,range,range_std\n0.125,105,2.5,0.1\n0.25,107,1.5,0.2\n0.375,105,2.25,0.1\n");
  EXPECT_EQ(read("map.csv"), "id,x,y\n105,-0.02,-0.01\n107,-0.02,2.365\n");
  EXPECT_EQ(read("odometry.csv"), "time,speed,yaw_rate\n0.125,0,0\n0.25,0.375,2\n");  // (0.5 - 0.25) / 0.125
  EXPECT_EQ(read("truth.csv"), "time,truth_x,truth_y\n0.125,1.625,2.25\n0.25,1.75,2.25\n");

  write("Indoor_UWB_Input.txt", "range2 0.125 2.5 0.01 -0.02 -0.01 105 0\nrange2 0.25 2.5 0.01 1.0 -0.01 105 0\n");
  try {
    convert::convertUwbLabyrinth(in(), out());
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("Indoor_UWB_Input.txt:2: module 105 at a second position"), std::string::npos)
        << e.what();
  }
  write("Indoor_UWB_Input.txt", "range2 0.125 2.5 -0.01 -0.02 -0.01 105 0\n");
  EXPECT_THROW(convert::convertUwbLabyrinth(in(), out()), std::runtime_error);  // a negative variance
  write("Indoor_UWB_Input.txt", "odom3 0.125 2.5\n");
  EXPECT_THROW(convert::convertUwbLabyrinth(in(), out()), std::runtime_error);  // an unknown row type
}

TEST_F(ConvertTest, CommandRefusesAnExistingOutputAndAMissingDirectory) {
  writeMrclam();
  ASSERT_EQ(run(std::string(LCMLOC_CONVERT_BIN) + " mrclam --dir " + in() + " -o " + out() + "/a"), 0) << output_;
  EXPECT_NE(output_.find("landmarks.csv"), std::string::npos) << output_;
  EXPECT_EQ(run(std::string(LCMLOC_CONVERT_BIN) + " mrclam --dir " + in() + " -o " + out() + "/a"), 2) << output_;
  EXPECT_EQ(run(std::string(LCMLOC_CONVERT_BIN) + " mrclam --dir " + in() + " -o " + out() + "/a --overwrite"), 0);
  EXPECT_EQ(run(std::string(LCMLOC_CONVERT_BIN) + " uwb-labyrinth --dir /nonexistent -o " + out() + "/b"), 2);
  write("Robot1_Odometry.dat", "1 2\n");  // damaged: a runtime error naming the line
  EXPECT_EQ(run(std::string(LCMLOC_CONVERT_BIN) + " mrclam --dir " + in() + " -o " + out() + "/c"), 1) << output_;
  EXPECT_NE(output_.find("Robot1_Odometry.dat:1"), std::string::npos) << output_;
}

// The real recordings, converted and imported as a user would.
TEST_F(ConvertTest, SharedRecordingsConvertAndImport) {
  const std::string data = LCMLOC_SHARED_DATA_DIR;
  if (!fs::exists(data + "/mrclam_ds6/Barcodes.dat") || !fs::exists(data + "/uwb_indoor/Indoor_UWB_Input.txt"))
    GTEST_SKIP() << "no " << data << "/mrclam_ds6 or uwb_indoor";
  for (int robot : {1, 2}) {
    const std::string csv = out() + "/mrclam" + std::to_string(robot);
    ASSERT_EQ(run(std::string(LCMLOC_CONVERT_BIN) + " mrclam --dir " + data + "/mrclam_ds6 --robot " +
                  std::to_string(robot) + " -o " + csv), 0) << output_;
    EXPECT_NE(output_.find("map.csv          map                 15 rows"), std::string::npos) << output_;
    // Robot 2's odometry repeats one time: that row is refused, named, and the rest imported
    // (exit 3: damaged input).
    ASSERT_EQ(run(std::string(LCMLOC_IMPORT_BIN) + " " + csv + " -o " + csv + "_run"), robot == 1 ? 0 : 3) << output_;
    EXPECT_NE(output_.find(robot == 1 ? ", 0 rows refused" : ", 1 rows refused"), std::string::npos) << output_;
    EXPECT_TRUE(fs::exists(csv + "_run/run.lcmlog"));
  }
  const std::string csv = out() + "/uwb";
  ASSERT_EQ(run(std::string(LCMLOC_CONVERT_BIN) + " uwb-labyrinth --dir " + data + "/uwb_indoor -o " + csv), 0) << output_;
  EXPECT_NE(output_.find("beacons.csv      beacons            233 rows"), std::string::npos) << output_;
  ASSERT_EQ(run(std::string(LCMLOC_IMPORT_BIN) + " " + csv + " -o " + csv + "_run"), 0) << output_;
  EXPECT_NE(output_.find("map: 4 entries"), std::string::npos) << output_;
}

// The recordings scored as a user would score them: the importer's written config (its noise
// fitted against the truth), no hand edits, the config's filter replayed by lcmloc-evaluate.
// The bounds are the real-data targets (the NEES target is not met yet and not asserted:
// tools/real_data_report.sh prints every figure); before re-localization and the noise fit,
// these runs ended 36-181 m (landmarks) and 11-20 m (UWB) off.
TEST_F(ConvertTest, SharedRecordingsScoredWithTheImportersConfig) {
  const std::string data = LCMLOC_SHARED_DATA_DIR;
  if (!fs::exists(data + "/mrclam_ds6/Barcodes.dat") || !fs::exists(data + "/uwb_indoor/Indoor_UWB_Input.txt"))
    GTEST_SKIP() << "no " << data << "/mrclam_ds6 or uwb_indoor";
  auto score = [&](const std::string& name, const std::string& convert_args) {
    const std::string d = out() + "/" + name;
    EXPECT_EQ(run(std::string(LCMLOC_CONVERT_BIN) + " " + convert_args + " -o " + d + "_csv"), 0) << output_;
    const int imported = run(std::string(LCMLOC_IMPORT_BIN) + " " + d + "_csv -o " + d);
    EXPECT_TRUE(imported == 0 || imported == 3) << output_;  // (3: a row refused, the rest imported)
    EXPECT_EQ(run(std::string(LCMLOC_EVALUATE_BIN) + " " + d + "/run.lcmlog --config " + d +
                  "/config.yaml --filters ukf_landmarks --no-plots --log-level warn -o " + d + "_eval"), 0)
        << output_;
    std::ifstream f(d + "_eval/report.json");
    return nlohmann::json::parse(f);
  };
  for (int robot : {1, 2}) {
    const auto j = score("mrclam" + std::to_string(robot),
                         "mrclam --dir " + data + "/mrclam_ds6 --robot " + std::to_string(robot));
    const auto& e = j.at("tracks").at(0).at("position_error_m");
    const double rmse = e.at("rmse").get<double>(), max = e.at("max").get<double>();
    EXPECT_LE(rmse, 0.25) << "robot " << robot;
    EXPECT_LT(max, 1.5) << "robot " << robot;
    // Consistent: the landmarks' residuals correlate from one observation to the next (about
    // 0.9), and the fitted correlation factor discounts them so (NEES 12-15 without it).
    const double nees = j.at("tracks").at(0).at("nees_xytheta").at("mean").get<double>();
    EXPECT_GE(nees, 1.0) << "robot " << robot;
    EXPECT_LE(nees, 6.0) << "robot " << robot;
    const auto& u = j.at("unknown_identity");
    const auto& by = u.at("by_filter").at(0);
    EXPECT_LE(by.at("unknown_accepted").get<double>(), 0.02 * u.at("without_identity").get<double>())
        << "robot " << robot;  // other robots taken for landmarks
  }
  // UWB: the truth has positions only; the process noise is fitted by the direction of travel,
  // after the odometry's reversed turn scale (0.89 m RMSE with the default process noise), and
  // the modules' range bias of about 0.1 m gets its states (0.171 m without them).
  const auto j = score("uwb", "uwb-labyrinth --dir " + data + "/uwb_indoor");
  const auto& e = j.at("tracks").at(0).at("position_error_m");
  EXPECT_LE(e.at("rmse").get<double>(), 0.12);
  EXPECT_LT(e.at("max").get<double>(), 0.4);
}
