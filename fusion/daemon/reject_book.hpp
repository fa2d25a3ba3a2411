#pragma once
// The daemon's count of refused inputs per channel and reason (undecodable, invalid, limits,
// too_old, too_new, second_publisher): a flood of bad messages costs a few status events per
// status period and one summary line, not one status message each.
#include <cstdint>
#include <map>
#include <string>
#include <utility>

namespace lcmloc::fusion {

class RejectBook {
 public:
  /// Status events per (channel, reason) within one status period; the rest are counted only.
  static constexpr int64_t kEventsPerPeriod = 5;
  /// Counts one; true when it may have a status event of its own.
  bool note(const std::string& channel, const std::string& reason);
  /// "rejected since the last periodic status: CH reason N (M not reported each), ..." of the
  /// counts since the last call, or "" when none; starts the next period.
  std::string period();
  /// "CH reason N, ..." of every count so far ("" when none).
  std::string totals() const;
  /// The reason of an intake refusal from its words (bus::LimitCheck: "limits"; else "invalid").
  static std::string reasonOf(const std::string& why);

 private:
  using Key = std::pair<std::string, std::string>;
  std::map<Key, int64_t> period_, total_;
};

}  // namespace lcmloc::fusion
