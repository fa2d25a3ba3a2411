// The layers of lib/ (docs/architecture.md), checked on the source tree: core includes only
// Eigen and the standard library (no clock, no middleware); sim, bus and logio include the core
// and themselves, never each other nor anything above; app includes core, bus and logio (not the
// simulator) and no program or tool. A layer that includes one above it fails this test. The
// fusion daemon and the logger take nothing from the simulator: lib/app, lib/bus, lib/logio,
// fusion/ and logger/ include nothing of lcmloc/sim (nor of the simulation's config), and
// lcmloc-fusion and lcmloc-logger do not link lcmloc_sim (their link closure, from CMake).
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace fs = std::filesystem;

namespace {

struct Layer {
  std::string name;                        ///< directory under lib/ and lcmloc/<name>/ include prefix
  std::set<std::string> lcmloc_prefixes;   ///< "lcmloc/<x>/" prefixes it may include (its own too)
  bool lcmtypes = false;                   ///< lcmloc/<type>_t.hpp and lcmloc/wire.hpp
  bool only_std_and_eigen = false;         ///< <...> includes: the standard library and Eigen only
  std::vector<std::string> forbidden_system;  ///< <...> include prefixes it may not use
};

const std::vector<Layer>& layers() {
  static const std::vector<Layer> l = {
      {"core", {"core"}, false, true, {}},
      {"sim", {"core", "sim"}, false, true, {}},
      {"bus", {"core", "bus"}, true, false, {"yaml-cpp/", "CLI/"}},
      {"logio", {"core", "logio"}, true, false, {"yaml-cpp/", "CLI/", "Eigen/"}},
      {"app", {"core", "bus", "logio", "app"}, true, false, {}},
  };
  return l;
}

/// Standard headers that read the clock or start threads: not in the deterministic math.
const std::set<std::string> kNoClock = {"chrono", "ctime", "thread", "future"};

bool isStandardHeader(const std::string& h) {
  return h.find('/') == std::string::npos && h.find('.') == std::string::npos && !kNoClock.count(h);
}

/// One include of a source: where ("<dir>/<file>:<line>"), quoted or <...>, the header.
struct Include {
  std::string where;
  bool quoted;
  std::string header;
};

/// Every include of every source (.cpp, .hpp, .h) under root/dir; "<dir>: missing" as the one
/// include's `where` (no header) when there is no such directory.
std::vector<Include> includesUnder(const fs::path& root, const std::string& dir) {
  static const std::regex include_re(R"(^\s*#\s*include\s*([<"])([^>"]+)[>"])");
  if (!fs::is_directory(root / dir)) return {{dir + ": missing", false, ""}};
  std::vector<Include> found;
  for (const auto& entry : fs::recursive_directory_iterator(root / dir)) {
    const std::string ext = entry.path().extension().string();
    if (!entry.is_regular_file() || (ext != ".cpp" && ext != ".hpp" && ext != ".h")) continue;
    std::ifstream in(entry.path());
    std::string line;
    for (int n = 1; std::getline(in, line); ++n) {
      std::smatch m;
      if (std::regex_search(line, m, include_re))
        found.push_back({fs::relative(entry.path(), root).string() + ":" + std::to_string(n), m[1] == "\"", m[2]});
    }
  }
  return found;
}

/// Every include of every source under root/lib that breaks its layer's rule, as
/// "lib/<layer>/<file>:<line>: <include>".
std::vector<std::string> layerViolations(const fs::path& root) {
  static const std::regex lcmtype_re(R"(^lcmloc/([a-z0-9_]+_t|wire)\.hpp$)");
  std::vector<std::string> found;
  for (const Layer& layer : layers()) {
    for (const Include& inc : includesUnder(root, "lib/" + layer.name)) {
      const std::string& h = inc.header;
      if (h.empty()) {  // the layer's directory is missing
        found.push_back(inc.where);
        continue;
      }
      bool ok = false;
      if (inc.quoted) {
        if (h.find('/') == std::string::npos) {
          ok = true;  // a header beside the source, in the same layer
        } else if (std::regex_match(h, lcmtype_re)) {
          ok = layer.lcmtypes;
        } else {
          for (const auto& p : layer.lcmloc_prefixes) ok = ok || h.rfind("lcmloc/" + p + "/", 0) == 0;
        }
      } else if (layer.only_std_and_eigen) {
        ok = isStandardHeader(h) || h.rfind("Eigen/", 0) == 0;
      } else {
        ok = h.rfind("lcmloc/", 0) != 0;
        for (const auto& p : layer.forbidden_system) ok = ok && h.rfind(p, 0) != 0;
      }
      if (!ok) found.push_back(inc.where + ": " + (inc.quoted ? "\"" + h + "\"" : "<" + h + ">"));
    }
  }
  return found;
}

