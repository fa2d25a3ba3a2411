// lcmloc-preflight: checks the LCM set-up of this host before the system starts, or while it
// runs (preflight.hpp).
#include <iostream>

#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/config.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "preflight.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-preflight: checks the LCM set-up of this host: the multicast route and ttl of the URL, "
               "net.core.rmem_max against the URL's recv_buf_size, LCM's self-test; then listens: a publisher on "
               "each --expect channel, and the clock offset of every host whose HEARTBEAT it hears. Each problem "
               "comes with what to do (docs/network.md)."};
  app.footer("lcmloc-preflight's own exit code: 4 a check failed (warnings do not fail).");
  app::CommonOptions opts;
  app::addCommonOptions(app, opts);
  preflight::Options po;
  app.add_flag("--multi-host", po.multi_host, "the system spans hosts: ttl=0 or a route via lo fail");
  app.add_option("--expect", po.expect, "channels that must have a publisher within --listen (comma-separated)")
      ->delimiter(',');
  app.add_option("--listen", po.listen, "[s] to listen for the expected channels and heartbeats; 0 = no listening")
      ->check(app::nonNegative())
      ->check(app::wallSeconds())
      ->capture_default_str();
  app.add_option("--max-clock-offset", po.max_clock_offset, "[s] largest clock offset of a host against this one")
      ->check(app::positive())
      ->capture_default_str();
  app.add_option("--rmem-max-file", po.rmem_max_file,
                 "where net.core.rmem_max is read (a test points it elsewhere: the value is the host's, not a "
                 "network namespace's)")
      ->capture_default_str();

  return app::runProcess(app, argc, argv, opts, "lcmloc-preflight", [&] {
    const auto cfg = app::loadSystemConfig(opts.config);
    po.url = opts.lcm_url;
    po.heartbeat_channel = cfg.channels.heartbeat;
    const auto findings = preflight::runAll(po);
    std::cout << preflight::format(findings) << std::flush;
    const bool failed = std::any_of(findings.begin(), findings.end(),
                                    [](const auto& f) { return f.level == preflight::Finding::Fail; });
    return failed ? preflight::kExitCheckFailed : app::kExitOk;
  });
}
