// The layers of lib/ (docs/architecture.md), checked on the source tree: core includes only
// Eigen and the standard library (no clock, no middleware); sim, bus and logio include the core
// and themselves, never each other nor anything above; app includes the libraries below it and
// no program or tool. A layer that includes one above it fails this test.
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
      {"app", {"core", "sim", "bus", "logio", "app"}, true, false, {}},
  };
  return l;
}

/// Standard headers that read the clock or start threads: not in the deterministic math.
const std::set<std::string> kNoClock = {"chrono", "ctime", "thread", "future"};

bool isStandardHeader(const std::string& h) {
  return h.find('/') == std::string::npos && h.find('.') == std::string::npos && !kNoClock.count(h);
}

/// Every include of every source under root/lib that breaks its layer's rule, as
/// "lib/<layer>/<file>:<line>: <include>".
std::vector<std::string> layerViolations(const fs::path& root) {
  static const std::regex include_re(R"(^\s*#\s*include\s*([<"])([^>"]+)[>"])");
  static const std::regex lcmtype_re(R"(^lcmloc/([a-z0-9_]+_t|wire)\.hpp$)");
  std::vector<std::string> found;
  for (const Layer& layer : layers()) {
    const fs::path dir = root / "lib" / layer.name;
    if (!fs::is_directory(dir)) {
      found.push_back("lib/" + layer.name + ": missing");
      continue;
    }
    for (const auto& entry : fs::recursive_directory_iterator(dir)) {
      const std::string ext = entry.path().extension().string();
      if (!entry.is_regular_file() || (ext != ".cpp" && ext != ".hpp" && ext != ".h")) continue;
      std::ifstream in(entry.path());
      std::string line;
      for (int n = 1; std::getline(in, line); ++n) {
        std::smatch m;
        if (!std::regex_search(line, m, include_re)) continue;
        const bool quoted = m[1] == "\"";
        const std::string h = m[2];
        bool ok = false;
        if (quoted) {
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
        if (!ok)
          found.push_back(fs::relative(entry.path(), root).string() + ":" + std::to_string(n) + ": " +
                          (quoted ? "\"" + h + "\"" : "<" + h + ">"));
      }
    }
  }
  return found;
}

void writeFile(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

}  // namespace

TEST(Layers, NoLibraryIncludesALayerAboveIt) {
  const std::vector<std::string> v = layerViolations(LCMLOC_SOURCE_DIR);
  std::string all;
  for (const auto& s : v) all += s + "\n";
  EXPECT_TRUE(v.empty()) << all;
}

TEST(Layers, TheCheckFindsEachKindOfViolation) {
  const fs::path root = fs::temp_directory_path() / ("lcmloc_layers_" + std::to_string(::getpid()));
  fs::remove_all(root);
  for (const auto& l : layers()) fs::create_directories(root / "lib" / l.name);
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
  const std::vector<std::string> v = layerViolations(root);
  EXPECT_EQ(v.size(), 8u);
  std::set<std::string> files;
  for (const auto& s : v) files.insert(fs::path(s.substr(0, s.find(':'))).filename().string());
  EXPECT_EQ(files, (std::set<std::string>{"d.cpp", "e.cpp", "f.cpp", "g.cpp", "h.cpp", "i.hpp", "j.cpp", "k.cpp"}));
  fs::remove_all(root);
}
