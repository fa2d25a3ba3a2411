#include "lcmloc/replay/command.hpp"

#include <iostream>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/files.hpp"
#include "lcmloc/app/signals.hpp"
#include "lcmloc/replay/replay.hpp"

namespace lcmloc::replay {
namespace {

std::string bytes(int64_t n) {
  if (n >= (1 << 20)) return fmt::format("{:.1f} MB", n / 1048576.0);
  if (n >= 1024) return fmt::format("{:.1f} kB", n / 1024.0);
  return fmt::format("{} B", n);
}

}  // namespace

simconfig::SimSystemConfig applyOverrides(simconfig::SimSystemConfig cfg, const CommandOptions& o) {
  if (!o.filter.empty()) {
    YAML::Node n;
    n["type"] = o.filter;
    cfg.fusion.filter = app::parseFilterConfig(n, cfg.fusion.filter, "--filter", "fusion.filter");
  }
  if (o.no_shadow) cfg.fusion.shadow.clear();
  if (!o.shadow.empty()) {
    cfg.fusion.shadow.clear();
    std::string item;
    for (std::size_t i = 0; i <= o.shadow.size(); ++i) {
      if (i == o.shadow.size() || o.shadow[i] == ',') {
        if (!item.empty()) cfg.fusion.shadow.push_back(item);
        item.clear();
      } else {
        item += o.shadow[i];
      }
    }
    app::checkFilterList(cfg.fusion.shadow, "--shadow", "shadow");
  }
  return cfg;
}

int runCommand(const simconfig::SimSystemConfig& cfg, const CommandOptions& o) {
  if (o.bench) return runBench(cfg, o.bench_options);
  if (o.input.empty() || o.output.empty()) throw app::UsageError("give an input log and --output FILE (or --bench)");
  app::requireInputFile(o.input, "input log");
  app::refuseOutputOverInputs("--output", o.output, {o.input}, "input log");  // (the more useful message)
  app::refuseExistingOutput(o.output, o.overwrite);
  ReplayOptions ro;
  ro.input = o.input;
  ro.output = o.output;
  ro.with_inputs = o.with_inputs;
  ro.control = o.control;
  ro.progress_period_s = o.progress_s;
  ro.read_ahead = !o.one_thread;
  ro.stop = [] { return app::stopRequested(); };
  const auto r = replayLog(cfg, ro);
  std::cout << fmt::format("replayed {} ({}) with filter {} (shadow: {}) -> {}\n", o.input, bytes(r.file_size),
                           cfg.fusion.filter.type,
                           cfg.fusion.shadow.empty() ? "none" : fmt::format("{}", fmt::join(cfg.fusion.shadow, ", ")),
                           o.output);
  if (!r.write_error.empty()) {
    spdlog::error("the output log {} could not be written ({}): the replay stopped after {} of the input's events; "
                  "the output holds the events that could be written (lcmloc-log info {})",
                  o.output, r.write_error, r.events_read, o.output);
    return app::kExitRuntimeError;
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
  return r.damaged ? app::kExitInputDamaged : app::kExitOk;
}

}  // namespace lcmloc::replay
