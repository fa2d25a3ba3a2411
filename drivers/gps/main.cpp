// lcmloc-gps: GNSS fixes on the GPS channel, simulated from GROUND_TRUTH or from gpsd
// (gps_driver.hpp).
#include "gps_driver.hpp"
#include "lcmloc/app/cli.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-gps: GNSS fixes on GPS, simulated (from GROUND_TRUTH) or from gpsd"};
  app::CommonOptions opts;
  app::addCommonOptions(app, opts);
  std::string source, host, port;
  app.add_option("--source", source, "override gps.source (sim, gpsd)")->check(CLI::IsMember({"sim", "gpsd"}));
  app.add_option("--gpsd-host", host, "override gps.gpsd_host");
  app.add_option("--gpsd-port", port, "override gps.gpsd_port");

  return app::runProcess(app, argc, argv, opts, "lcmloc-gps", [&] {
    auto cfg = simconfig::loadSimSystemConfig(opts.config);
    if (!source.empty()) cfg.gps_driver.source = source;
    if (!host.empty()) cfg.gps_driver.gpsd_host = host;
    if (!port.empty()) cfg.gps_driver.gpsd_port = port;
    bus::Bus bus(opts.lcm_url);
    return gps::run(cfg, bus);
  });
}
