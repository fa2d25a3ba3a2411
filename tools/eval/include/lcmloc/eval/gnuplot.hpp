#pragma once
// Running gnuplot for the evaluation figures.
#include <string>
#include <vector>

#include "lcmloc/eval/report.hpp"

namespace lcmloc::eval {

/// text as a gnuplot single-quoted string literal, quotes included. Every string that comes from
/// a log or the command line (titles, labels, file names) goes into a script through this: every
/// ' is doubled and every control character (bytes below 0x20 and 0x7f, newline and carriage
/// return included) becomes '?', so the literal cannot end early and no new command line can
/// start. Inside single quotes gnuplot expands neither `backquotes` nor @macros and takes
/// backslashes literally.
std::string gnuplotQuote(const std::string& text);

/// app::printable(text): every control character (C0, DEL, C1) and invalid UTF-8 byte as '?'.
std::string withoutControlCharacters(std::string text);

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