/// The directories whose code takes nothing from the simulator, and what that is.
const std::vector<std::string> kWithoutSimulator = {"lib/app", "lib/bus", "lib/logio", "fusion", "logger"};
const std::vector<std::string> kSimulatorIncludes = {"lcmloc/sim/", "lcmloc/simconfig/", "lcmloc/drivers/"};

/// Every include of the simulator (kSimulatorIncludes) in a source under root/<kWithoutSimulator>,
/// as "<dir>/<file>:<line>: <include>".
std::vector<std::string> simulatorIncludes(const fs::path& root) {
  std::vector<std::string> found;
  for (const std::string& d : kWithoutSimulator) {
    for (const Include& inc : includesUnder(root, d)) {
      if (inc.header.empty()) {  // the directory is missing
        found.push_back(inc.where);
        continue;
      }
      for (const auto& p : kSimulatorIncludes)
        if (inc.header.rfind(p, 0) == 0) found.push_back(inc.where + ": " + inc.header);
    }
  }
  return found;
}

/// The libraries of a comma-separated link closure (tests/layers/CMakeLists.txt).
std::set<std::string> links(const std::string& closure) {
  std::set<std::string> out;
  std::size_t start = 0;
  for (std::size_t end; start <= closure.size(); start = end + 1) {
    end = closure.find(',', start);
    if (end == std::string::npos) end = closure.size();
    if (end > start) out.insert(closure.substr(start, end - start));
  }
  return out;
}

/// The file names of found lines ("<dir>/<file>:<line>: ..."), one each.
std::set<std::string> fileNames(const std::vector<std::string>& found) {
  std::set<std::string> files;
  for (const auto& s : found) files.insert(fs::path(s.substr(0, s.find(':'))).filename().string());
  return files;
}

std::string lines(const std::vector<std::string>& found) {
  std::string all;
  for (const auto& s : found) all += s + "\n";
  return all;
}

