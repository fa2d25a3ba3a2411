// Fuzz target: the configuration readers. Byte 0 picks the reader, the rest is its text:
//   0  a system file with its simulation sections (parseSimSystemConfig), then the fusion
//      daemon made from it (engineConfig, the map file, the engine);
//   1  a system file as the daemon and the logger read it (parseSystemConfig), then the daemon;
//   2  filter parameters (a FUSION_CONTROL command's parameters, parseFilterConfig);
//   3  a map file (app::csv::loadMap: id,x,y);
//   4  a launcher's system file (lcmloc-launcher: loadLaunchConfig).
// For 0, 1 and 4, the text after a NUL byte, if any, is a second file next to the first: for 0
// and 1 map.csv (fusion.map_file: map.csv reads it), for 4 scenario.yaml (scenario:
// scenario.yaml reads it).
#include <algorithm>
#include <cstdint>
#include <exception>
#include <string>

#include "daemon/daemon.hpp"
#include "fuzz_util.hpp"
#include "lcmloc/app/config.hpp"
#include "lcmloc/app/csv.hpp"
#include "lcmloc/bus/memory_bus.hpp"
#include "lcmloc/simconfig/sim_config.hpp"
#include "launch_config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  using namespace lcmloc;
  static const bool kQuiet = (fuzz::quiet(), true);
  (void)kQuiet;
  if (size < 1) return 0;
  const uint8_t mode = data[0] % 5;
  const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
  try {
    const auto nul = text.find('\0');
    const std::string first = text.substr(0, nul);
    const std::string second = nul == std::string::npos ? "" : text.substr(nul + 1);
    const auto* second_bytes = reinterpret_cast<const uint8_t*>(second.data());
    if (mode == 0 || mode == 1) {
      const std::string& yaml = first;
      fuzz::writeFile("map.csv", second_bytes, second.size());
      const std::string file = (fuzz::scratchDir() / "system.yaml").string();
      const app::SystemConfig cfg = mode == 0 ? simconfig::parseSimSystemConfig(yaml, file)
                                              : app::parseSystemConfig(yaml, file);
      bus::MemoryBus bus;
      fusion::FusionDaemon daemon(cfg, bus);
      daemon.shutdown();
    } else if (mode == 2) {
      const YAML::Node node = app::parseYamlText(text, "FUSION_CONTROL");
      app::parseFilterConfig(node, core::FilterConfig{}, "FUSION_CONTROL", "parameters.");
    } else if (mode == 3) {
      const std::string path = fuzz::writeFile("map.csv", data + 1, size - 1);
      app::csv::loadMap(path);
    } else {
      fuzz::writeFile("scenario.yaml", second_bytes, second.size());
      launcher::loadLaunchConfig(fuzz::writeFile("system.yaml", reinterpret_cast<const uint8_t*>(first.data()), first.size()));
    }
  } catch (const std::exception& e) {
    fuzz::refused(e);
  }
  return 0;
}
