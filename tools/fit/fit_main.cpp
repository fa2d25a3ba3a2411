// lcmloc-fit-noise: measurement and process noise fitted against a log's ground truth, written
// as a config fragment (fusion.filter keys), with the residuals per sensor.
#include <cstdio>
#include <fstream>

#include <spdlog/spdlog.h>

#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/files.hpp"
#include "lcmloc/fit/fit_log.hpp"
#include "lcmloc/fit/report.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-fit-noise: fits the filters' measurement and process noise to a log with ground truth "
               "(residuals of each sensor against the truth; odometry error growth per distance and turn)"};
  common::CommonOptions opts;
  common::addOfflineOptions(app, opts, "system config of the log (channels, datum, map, wheelbase), e.g. the "
                                       "config.yaml lcmloc-import wrote")->required();
  std::string log, out = "out/fit_noise.yaml";
  bool overwrite = false;
  app.add_option("log", log, "LCM log with a ground truth")->required();
  common::addOutputOption(app, out, "the fitted config fragment (YAML)")->capture_default_str();
  common::addOverwriteFlag(app, overwrite);
  return common::runProcess(app, argc, argv, opts, "lcmloc-fit-noise", [&] {
    common::requireInputFile(log, "input log");
    const auto cfg = common::loadSystemConfig(opts.config);
    common::refuseExistingOutput(out, overwrite);
    const auto read = fit::readRecording(log, cfg);
    const auto f = fit::fitAgainstTruth(read.recording);
    fit::printFit(f, read);
    std::ofstream(out) << fit::configFragment(f, read.recording.pw_distance);
    std::printf("wrote %s\n", out.c_str());
    return read.damaged ? common::kExitInputDamaged : common::kExitOk;
  });
}
