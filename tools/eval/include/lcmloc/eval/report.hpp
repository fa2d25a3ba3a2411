#pragma once
// Outputs of the evaluation: report.json, a human summary table, and PNG figures drawn by
// gnuplot (data files + a gnuplot script written next to them, so a figure can be redrawn).
#include <ostream>
#include <string>

#include <nlohmann/json.hpp>

#include "lcmloc/eval/evaluate.hpp"

namespace lcmloc::eval {

struct ReportMeta {
  std::string config_file;
  core::GateConfig gate;
};

/// The whole report as JSON (see README, "Report fields").
nlohmann::json makeReport(const LogData& data, const Evaluation& ev, const ReportMeta& meta);

/// Writes json to path (pretty-printed; invalid UTF-8 in strings replaced by U+FFFD); throws
/// std::runtime_error on I/O failure.
void writeJson(const nlohmann::json& report, const std::string& path);

/// Human summary: one line per filter (and the live run), then the log's health.
void printSummary(std::ostream& os, const LogData& data, const Evaluation& ev);

struct PlotResult {
  bool ok = false;
  std::string message;               ///< what happened (e.g. "gnuplot not found in PATH")
  std::vector<std::string> figures;  ///< PNG files written
};

/// Writes the data files and plot.gp into dir, then runs gnuplot there.
PlotResult writePlots(const LogData& data, const Evaluation& ev, const core::MarkerMap& map,
                      const std::string& dir);

}  // namespace lcmloc::eval
