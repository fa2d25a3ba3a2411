// lcmloc-latency-bench: the fusion daemon's latency at nominal input rates beside a raw LCM relay,
// its CPU beside a bare subscriber, its RSS (latency_bench.hpp).
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iostream>

#include "lcmloc/app/cli.hpp"
#include "latency_bench.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-latency-bench: runs lcmloc-fusion at nominal rates (100 Hz ODOMETRY and IMU, 10 Hz GPS, "
               "5 Hz MAGRULER) on a udpm URL beside a raw LCM relay, and reports p50/p99/max latency of "
               "POSE_CONTROL, POSE and the relay, the daemon's CPU beside a bare subscriber, and its RSS."};
  app::CommonOptions opts;
  app::addCommonOptions(app, opts);
  latency::BenchOptions o;
  std::error_code ec;
  o.fusion = (std::filesystem::read_symlink("/proc/self/exe", ec).parent_path() / "lcmloc-fusion").string();
  app.add_option("--fusion", o.fusion, "the lcmloc-fusion executable")->capture_default_str();
  app.add_option("--filter", o.filter, "the daemon's --filter (default: the configuration's)");
  app.add_option("--url", o.lcm_url, "udpm URL of the run (ttl=0: this host only)")->capture_default_str();
  app.add_option("--duration", o.duration_s, "[s, wall] measured")->capture_default_str()->check(app::positive());
  app.add_option("--warmup", o.warmup_s, "[s, wall] before, not measured")->capture_default_str()
      ->check(app::nonNegative());
  app::addOutputOption(app, o.report, "JSON report file");
  app.footer("--lcm-url is not used: the run is on --url, its own group and port, not the system's bus.");

  return app::runProcess(app, argc, argv, opts, "lcmloc-latency-bench", [&] {
    o.config = opts.config;
    const auto r = latency::run(o);
    std::cout << latency::toText(r);
    if (!o.report.empty()) std::ofstream(o.report) << latency::toJson(o, r);
    return 0;
  });
}
