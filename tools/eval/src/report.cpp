// writeJson: the reports' JSON writer.
#include "lcmloc/eval/report.hpp"

#include <fstream>
#include <stdexcept>

namespace lcmloc::eval {

using nlohmann::json;

void writeJson(const json& report, const std::string& path) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write '" + path + "'");
  // Strings from a log (channel, filter and sensor names) may hold any bytes: invalid UTF-8 is
  // written as U+FFFD rather than failing the whole report.
  f << report.dump(2, ' ', false, json::error_handler_t::replace) << "\n";
  if (!f) throw std::runtime_error("error while writing '" + path + "'");
}

}  // namespace lcmloc::eval
