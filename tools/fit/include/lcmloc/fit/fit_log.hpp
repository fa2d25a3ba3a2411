#pragma once
// The fit's input from an LCM log (any of ours: an import, a recording): the truth, odometry,
// landmark, beacon and GPS channels of a system config, each message checked and converted as
// the fusion daemon does (bus::toCore); the map from the config's fusion.map_file.
#include <string>

#include "lcmloc/app/config.hpp"
#include "lcmloc/fit/noise_fit.hpp"

namespace lcmloc::fit {

/// What reading found besides the recording: messages refused by the conversion, damage.
struct LogRead {
  Recording recording;
  int64_t refused = 0;
  bool damaged = false;
};

/// Throws std::runtime_error when the log cannot be read.
LogRead readRecording(const std::string& log, const app::SystemConfig& cfg);

}  // namespace lcmloc::fit
