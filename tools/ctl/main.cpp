// lcmloc-ctl: sends one FUSION_CONTROL command to the fusion daemon and prints its answer
// (lcmloc/ctl/control.hpp); prints the processes on the bus and stops, starts or restarts one
// under a launcher (lcmloc/ctl/processes.hpp).
#include "lcmloc/app/cli.hpp"
#include "lcmloc/core/filter.hpp"
#include "lcmloc/ctl/control.hpp"
#include "lcmloc/ctl/processes.hpp"
#include "lcmloc/ctl/status.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-ctl: send a command to the fusion daemon (FUSION_CONTROL) and print its answer from "
               "FUSION_STATUS; print the processes on the bus and the daemon's status and timing (status); stop, start or "
               "restart a process under a launcher (proc)."};
  app.footer("lcmloc-ctl's own exit codes: 4 no answer within --timeout, 5 the daemon refused the command "
             "(1: no daemon on the bus; status: no heartbeat on the bus).");
  app::CommonOptions opts;
  app::addCommonOptions(app, opts);
  double timeout = 5.0;
  int64_t utime = -1;
  app.add_option("--timeout", timeout, "[s] to wait for the daemon (its time, then its answer)")
      ->check(lcmloc::app::positive())
      ->check(lcmloc::app::wallSeconds());
  app.add_option("--utime", utime,
                 "message time of the command [us] (default: one reorder window after the newest ODOMETRY, IMU, "
                 "POSE or FUSION_STATUS on the bus)")
      ->check(lcmloc::app::nonNegative());
  app.require_subcommand(1);
  app.fallthrough();  // the options above may come after the subcommand too (set-pose 1 2 0 --timeout 1)

  ctl::Command c;
  auto* sw = app.add_subcommand("switch", "switch the active filter: NAME [--param KEY=VALUE ...]");
  sw->add_option("name", c.filter, "filter type (" + core::filterTypeList() + ")")->required();
  sw->add_option("--param", c.params, "filter parameter KEY=VALUE (dotted keys for nesting: gate.value=6.635)");
  sw->add_option("--params", c.params_yaml, "filter parameters as a YAML flow map, e.g. '{gate: {value: 6.635}}'");
  app.add_subcommand("reset", "reset every filter to the configured initial state");
  auto* sp = app.add_subcommand("set-pose", "re-initialise x [m], y [m], theta [rad]: X Y THETA [--std SX SY STH]");
  sp->add_option("pose", c.pose, "X Y THETA")->expected(3)->required();
  sp->add_option("--std", c.stddev, "1-sigma of x [m], y [m], theta [rad]")->expected(3);

  ctl::ProcessCommands pcs;
  ctl::addProcessCommands(app, pcs);

  return app::runProcess(app, argc, argv, opts, "lcmloc-ctl", [&]() -> int {
    const auto cfg = app::loadSystemConfig(opts.config);
    if (app.got_subcommand(pcs.status)) {  // the processes, then the fusion daemon's status and timing
      const int processes = ctl::status(cfg, opts.lcm_url, pcs.listen);
      const int fusion = ctl::fusionStatus(cfg, opts.lcm_url, timeout);
      return processes == app::kExitOk ? app::kExitOk : fusion;
    }
    if (app.got_subcommand(pcs.proc)) return ctl::proc(cfg, opts.lcm_url, pcs.command, timeout);
    c.kind = app.got_subcommand(sw) ? ctl::Command::Switch
             : app.got_subcommand(sp) ? ctl::Command::SetPose : ctl::Command::Reset;
    return ctl::send(cfg, opts.lcm_url, ctl::makeCommand(c), timeout, utime);
  });
}
