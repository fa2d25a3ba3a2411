// lcmloc-fit-noise: measurement and process noise fitted to a log, written as a config fragment
// (fusion.filter keys): against the ground truth when the log has one (the residuals per
// sensor), else to the filter's innovations; with each sensor's NIS against its chi-square band.
#include <cstdio>
#include <fstream>

#include <spdlog/spdlog.h>

#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/files.hpp"
#include "lcmloc/fit/fit_log.hpp"
#include "lcmloc/fit/innovation_fit.hpp"
#include "lcmloc/fit/report.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-fit-noise: fits the filters' noise to a log: against its ground truth when it has one "
               "(residuals of each sensor; odometry error growth per distance and turn), else to the filter's "
               "innovations (tvekf and ukf_gps: gnss.position_rw to the fixes' prediction error; then each sensor's "
               "sigma scaled until its median NIS is the chi-square median); prints "
               "each sensor's NIS against its 95 % band"};
  app::CommonOptions opts;
  app::addOfflineOptions(app, opts, "system config of the log (channels, datum, map, wheelbase, filter), e.g. the "
                                       "config.yaml lcmloc-import wrote")->required();
  std::string log, out = "out/fit_noise.yaml";
  bool overwrite = false, innovations = false;
  app.add_option("log", log, "LCM log")->required();
  app.add_flag("--innovations", innovations, "fit to the innovations even when the log has a ground truth");
  app::addOutputOption(app, out, "the fitted config fragment (YAML)")->capture_default_str();
  app::addOverwriteFlag(app, overwrite);
  return app::runProcess(app, argc, argv, opts, "lcmloc-fit-noise", [&] {
    app::requireInputFile(log, "input log");
    const auto cfg = app::loadSystemConfig(opts.config);
    app::refuseExistingOutput(out, overwrite);
    const auto read = fit::readRecording(log, cfg);
    const fit::Recording& r = read.recording;
    const auto text = (r.truth.empty() || innovations) ? fit::innovationFitReport(read, cfg)
                                                        : fit::truthFitReport(read, cfg);
    std::ofstream(out) << text;
    std::printf("wrote %s\n", out.c_str());
    return read.damaged ? app::kExitInputDamaged : app::kExitOk;
  });
}
