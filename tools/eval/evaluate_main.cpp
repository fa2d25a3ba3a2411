// lcmloc-evaluate: scores the estimates recorded in any log (POSE, optionally every POSE_*)
// against the ground truth recorded with them: position / heading / drift errors, NEES against
// its chi-square bounds, gate statistics from GATE; writes report.json, PNG figures and, on
// request, TUM trajectory files for the evo tools (lcmloc/eval/evaluate_command.hpp).
#include <CLI/CLI.hpp>

#include "lcmloc/app/cli.hpp"
#include "lcmloc/eval/evaluate_command.hpp"

int main(int argc, char** argv) {
  using namespace lcmloc;
  CLI::App app{"lcmloc-evaluate: scores the estimates recorded in an LCM log (pose_t) against the ground truth "
               "recorded with them: position, heading and drift errors, NEES against its chi-square bounds, gate "
               "statistics; writes report.json, PNG figures and TUM files (docs/evaluate.md). Exit: 0 done, 1 nothing "
               "to evaluate, 2 bad options or config, 3 done from a damaged log (its intact events; each damaged "
               "place reported), or nothing to evaluate in a damaged, empty or not-a-log file."};
  eval::EvaluateCommand command;
  app::CommonOptions opts;
  eval::addEvaluateOptions(app, command);
  app::addOfflineOptions(app, opts,
                            "system config (YAML): its channels.pose, channels.ground_truth, channels.gate and "
                            "datum are the defaults of --pose-channel, --truth-channel, --gate-channel and --datum");
  return app::runProcess(app, argc, argv, opts, "lcmloc-evaluate", [&] {
    command.config_path = opts.config;
    return eval::runEvaluate(command);
  });
}
