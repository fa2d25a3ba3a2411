// lcmloc-fusion: the fusion daemon (see daemon.hpp; its process: runner.hpp).
#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/signals.hpp"
#include "lcmloc/bus/transport.hpp"
#include "runner.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-fusion: fusion daemon, ODOMETRY + MAGRULER* + IMU + GPS + LANDMARKS + BEACONS + VISION + "
               "FUSION_CONTROL -> POSE (POSE_<TYPE> for shadows), GATE, FUSION_STATUS"};
  app::CommonOptions opts;
  app::addCommonOptions(app, opts);
  fusion::RunnerOptions ro;
  fusion::addRunnerOptions(app, ro);

  return app::runProcess(app, argc, argv, opts, "lcmloc-fusion", [&] {
    fusion::DaemonRunner runner(opts.config, ro);  // configuration and checkpoint checked first
    bus::Bus bus(opts.lcm_url);
    runner.start(bus);
    while (!app::stopRequested()) runner.step(100);
    return runner.finish();
  });
}
