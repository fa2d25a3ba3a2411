// lcmloc-replay: offline replay of an LCM log through the fusion daemon's code (see replay.hpp),
// or (--bench) the replay throughput benchmark on a long synthetic log.
#include <iostream>
#include <string>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "bench.hpp"
#include "lcmloc/app/process.hpp"
#include "lcmloc/replay/replay.hpp"

using namespace lcmloc;

namespace {

std::string bytes(int64_t n) {
  if (n >= (1 << 20)) return fmt::format("{:.1f} MB", n / 1048576.0);
  if (n >= 1024) return fmt::format("{:.1f} kB", n / 1024.0);
  return fmt::format("{} B", n);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "lcmloc-replay: replays an LCM log offline (no network) through the fusion daemon's code and writes the "
      "daemon's outputs (POSE, POSE_<TYPE>, GATE, FUSION_STATUS) to an output log, byte-identical to what the "
      "daemon publishes live. Exit: 0 ok, 1 error, 2 bad config or arguments, 3 input log damaged (replayed up to and past "
      "the damage, each damaged place reported)."};
  common::CommonOptions opts;
  common::addCommonOptions(app, opts);
  std::string input, output, filter, shadow;
  bool with_inputs = false, no_shadow = false, bench = false, one_thread = false;
  double progress = 2.0;
  replay::BenchOptions bo;
  app.add_option("log", input, "input LCM log file");
  app.add_option("-o,--output", output, "output LCM log (the daemon's outputs)");
  app.add_option("--filter", filter, "override fusion.filter.type (" + core::filterTypeList() + ")");
  auto* o_shadow =
      app.add_option("--shadow", shadow, "override fusion.shadow: comma-separated filter types (POSE_<TYPE>)");
  app.add_flag("--no-shadow", no_shadow, "run no shadow filters")->excludes(o_shadow);
  app.add_flag("--with-inputs", with_inputs,
               "copy the input events to the output too (all but the old outputs, HEARTBEAT and LCM_SELF_TEST)");
  app.add_flag("--one-thread", one_thread,
               "read the log and apply it in one thread (by default a second thread reads, decodes and validates "
               "ahead); the output is the same either way");
  app.add_option("--progress", progress, "[s, wall] between progress lines; 0 = none")->capture_default_str()->check(lcmloc::common::wallSeconds());
  app.add_flag("--bench", bench,
               "benchmark instead: generate a synthetic log, measure read+decode, dead_reckoning and ukf_gated "
               "replay (messages/s, medians)");
  app.add_option("--bench-duration", bo.duration_s, "[s] message time of the synthetic log (at most a day)")
      ->capture_default_str()
      ->check(lcmloc::common::positive())
      ->check(CLI::Validator(
          [](std::string& s) {
            return std::stod(s) <= 86400.0 ? std::string() : s + " s is more than a day (86400 s)";
          },
          "<= 86400"));
  app.add_option("--bench-reps", bo.repetitions, "repetitions (medians are reported)")->capture_default_str()->check(lcmloc::common::positive());
  app.add_option("--bench-dir", bo.dir, "where the synthetic log and bench.json go")->capture_default_str();
  app.add_flag("--bench-keep-log", bo.keep_log, "reuse the synthetic log of an earlier run if present");
  app.add_option("--bench-output-every", bo.output_every,
                 "fusion.output_every of the batched rows (1 = none)")->capture_default_str()->check(lcmloc::common::positive());
  app.add_option("--bench-case", bo.cases,
                 "measure only these cases (their keys in bench.json, e.g. ukf_gated_output_every_10; repeatable); "
                 "read+decode is measured beside each");
  app.footer("--lcm-url is accepted for uniformity and unused: the replay reads and writes files only.");

  return common::runProcess(app, argc, argv, opts, "lcmloc-replay", [&]() -> int {
    auto cfg = common::loadSystemConfig(opts.config);
    if (!filter.empty()) {
      YAML::Node n;
      n["type"] = filter;
      cfg.fusion.filter = common::parseFilterConfig(n, cfg.fusion.filter, "--filter", "fusion.filter");
    }
    if (no_shadow) cfg.fusion.shadow.clear();
    if (!shadow.empty()) {
      cfg.fusion.shadow.clear();
      std::string item;
      for (std::size_t i = 0; i <= shadow.size(); ++i) {
        if (i == shadow.size() || shadow[i] == ',') {
          if (!item.empty()) cfg.fusion.shadow.push_back(item);
          item.clear();
        } else {
          item += shadow[i];
        }
      }
      common::checkFilterList(cfg.fusion.shadow, "--shadow", "shadow");
    }
    if (bench) return replay::runBench(cfg, bo);
    if (input.empty() || output.empty()) {
      spdlog::error("give an input log and --output FILE (or --bench)");
      return common::kExitConfigError;
    }
    replay::ReplayOptions ro;
    ro.input = input;
    ro.output = output;
    ro.with_inputs = with_inputs;
    ro.progress_period_s = progress;
    ro.read_ahead = !one_thread;
    ro.stop = [] { return common::stopRequested(); };
    const auto r = replay::replayLog(cfg, ro);
    std::cout << fmt::format("replayed {} ({}) with filter {} (shadow: {}) -> {}\n", input, bytes(r.file_size),
                             cfg.fusion.filter.type,
                             cfg.fusion.shadow.empty() ? "none" : fmt::format("{}", fmt::join(cfg.fusion.shadow, ", ")),
                             output);
    if (!r.write_error.empty()) {
      spdlog::error("the output log {} could not be written ({}): the replay stopped after {} of the input's events; "
                    "the output holds the events that could be written (lcmloc-log info {})",
                    output, r.write_error, r.events_read, output);
      return common::kExitRuntimeError;
    }
    std::string per;
    for (const auto& [ch, n] : r.written_per_channel) per += fmt::format("{}{} {}", per.empty() ? "" : ", ", ch, n);
    std::cout << fmt::format(
        "read {} events ({} recorded outputs ignored), used {}, rejected {}, sequence gaps {}, written {} ({}){}; "
        "final filter {}; {:.2f} s\n",
        r.events_read, r.old_outputs, r.used, r.rejected, r.gaps, r.written, per,
        r.copied ? fmt::format(", of which {} copied inputs", r.copied) : std::string(), r.final_filter, r.seconds);
    if (r.interrupted) std::cout << "interrupted: the output holds what was replayed so far\n";
    for (const auto& is : r.issues)
      std::cout << fmt::format("damage: before event {} at byte {}: {}\n", is.event_index, is.byte_offset, is.what);
    if (r.damaged) return common::kExitInputDamaged;
    return common::kExitOk;
  });
}
