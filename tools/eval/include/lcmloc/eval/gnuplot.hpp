#pragma once
// Running gnuplot for the evaluation figures.
#include <string>

#include "lcmloc/eval/report.hpp"

namespace lcmloc::eval {

/// True when an executable named exe is in PATH.
bool findInPath(const std::string& exe);

/// Runs gnuplot on script inside dir, its output to dir/gnuplot.log; returns the exit status
/// (-1 when it could not be run or was killed).
int runGnuplot(const std::string& dir, const std::string& script);

/// Draws res.figures (names relative to dir) with gnuplot script in dir: on success the names
/// become paths and res.ok is set; without gnuplot or when it fails, res.figures is cleared and
/// res.message says why (the data files and the script stay in dir). Returns res.
PlotResult& drawFigures(PlotResult& res, const std::string& dir, const std::string& script);

}  // namespace lcmloc::eval
