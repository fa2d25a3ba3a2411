// The README's "bring your own data" walk-through, command for command: lcmloc-import on the
// documented example directory, lcmloc-replay of the imported log with the config the import
// wrote, lcmloc-evaluate of the replay's output. Each step is the installed program, run the
// way a user types it; the test reads the evaluation's report.json.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace fs = std::filesystem;

namespace {

int run(const std::string& cmd) {
  const int st = std::system((cmd + " > /dev/null 2>&1").c_str());
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

}  // namespace

TEST(Walkthrough, CsvDirectoryToScoredReportWithTheDocumentedCommands) {
  const fs::path out = fs::temp_directory_path() / ("lcmloc_walkthrough_" + std::to_string(::getpid()));
  fs::remove_all(out);
  const std::string dir = out.string();
  ASSERT_EQ(run(std::string(LCMLOC_IMPORT_BIN) + " " + LCMLOC_EXAMPLE_DIR + " -o " + dir), 0);
  ASSERT_TRUE(fs::exists(out / "run.lcmlog"));
  ASSERT_TRUE(fs::exists(out / "config.yaml"));
  ASSERT_EQ(run(std::string(LCMLOC_REPLAY_BIN) + " " + dir + "/run.lcmlog --config " + dir +
                "/config.yaml --with-inputs -o " + dir + "/estimates.lcmlog"),
            0);
  ASSERT_EQ(run(std::string(LCMLOC_EVALUATE_BIN) + " " + dir + "/estimates.lcmlog -o " + dir + "/eval"), 0);
  std::ifstream in(out / "eval" / "report.json");
  ASSERT_TRUE(in.good());
  const auto r = nlohmann::json::parse(in);
  const auto& track = r.at("tracks").at(0);
  EXPECT_EQ(track.at("channel"), "POSE");
  EXPECT_GT(track.at("scored").get<int>(), 3000);
  // Measured on the example: RMSE 1.8 cm, max 6.7 cm, heading RMSE 0.6 deg, NEES(x, y, theta) 3.15.
  const auto& pos = track.at("position_error_m");
  EXPECT_LT(pos.at("rmse").get<double>(), 0.05);
  EXPECT_LT(pos.at("max").get<double>(), 0.15);
  EXPECT_LT(track.at("heading_error_rad").at("rmse").get<double>(), 0.03);
  const double nees = track.at("nees_xytheta").at("mean").get<double>();
  EXPECT_GT(nees, 1.5);
  EXPECT_LT(nees, 6.0);
  // Gate statistics per sensor: landmarks and beacons both seen and nearly all accepted.
  int sensors = 0;
  for (const auto& g : r.at("gate").at("by_filter_sensor")) {
    const std::string s = g.at("sensor");
    if (s != "LANDMARKS" && s != "BEACONS") continue;
    ++sensors;
    EXPECT_GT(g.at("accepted").get<double>(), 0.95 * g.at("decisions").get<double>()) << s;
  }
  EXPECT_EQ(sensors, 2);
  fs::remove_all(out);
}
