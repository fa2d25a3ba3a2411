// lcmloc-eval: offline evaluation of a recorded run. Reads the log directly (no network),
// replays its sensor channels through the fusion engine once per filter, scores every filter
// (and the live daemon's POSE, if recorded) against ground truth, writes report.json and PNG
// figures, and prints a summary table.
#include <cmath>
#include <filesystem>
#include <iostream>

#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/process.hpp"
#include "lcmloc/eval/evaluate.hpp"
#include "lcmloc/eval/log_reader.hpp"
#include "lcmloc/eval/report.hpp"
#include "lcmloc/sim/world.hpp"

namespace {

constexpr int kExitNothingUsable = lcmloc::common::kExitRuntimeError;
constexpr int kExitBadConfig = lcmloc::common::kExitConfigError;

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Offline evaluation of an lcmloc log: replays the sensor channels through each "
               "filter, scores them against ground truth, writes report.json and PNG figures. "
               "Exit: 0 report written, 1 nothing usable, 2 bad config or filter, 3 report written from a "
               "damaged log (its intact events; each damaged place reported)."};
  std::string log_path, out_dir = "out/eval";
  lcmloc::common::CommonOptions opts;
  const std::string& config_path = opts.config;
  std::vector<std::string> filters{"dead_reckoning", "ukf", "ukf_gated"};
  bool no_plots = false;
  app.add_option("log", log_path, "LCM log file to evaluate")->required();
  app.add_option("-o,--out", out_dir, "output directory for report.json and figures")->capture_default_str();
  app.add_option("--filters", filters,
                 "filters to replay: dead_reckoning, ukf, ukf_gated, ukf_calib (odometry and ruler detections "
                 "are replayed; for the IMU, GPS and landmark filters use lcmloc-replay + lcmloc-evaluate)")
      ->delimiter(',')->capture_default_str();
  app.add_flag("--no-plots", no_plots, "do not draw figures");
  lcmloc::common::addOfflineOptions(app, opts,
                                    "system config (YAML) giving filter parameters, marker map and channels; "
                                    "built-in defaults (the paper's experiment) when omitted");
  return lcmloc::common::runProcess(app, argc, argv, opts, "lcmloc-eval", [&] {
    lcmloc::common::SystemConfig cfg;
    try {
      if (!config_path.empty()) cfg = lcmloc::common::loadSystemConfig(config_path);
    } catch (const std::exception& e) {
      spdlog::error("{}", e.what());
      return kExitBadConfig;
    }

    lcmloc::eval::EvalSetup setup;
    setup.engine = lcmloc::common::engineConfig(cfg);  // the daemon's time-jump guard and odometry gaps
    setup.filter = cfg.fusion.filter;
    setup.reorder_window_us = static_cast<int64_t>(std::llround(cfg.fusion.reorder_window * 1e6));
    setup.filters = filters;
    try {
      lcmloc::models::Path path(cfg.scenario.path);
      setup.map = lcmloc::models::makeMarkerMap(path, cfg.scenario.markers);
    } catch (const std::exception& e) {
      spdlog::error("cannot build the marker map from '{}': {}", config_path, e.what());
      return kExitBadConfig;
    }

    lcmloc::eval::LogData data;
    try {
      data = lcmloc::eval::readLog(log_path, cfg.channels, &lcmloc::common::stopFlag());
    } catch (const std::exception& e) {
      spdlog::error("{}", e.what());
      return kExitNothingUsable;
    }
    for (const auto& i : data.issues)
      spdlog::warn("{}: {}", log_path, i.describe());
    if (data.interrupted) spdlog::warn("interrupted: evaluating the {} events read so far", data.events_read);
    if (!data.usable()) {
      spdlog::error("{}: no usable odometry or ruler measurement in {} events ({} bytes)", log_path,
                    data.events_read, data.file_size);
      return kExitNothingUsable;
    }
    if (data.truth.empty()) spdlog::warn("{}: no ground truth: errors cannot be computed", log_path);

    lcmloc::eval::Evaluation ev;
    try {
      ev = lcmloc::eval::evaluate(data, setup);
    } catch (const std::invalid_argument& e) {
      spdlog::error("{}", e.what());
      return kExitBadConfig;
    }

    std::error_code ec;
    std::filesystem::create_directories(out_dir, ec);
    if (ec) {
      spdlog::error("cannot create output directory '{}': {}", out_dir, ec.message());
      return kExitNothingUsable;
    }
    const auto report = lcmloc::eval::makeReport(data, ev, {config_path, setup.filter.gate});
    try {
      lcmloc::eval::writeJson(report, out_dir + "/report.json");
    } catch (const std::exception& e) {
      spdlog::error("{}", e.what());
      return kExitNothingUsable;
    }
    lcmloc::eval::printSummary(std::cout, data, ev);
    std::cout << "report: " << out_dir << "/report.json\n";
    if (!no_plots) {
      const auto plots = lcmloc::eval::writePlots(data, ev, setup.map, out_dir);
      if (plots.ok) std::cout << "figures:";
      for (const auto& f : plots.figures) std::cout << " " << f;
      if (plots.ok) std::cout << "\n";
      else spdlog::warn("{}", plots.message);
    }
    if (data.damaged) {
      spdlog::warn("{}: the log is damaged ({} bytes unreadable): the report covers the intact events only",
                   log_path, data.bytes_unreadable);
      return static_cast<int>(lcmloc::common::kExitInputDamaged);
    }
    return 0;
  });
}
