#include "lcmloc/app/logging.hpp"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

namespace lcmloc::app {

void setupLogging(const std::string& process_name, const std::string& level) {
  spdlog::drop(process_name);  // (set up again: a test that runs several programs' runProcess)
  auto logger = spdlog::stderr_color_mt(process_name);
  spdlog::set_default_logger(logger);
  spdlog::set_pattern("%H:%M:%S.%e [%n] %^%l%$: %v");
  spdlog::set_level(spdlog::level::from_str(level));
  spdlog::flush_on(spdlog::level::info);
}

}  // namespace lcmloc::app
