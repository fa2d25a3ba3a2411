// The fusion daemon reads its map from a file only. A simulated run's map file is the
// simulator's world written out (lcmloc-sim --write-map): every shipped config whose world has
// markers names a map file that holds exactly those markers, and a map written and read back is
// the same map, bit for bit (so a replay with the file computes what one with the world would).
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include <gtest/gtest.h>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/csv.hpp"
#include "lcmloc/drivers/scenario_map.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

using namespace lcmloc;
namespace fs = std::filesystem;

namespace {

void expectSameMap(const core::MarkerMap& got, const core::MarkerMap& want, const std::string& what) {
  ASSERT_EQ(got.size(), want.size()) << what;
  for (std::size_t i = 0; i < want.size(); ++i) {
    EXPECT_EQ(got[i].id, want[i].id) << what << " marker " << i;
    EXPECT_EQ(got[i].x, want[i].x) << what << " marker " << i;  // exactly: no rounding on the way
    EXPECT_EQ(got[i].y, want[i].y) << what << " marker " << i;
  }
}

}  // namespace

TEST(ScenarioMap, AMapWrittenAndReadBackIsTheSameBitForBit) {
  const core::MarkerMap map = {{0, 0.1 + 0.2, 1.0 / 3.0},
                               {1, -1e-17, 123456.78901234567},
                               {7, std::nextafter(2.0, 3.0), -std::numeric_limits<double>::min()},
                               {9, 314.15926535897932, 5e300}};
  const std::string file = (fs::temp_directory_path() / ("lcmloc_map_" + std::to_string(::getpid()) + ".csv")).string();
  common::csv::writeMap(file, map);
  expectSameMap(common::csv::loadMap(file), map, "round trip");
  fs::remove(file);
}

TEST(ScenarioMap, EveryShippedConfigWithMarkersNamesTheMapOfItsWorld) {
  int checked = 0;
  for (const std::string dir : {LCMLOC_SOURCE_DIR "/config", LCMLOC_SOURCE_DIR "/tests/data", LCMLOC_SOURCE_DIR "/tests/data/golden"}) {
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string file = entry.path().filename().string();
    // (the launcher's system files list processes: no world of their own)
    if (entry.path().extension() != ".yaml" || (file.size() >= 11 && file.substr(file.size() - 11) == "system.yaml"))
      continue;
    const common::SimSystemConfig cfg = common::loadSimSystemConfig(entry.path().string());
    const core::MarkerMap world = common::scenarioMap(cfg);
    if (world.empty()) continue;
    const std::string& name = file;
    ASSERT_FALSE(cfg.fusion.map_file.empty()) << name << ": markers in the world, no fusion.map_file";
    expectSameMap(common::csv::loadMap(cfg.fusion.map_file), world, name + ": " + cfg.fusion.map_file);
    ++checked;
  }
  }
  EXPECT_GE(checked, 4);  // paper.yaml, oval.yaml, the evaluation's straight world and the ruler golden at least
}
