#pragma once
// lcmloc-hostile-run's two commands over runLive (live_run.hpp), each writing a report (JSON and
// text) and returning the exit code: 0 every check passed, 1 one failed.
//  - hostile: the system once clean, once with a second publisher sending each kind of bad message
//    on every input channel; RMSE within 2x of the clean run, POSE's longest step at most twice
//    its period, no NaN, and the status naming each channel's second publisher.
//  - soak: the system for a duration with a fraction of the messages on its input channels
//    corrupted at random; the daemon's RSS (first, last, max, slope), no NaN, no POSE step longer
//    than twice its period.
#include <string>

#include "live_run.hpp"

namespace lcmloc::hostile {

struct CommandOptions {
  LiveRunOptions run;      ///< the base of every run (out_dir: the command's output directory)
  std::string report;      ///< report.json's path ("" = out_dir/report.json)
};

int hostileCommand(const CommandOptions& c);
int soakCommand(const CommandOptions& c);

/// Least-squares slope of (t [s], kB) samples at or after from_s [kB per minute]; 0 for fewer than 2.
double rssSlopeKbPerMin(const std::vector<std::pair<double, int64_t>>& samples, double from_s);

}  // namespace lcmloc::hostile
