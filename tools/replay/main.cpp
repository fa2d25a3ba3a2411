// lcmloc-replay: offline replay of an LCM log through the fusion daemon's code (replay.hpp,
// command.hpp), or (--bench) the replay throughput benchmark on a long synthetic log (bench.hpp).
#include "lcmloc/app/cli.hpp"
#include "lcmloc/replay/command.hpp"
#include "lcmloc/simconfig/sim_config.hpp"

using namespace lcmloc;

int main(int argc, char** argv) {
  CLI::App app{
      "lcmloc-replay: replays an LCM log offline (no network) through the fusion daemon's code and writes the "
      "daemon's outputs (POSE, POSE_<TYPE>, GATE, FUSION_STATUS) to an output log, byte-identical to what the "
      "daemon publishes live. A damaged input log is replayed up to and past the damage, each damaged place "
      "reported (exit 3)."};
  app::CommonOptions opts;
  app::addCommonOptions(app, opts);
  replay::CommandOptions o;
  replay::BenchOptions& bo = o.bench_options;
  app.add_option("log", o.input, "input LCM log file");
  app::addOutputOption(app, o.output, "output LCM log (the daemon's outputs)");
  app::addOverwriteFlag(app, o.overwrite);
  app.add_option("--filter", o.filter, "override fusion.filter.type (" + core::filterTypeList() + ")");
  auto* o_shadow =
      app.add_option("--shadow", o.shadow, "override fusion.shadow: comma-separated filter types (POSE_<TYPE>)");
  app.add_flag("--no-shadow", o.no_shadow, "run no shadow filters")->excludes(o_shadow);
  app.add_flag("--with-inputs", o.with_inputs,
               "copy the input events to the output too (all but the old outputs, HEARTBEAT and LCM_SELF_TEST)");
  app.add_flag("--control", o.control,
               "write the control pose too (channels.pose_control, POSE_CONTROL), as the daemon published it live "
               "given the log's event order as the order of arrival");
  app.add_flag("--one-thread", o.one_thread,
               "read the log and apply it in one thread (by default a second thread reads, decodes and validates "
               "ahead); the output is the same either way");
  app.add_option("--progress", o.progress_s, "[s, wall] between progress lines; 0 = none")
      ->capture_default_str()->check(app::wallSeconds());
  app.add_flag("--bench", o.bench,
               "benchmark instead: generate a synthetic log, measure read+decode, dead_reckoning and ukf_gated "
               "replay (messages/s, medians)");
  app.add_option("--bench-duration", bo.duration_s, "[s] message time of the synthetic log (at most a day)")
      ->capture_default_str()->check(app::positive())
      ->check(CLI::Validator(
          [](std::string& s) { return std::stod(s) <= 86400.0 ? std::string() : s + " s is more than a day (86400 s)"; },
          "<= 86400"));
  app.add_option("--bench-reps", bo.repetitions, "repetitions (medians are reported)")
      ->capture_default_str()->check(app::positive());
  app.add_option("--bench-dir", bo.dir, "where the synthetic log and bench.json go")->capture_default_str();
  app.add_flag("--bench-keep-log", bo.keep_log, "reuse the synthetic log of an earlier run if present");
  app.add_option("--bench-output-every", bo.output_every, "fusion.output_every of the batched rows (1 = none)")
      ->capture_default_str()->check(app::positive());
  app.add_option("--bench-case", bo.cases,
                 "measure only these cases (their keys in bench.json, e.g. ukf_gated_output_every_10; repeatable); "
                 "read+decode is measured beside each");
  app.footer("--lcm-url is accepted for uniformity and unused: the replay reads and writes files only.");

  return app::runProcess(app, argc, argv, opts, "lcmloc-replay", [&] {
    return replay::runCommand(replay::applyOverrides(simconfig::loadSimSystemConfig(opts.config), o), o);
  });
}
