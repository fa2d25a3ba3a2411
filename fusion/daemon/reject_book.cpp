#include "reject_book.hpp"

#include <fmt/format.h>

#include "lcmloc/app/text.hpp"

namespace lcmloc::fusion {

bool RejectBook::note(const std::string& channel, const std::string& reason) {
  const Key k{channel, reason};
  ++total_[k];
  return ++period_[k] <= kEventsPerPeriod;
}

std::string RejectBook::period() {
  std::string s;
  for (const auto& [k, n] : period_) {
    s += fmt::format("{}{} {} {}", s.empty() ? "rejected since the last periodic status: " : ", ",
                     app::printable(k.first), k.second, n);
    if (n > kEventsPerPeriod) s += fmt::format(" ({} not reported each)", n - kEventsPerPeriod);
  }
  period_.clear();
  return s;
}

std::string RejectBook::totals() const {
  std::string s;
  for (const auto& [k, n] : total_) s += fmt::format("{}{} {} {}", s.empty() ? "" : ", ", app::printable(k.first), k.second, n);
  return s;
}

std::string RejectBook::reasonOf(const std::string& why) {
  return why.find("fusion.limits") != std::string::npos ? "limits" : "invalid";
}

}  // namespace lcmloc::fusion
