#pragma once
// The spdlog set-up of every lcmloc program (runProcess calls it).
#include <string>

namespace lcmloc::app {

/// Sets the default spdlog logger (stderr, "[name] " prefix) at level ("trace".."off").
void setupLogging(const std::string& process_name, const std::string& level);

}  // namespace lcmloc::app
