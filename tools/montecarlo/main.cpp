// lcmloc-montecarlo: runs the scenario N times (seed = base + i) in process with each requested
// filter and writes per-filter lock-out rate, RMSE median / p95, faults and valid markers
// rejected to a JSON report (lcmloc/montecarlo/montecarlo.hpp).
#include <filesystem>

#include <CLI/CLI.hpp>

#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/files.hpp"
#include "lcmloc/montecarlo/montecarlo.hpp"

int main(int argc, char** argv) {
  lcmloc::montecarlo::Options o;
  CLI::App app{"Monte Carlo of the magnetic-ruler scenario: N seeded in-process runs per filter"};
  lcmloc::app::CommonOptions common;
  lcmloc::app::addOfflineOptions(app, common, "system YAML file (default: built-in paper scenario)")
      ->check(CLI::ExistingFile);
  lcmloc::montecarlo::addOptions(app, o);
  return lcmloc::app::runProcess(app, argc, argv, common, "lcmloc-montecarlo", [&] {
    o.config = common.config;
    lcmloc::app::prepareOutputDir(std::filesystem::path(o.out).parent_path().string(), true);  // (the report file itself: --overwrite)
    return lcmloc::montecarlo::run(o);
  });
}
