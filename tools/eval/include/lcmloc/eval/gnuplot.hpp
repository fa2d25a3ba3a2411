#pragma once
// Running gnuplot for the evaluation figures.
#include <string>

namespace lcmloc::eval {

/// True when an executable named exe is in PATH.
bool findInPath(const std::string& exe);

/// Runs gnuplot on script inside dir, its output to dir/gnuplot.log; returns the exit status
/// (-1 when it could not be run or was killed).
int runGnuplot(const std::string& dir, const std::string& script);

}  // namespace lcmloc::eval
