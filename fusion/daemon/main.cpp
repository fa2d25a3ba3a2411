// lcmloc-fusion: the fusion daemon (see daemon.hpp).
#include <spdlog/spdlog.h>

#include "daemon.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-fusion: fusion daemon, ODOMETRY + MAGRULER* + IMU + GPS + FUSION_CONTROL -> POSE, GATE, FUSION_STATUS"};
  common::CommonOptions opts;
  common::addCommonOptions(app, opts);
  std::string filter;
  app.add_option("--filter", filter, "override fusion.filter.type (dead_reckoning, ukf, ukf_gated, ukf_calib, tvekf, ukf_gps)");

  return common::runProcess(app, argc, argv, opts, "lcmloc-fusion", [&] {
    auto cfg = common::loadSystemConfig(opts.config);
    if (!filter.empty()) {
      YAML::Node n;
      n["type"] = filter;
      cfg.fusion.filter = common::parseFilterConfig(n, cfg.fusion.filter, "--filter", "fusion.filter");
    }
    common::Bus bus(opts.lcm_url);
    fusion::FusionDaemon daemon(cfg, bus);
    common::Heartbeat hb(bus, cfg.channels.heartbeat, "lcmloc-fusion", [&] { return daemon.counters(); });
    while (!common::stopRequested()) {
      hb.tick();
      bus.handle(100);
    }
    while (bus.handle(0) > 0) {}  // what already arrived is processed too
    daemon.shutdown();
    hb.publish("stopping");
    return common::kExitOk;
  });
}
