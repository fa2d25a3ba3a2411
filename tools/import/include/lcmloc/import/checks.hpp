#pragma once
// What the three importers (lcmloc-import, lcmloc-import-vp, lcmloc-magnet-grid) check the same
// way: the order of a file's time column (docs/import_formats.md, "Time order"), times that fit
// the microsecond clock of the log, outputs that would overwrite an input, and command-line
// values that go into a generated config.yaml.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace lcmloc::import {

/// t in units of us_per_unit microseconds (1e6: seconds, 1e3: milliseconds, 1: microseconds),
/// rounded to the microsecond; nullopt when not finite or beyond the int64 microsecond clock
/// (about 292,000 years either side of 1970).
std::optional<int64_t> toMicros(double t, double us_per_unit);

/// The verdict of the time-order rule on one row.
struct TimeVerdict {
  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  enum Kind { Kept, Backwards, Ahead };
  Kind kind = Kept;
  std::size_t prev = kNone;  ///< the kept row before it (kNone: none)
  std::size_t next = kNone;  ///< the kept row after it (kNone: none)
};

/// The time-order rule (docs/import_formats.md, "Time order"). The rows kept are the longest
/// sequence of rows in time order: strictly increasing (strict: odometry, gps, ground truth, the
/// Victoria Park and magnet-grid files) or non-decreasing (landmarks, beacons); of several such
/// sequences the one of the earliest rows. Every other row is refused: Backwards when its time is
/// not in order after the kept row before it, else Ahead (not in order before the kept row after
/// it). So one wrong time, far ahead or far back, is refused alone and the rows after it are kept;
/// of two rows swapped the later is refused. Rows without a time (nullopt: refused for another
/// reason) take no part and are Kept here.
std::vector<TimeVerdict> checkTimeOrder(const std::vector<std::optional<int64_t>>& utimes, bool strict);

/// The refusal reason of a verdict that is not Kept, naming the row's time and its kept
/// neighbours' as text(i) gives them (as written in the file, with a unit where the file has one).
std::string timeOrderReason(const std::vector<std::optional<int64_t>>& utimes, std::size_t i, const TimeVerdict& v,
                            bool strict, const std::function<std::string(std::size_t)>& text);

/// Throws app::ConfigError naming flag when value (YAML, e.g. "[1e-5, 2e-3]") is not what a
/// system config accepts for fusion.filter.<key>: a command-line value bound for a generated
/// config.yaml is refused with the flag's name, not later by the replay naming the file.
void checkFilterValue(const std::string& flag, const std::string& key, const std::string& value);

}  // namespace lcmloc::import
