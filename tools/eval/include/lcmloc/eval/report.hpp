#pragma once
// Outputs shared by the tools' reports: report.json written safely, and the result of drawing
// PNG figures with gnuplot (data files + a gnuplot script written next to them, so a figure can
// be redrawn).
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace lcmloc::eval {

/// Writes json to path (pretty-printed; invalid UTF-8 in strings replaced by U+FFFD); throws
/// std::runtime_error on I/O failure.
void writeJson(const nlohmann::json& report, const std::string& path);

struct PlotResult {
  bool ok = false;
  std::string message;               ///< what happened (e.g. "gnuplot not found in PATH")
  std::vector<std::string> figures;  ///< PNG files written
};

}  // namespace lcmloc::eval
