// lcmloc-launcher: starts, watches and stops the processes of a system file (launcher.hpp).
#include "launcher.hpp"
#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/files.hpp"
#include "lcmloc/app/signals.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  // Before anything else: a SIGTERM right after start-up is an orderly stop (exit 0), not the
  // default action's death, nor a failed start.
  app::installSignalHandlers();
  CLI::App app{"lcmloc-launcher: starts, watches (heartbeats; starting again those with `restart: N` that crash or "
               "hang) and stops the processes of a system file.\n"
               "A udpm:// URL without recv_buf_size gets the system file's recv_buf_size (default 4194304) for "
               "every child; a child silent for heartbeat_timeout (default 3 s) is stopped as hung; a child with "
               "`critical: false` that fails is reported and the others keep running (exit status 1 at the end); a status "
               "table every status_period (10 s); `lcmloc-ctl proc stop|start|restart NAME` on control_channel."};
  app::CommonOptions opts;
  opts.config = "-";  // placeholder: the system file names the scenario unless --config is given
  app::addCommonOptions(app, opts);
  app.get_option("--config")->description("scenario YAML for every child (default: the system file's `scenario`)");
  app.get_option("--lcm-url")
      ->description("LCM provider URL for the launcher and every child (default: $LCM_DEFAULT_URL or udpm); a "
                    "udpm:// URL without recv_buf_size gets the system file's recv_buf_size");
  std::string system = app::configDir() + "/system.yaml";
  app.add_option("--system", system, "system file: processes to run")->capture_default_str();

  return app::runProcess(app, argc, argv, opts, "lcmloc-launcher", [&] {
    return launcher::launch(system, opts.config != "-" ? opts.config : "", opts.lcm_url);
  });
}
