// lcmloc-hostile-run: the default system under lcmloc-launcher with a second publisher sending
// bad messages (hostile) or with a fraction of its input messages corrupted (soak); a report of
// the pose's accuracy, continuity and finiteness, and the daemon's memory (commands.hpp).
#include <filesystem>
#include <iostream>

#include "commands.hpp"
#include "lcmloc/app/cli.hpp"
#include "lcmloc/app/files.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{"lcmloc-hostile-run: runs the default magnetic system under lcmloc-launcher on its own LCM URL and "
               "disturbs it. `hostile`: once clean, once with a second publisher sending each kind of bad message "
               "on every input channel at times near the live time; checks RMSE within 2x of the clean run, POSE "
               "never silent for more than twice its period, no NaN, each channel's second publisher named on the "
               "status. `soak`: a long run with a fraction of the input messages corrupted at random; reports the "
               "daemon's RSS and checks no NaN and no POSE gap. Exit 1 when a check fails (docs/hostile_run.md)."};
  app::CommonOptions opts;
  app::addCommonOptions(app, opts);
  hostile::CommandOptions c;
  c.run.bin_dir = std::filesystem::read_symlink("/proc/self/exe").parent_path().string();
  c.run.system = app::configDir() + "/system.yaml";
  app.add_option("--bin-dir", c.run.bin_dir, "where lcmloc-launcher and the processes are")->capture_default_str();
  app.add_option("--system", c.run.system, "the launcher's system file")->capture_default_str();
  app.add_option("--factor", c.run.factor, "real-time factor (the reorder window and time-jump guard scaled by it)")
      ->capture_default_str()->check(app::positive());
  app.add_option("--seed", c.run.seed, "seed of the disturber's choices")->capture_default_str()->check(app::seed());
  app.add_option("--report", c.report, "report file (JSON; default OUTPUT/report.json)");
  std::string out_dir;
  double duration = 600, fraction = 0.01;
  app.add_option("-o,--output", out_dir, "output directory (default out/hostile, out/soak)");
  app.add_option("--rate", c.run.hostile_rate, "hostile: messages per second (each copy of a flood counts)")
      ->capture_default_str()->check(app::positive());
  app.add_flag("--first", c.run.hostile_first, "hostile: on the odometry's and the ruler's channels, send from the "
               "start, not once the system's own stream is there (the hostile publisher may come first)");
  app.add_option("--duration", duration, "soak: [s, wall] run length")->capture_default_str()
      ->check(app::positive() & app::wallSeconds());
  app.add_option("--corrupt", fraction, "soak: fraction of the input messages corrupted")->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.require_subcommand(1);
  auto* hostile = app.add_subcommand("hostile", "clean run, then hostile run (default scenario: --config)");
  auto* soak = app.add_subcommand("soak", "a long run with corrupted input messages (default scenario: oval.yaml, "
                                          "laps enough for --duration)");
  hostile->fallthrough();
  soak->fallthrough();

  return app::runProcess(app, argc, argv, opts, "lcmloc-hostile-run", [&] {
    c.run.lcm_url = opts.lcm_url;
    c.run.scenario = opts.config;
    if (*soak) {
      if (app.get_option("--config")->count() == 0) c.run.scenario = app::configDir() + "/oval.yaml";
      c.run.out_dir = out_dir.empty() ? "out/soak" : out_dir;
      c.run.duration_s = duration;
      c.run.corrupt_fraction = fraction;
      c.run.laps = 0;
      return hostile::soakCommand(c);
    }
    c.run.out_dir = out_dir.empty() ? "out/hostile" : out_dir;
    return hostile::hostileCommand(c);
  });
}