/// An empty tree lcmloc_<name>_<pid> in the temporary directory, with the directories dirs.
fs::path scratchTree(const std::string& name, const std::vector<std::string>& dirs) {
  const fs::path root = fs::temp_directory_path() / ("lcmloc_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(root);
  for (const auto& d : dirs) fs::create_directories(root / d);
  return root;
}

void writeFile(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

}  // namespace

TEST(Layers, NoLibraryIncludesALayerAboveIt) {
  const std::vector<std::string> v = layerViolations(LCMLOC_SOURCE_DIR);
  EXPECT_TRUE(v.empty()) << lines(v);
}

TEST(Layers, TheCheckFindsEachKindOfViolation) {
  std::vector<std::string> dirs;
  for (const auto& l : layers()) dirs.push_back("lib/" + l.name);
  const fs::path root = scratchTree("layers", dirs);
  // Allowed: the layer's own headers, the core, Eigen, the standard library, lcmtypes in bus.
  writeFile(root / "lib/core/src/a.cpp", "#include \"lcmloc/core/a.hpp\"\n#include <Eigen/Core>\n#include <vector>\n");
  writeFile(root / "lib/sim/src/b.cpp", "#include \"lcmloc/core/a.hpp\"\n#include \"lcmloc/sim/b.hpp\"\n");
  writeFile(root / "lib/bus/src/c.cpp", "#include \"lcmloc/pose_t.hpp\"\n#include <lcm/lcm-cpp.hpp>\n");
  EXPECT_TRUE(layerViolations(root).empty());
  // Not allowed: each of these is one violation.
  writeFile(root / "lib/core/src/d.cpp", "#include <lcm/lcm-cpp.hpp>\n");         // middleware in core
  writeFile(root / "lib/core/src/e.cpp", "#include <chrono>\n");                  // a clock in core
  writeFile(root / "lib/core/src/f.cpp", "#include \"lcmloc/pose_t.hpp\"\n");     // lcmtypes in core
  writeFile(root / "lib/sim/src/g.cpp", "#include \"lcmloc/bus/convert.hpp\"\n"); // sim -> bus
  writeFile(root / "lib/bus/src/h.cpp", "#include \"lcmloc/sim/world.hpp\"\n");   // bus -> sim
  writeFile(root / "lib/logio/src/i.hpp", "  #  include \"lcmloc/app/config.hpp\"\n");  // logio -> app
  writeFile(root / "lib/app/src/j.cpp", "#include \"lcmloc/replay/replay.hpp\"\n");  // app -> a tool
  writeFile(root / "lib/bus/src/k.cpp", "#include <yaml-cpp/yaml.h>\n");          // configuration in bus
  writeFile(root / "lib/app/src/l.cpp", "#include \"lcmloc/sim/world.hpp\"\n");   // app -> the simulator
  const std::vector<std::string> v = layerViolations(root);
  EXPECT_EQ(v.size(), 9u) << lines(v);
  EXPECT_EQ(fileNames(v), (std::set<std::string>{"d.cpp", "e.cpp", "f.cpp", "g.cpp", "h.cpp", "i.hpp", "j.cpp", "k.cpp", "l.cpp"}));
  fs::remove_all(root);
}

TEST(Layers, TheDaemonAndTheLoggerIncludeNothingOfTheSimulator) {
  const std::vector<std::string> v = simulatorIncludes(LCMLOC_SOURCE_DIR);
  EXPECT_TRUE(v.empty()) << lines(v);
}

TEST(Layers, TheSimulatorCheckFindsAnIncludeOfIt) {
  const fs::path root = scratchTree("nosim", kWithoutSimulator);
  writeFile(root / "fusion/daemon/a.cpp", "#include \"lcmloc/app/config.hpp\"\n#include \"lcmloc/core/engine.hpp\"\n");
  EXPECT_TRUE(simulatorIncludes(root).empty());
  writeFile(root / "fusion/daemon/b.cpp", "#include \"lcmloc/sim/world.hpp\"\n");               // daemon -> sim
  writeFile(root / "logger/c.hpp", "  # include <lcmloc/simconfig/sim_config.hpp>\n");          // logger -> sim config
  writeFile(root / "lib/app/src/d.cpp", "#include \"lcmloc/sim/scenario_config.hpp\"\n");      // app -> sim
  writeFile(root / "lib/bus/src/e.cpp", "#include \"lcmloc/drivers/sim_convert.hpp\"\n");      // bus -> drivers
  const std::vector<std::string> v = simulatorIncludes(root);
  EXPECT_EQ(v.size(), 4u) << lines(v);
  EXPECT_EQ(fileNames(v), (std::set<std::string>{"b.cpp", "c.hpp", "d.cpp", "e.cpp"}));
  fs::remove_all(root);
}

// The link closures CMake computed for the programs: lcmloc-fusion and lcmloc-logger link the
// libraries below them, not the simulator; lcmloc-sim (the simulated world's driver) does, which
// shows that the closure reaches the simulator where it is linked.
TEST(Layers, TheDaemonAndTheLoggerDoNotLinkTheSimulator) {
  const auto fusion = links(LCMLOC_FUSION_LINKS), logger = links(LCMLOC_LOGGER_LINKS);
  EXPECT_TRUE(fusion.count("lcmloc_app") && fusion.count("lcmloc_core") && fusion.count("lcmloc_bus")) << LCMLOC_FUSION_LINKS;
  EXPECT_TRUE(logger.count("lcmloc_app") && logger.count("lcmloc_logio")) << LCMLOC_LOGGER_LINKS;
  for (const char* sim : {"lcmloc_sim", "lcmloc_simconfig", "lcmloc_drivers"}) {
    EXPECT_EQ(fusion.count(sim), 0u) << sim << " in lcmloc-fusion's " << LCMLOC_FUSION_LINKS;
    EXPECT_EQ(logger.count(sim), 0u) << sim << " in lcmloc-logger's " << LCMLOC_LOGGER_LINKS;
  }
  const auto driver = links(LCMLOC_SIM_DRIVER_LINKS);
  EXPECT_EQ(driver.count("lcmloc_sim"), 1u) << LCMLOC_SIM_DRIVER_LINKS;
  EXPECT_EQ(driver.count("lcmloc_simconfig"), 1u) << LCMLOC_SIM_DRIVER_LINKS;
}
