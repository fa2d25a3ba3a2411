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
  app::CommonOptions opts;
  app::addOfflineOptions(app, opts, "system config of the log (channels, datum, map, wheelbase), e.g. the "
                                       "config.yaml lcmloc-import wrote")->required();
  std::string log, out = "out/fit_noise.yaml";
  bool overwrite = false;
  app.add_option("log", log, "LCM log with a ground truth")->required();
  app::addOutputOption(app, out, "the fitted config fragment (YAML)")->capture_default_str();
  app::addOverwriteFlag(app, overwrite);
  return app::runProcess(app, argc, argv, opts, "lcmloc-fit-noise", [&] {
    app::requireInputFile(log, "input log");
    const auto cfg = app::loadSystemConfig(opts.config);
    app::refuseExistingOutput(out, overwrite);
    const auto read = fit::readRecording(log, cfg);
    const auto f = fit::fitAgainstTruth(read.recording);
    fit::printFit(f, read);
    std::ofstream(out) << fit::configFragment(f, read.recording.pw_distance);
    std::printf("wrote %s\n", out.c_str());
    return read.damaged ? app::kExitInputDamaged : app::kExitOk;
  });
}
