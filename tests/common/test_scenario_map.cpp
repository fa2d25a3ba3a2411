// The fusion daemon reads its map from a file only. A simulated run's map file is the
// simulator's world written out (lcmloc-sim --write-map): every shipped config whose world has
// markers names a map file that holds exactly those markers, and a map written and read back is
// the same map, bit for bit (so a replay with the file computes what one with the world would).
#include <unistd.h>

#include <cmath>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <limits>

#include <fmt/format.h>
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
                               {9, 314.15926535897932, 5e300},
                               {10, 315.0, 5e300}};  // (a lone marker there would be far outside the rest)
  const std::string file = (fs::temp_directory_path() / ("lcmloc_map_" + std::to_string(::getpid()) + ".csv")).string();
  app::csv::writeMap(file, map);
  expectSameMap(app::csv::loadMap(file), map, "round trip");
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
    const simconfig::SimSystemConfig cfg = simconfig::loadSimSystemConfig(entry.path().string());
    const core::MarkerMap world = drivers::scenarioMap(cfg);
    if (world.empty()) continue;
    const std::string& name = file;
    ASSERT_FALSE(cfg.fusion.map_file.empty()) << name << ": markers in the world, no fusion.map_file";
    expectSameMap(app::csv::loadMap(cfg.fusion.map_file), world, name + ": " + cfg.fusion.map_file);
    ++checked;
  }
  }
  EXPECT_GE(checked, 4);  // paper.yaml, oval.yaml, the evaluation's straight world and the ruler golden at least
}

namespace {

/// loadMap's error for this file content ("" when it loads).
std::string mapError(const std::string& content, std::string* file_out = nullptr) {
  const std::string file = (fs::temp_directory_path() / ("lcmloc_badmap_" + std::to_string(::getpid()) + ".csv")).string();
  { std::ofstream(file) << content; }
  if (file_out) *file_out = file;
  std::string error;
  try {
    app::csv::loadMap(file);
  } catch (const std::runtime_error& e) {
    error = e.what();
  }
  fs::remove(file);
  return error;
}

/// A road of n markers along y, spacing apart, scaled by s, as map file rows from line 2 on.
std::string roadRows(int n, double spacing, double s) {
  std::string rows;
  for (int i = 0; i < n; ++i) rows += std::to_string(i) + "," + std::to_string(s * 0.1 * (i % 2)) + "," + std::to_string(s * spacing * i) + "\n";
  return rows;
}

}  // namespace

TEST(MapFile, ADuplicateIdNamesTheFileAndBothLines) {
  std::string file;
  const std::string e = mapError("id,x,y\n1,0,0\n2,1,0\n3,2,0\n2,3,0\n3,4,0\n", &file);
  EXPECT_EQ(e, "'" + file + "': line 5: duplicate id 2 (first on line 3)");
}

TEST(MapFile, ANaNOrAnInfinityNamesTheLine) {
  std::string file;
  std::string e = mapError("id,x,y\n1,0,0\n\n2,nan,0\n", &file);
  EXPECT_EQ(e, "'" + file + "': line 4: column 2: not finite: 'nan'");
  e = mapError("id,x,y\n1,0,0\n2,0,-inf\n", &file);
  EXPECT_EQ(e, "'" + file + "': line 3: column 3: not finite: '-inf'");
}

TEST(MapFile, AMarkerFarOutsideTheRestIsRefusedAtAnyScale) {
  // A road of 1000 markers 2 m apart (2 km; spread 500 m): a marker 5 km beyond its end is far
  // (no other within 8 spreads, 4 km); one 3 km beyond is not. The same at a thousand times the
  // scale: "far" comes from the map, not from a length.
  for (const double s : {1.0, 1000.0}) {
    const std::string road = "id,x,y\n" + roadRows(1000, 2.0, s);
    EXPECT_EQ(mapError(road + "1000,0," + std::to_string(s * 5000.0) + "\n"), "") << s;
    std::string file;
    std::size_t third = 0;  // after the header and two rows: the marker on line 4
    for (int i = 0; i < 3; ++i) third = road.find('\n', third) + 1;
    const std::string e = mapError(road.substr(0, third) + "5000,0," + std::to_string(s * 7000.0) + "\n" + road.substr(third), &file);
    EXPECT_EQ(e.rfind("'" + file + "': line 4: marker 5000 at (0, " + fmt::format("{}", s * 7000.0) + ") is far outside the rest", 0), 0u)
        << s << ": " << e;
  }
  // a second group of markers far away is a part of the map, not a marker outside it
  EXPECT_EQ(mapError("id,x,y\n" + roadRows(1000, 2.0, 1.0) + "2000,0,90000\n2001,5,90000\n2002,5,90005\n"), "");
  // a marker at the road's side, a few metres off: inside
  EXPECT_EQ(mapError("id,x,y\n" + roadRows(1000, 2.0, 1.0) + "3000,40,1000\n"), "");
}

TEST(MapFile, TheFarRuleUsesARobustSpread) {
  core::MarkerMap map;
  for (int i = 0; i < 101; ++i) map.push_back({i, 0.0, 2.0 * i});  // 200 m along y, centre (0, 100)
  map.push_back({500, 1e9, 1e9});                                  // a wrong row does not move it
  const app::csv::MapSpread s = app::csv::mapSpread(map);
  EXPECT_EQ(s.cx, 0.0);
  EXPECT_EQ(s.cy, 102.0);
  EXPECT_EQ(s.spread, 52.0);  // the 52nd of the distances 0, 2, 2, 4, 4, ...
  EXPECT_EQ(app::csv::farMarker(map, s), 101);
  map.pop_back();
  EXPECT_EQ(app::csv::farMarker(map, app::csv::mapSpread(map)), -1);
  EXPECT_EQ(app::csv::farMarker({{1, 0, 0}, {2, 1e9, 0}}, app::csv::mapSpread({{1, 0, 0}, {2, 1e9, 0}})), -1);
}
