#include "lcmloc/import/checks.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include <fmt/format.h>

#include "lcmloc/app/config.hpp"

namespace lcmloc::import {

std::optional<int64_t> toMicros(double t, double us_per_unit) {
  const double us = t * us_per_unit;
  if (!std::isfinite(us) || std::abs(us) >= 9.2e18) return std::nullopt;  // int64 ends at 9.22e18
  return std::llround(us);
}

std::vector<TimeVerdict> checkTimeOrder(const std::vector<std::optional<int64_t>>& t, bool strict) {
  const std::size_t n = t.size();
  // longest[i]: the longest sequence in time order that starts at row i, from the end of the
  // file backwards (patience sorting on the reversed, negated times: O(n log n)).
  std::vector<std::size_t> longest(n, 0);
  std::vector<int64_t> tails;  // tails[k]: the largest first time of a sequence of k + 1 rows, negated
  for (std::size_t i = n; i-- > 0;) {
    if (!t[i]) continue;
    const int64_t w = -*t[i];  // no overflow: times are within +-9.2e18
    const auto at = strict ? std::lower_bound(tails.begin(), tails.end(), w)
                           : std::upper_bound(tails.begin(), tails.end(), w);
    longest[i] = static_cast<std::size_t>(at - tails.begin()) + 1;
    if (at == tails.end()) tails.push_back(w);
    else *at = w;
  }
  // Keep the earliest rows of such a sequence of the greatest length, greedily from the start.
  std::vector<bool> kept(n, false);
  std::size_t need = tails.size(), last = TimeVerdict::kNone;
  for (std::size_t i = 0; i < n && need > 0; ++i) {
    if (!t[i] || longest[i] != need) continue;
    if (last != TimeVerdict::kNone && !(strict ? *t[i] > *t[last] : *t[i] >= *t[last])) continue;
    kept[i] = true;
    last = i;
    --need;
  }
  std::vector<TimeVerdict> v(n);
  std::size_t prev = TimeVerdict::kNone;
  for (std::size_t i = 0; i < n; ++i) {  // the kept row before each row
    v[i].prev = prev;
    if (kept[i]) prev = i;
  }
  std::size_t next = TimeVerdict::kNone;
  for (std::size_t i = n; i-- > 0;) {  // and after it; the verdict
    v[i].next = next;
    if (kept[i]) next = i;
    if (!t[i] || kept[i]) continue;
    const bool after_prev = v[i].prev == TimeVerdict::kNone ||
                            (strict ? *t[i] > *t[v[i].prev] : *t[i] >= *t[v[i].prev]);
    v[i].kind = after_prev ? TimeVerdict::Ahead : TimeVerdict::Backwards;
  }
  return v;
}

std::string timeOrderReason(const std::vector<std::optional<int64_t>>& t, std::size_t i, const TimeVerdict& v,
                            bool strict, const std::function<std::string(std::size_t)>& text) {
  switch (v.kind) {
    case TimeVerdict::Backwards: {
      std::string s = fmt::format("time {} {} the previous row's {} (time going backwards{})", text(i),
                                  strict ? "not after" : "before", text(v.prev), strict ? " or repeated" : "");
      if (*t[i] == *t[v.prev] && text(i) != text(v.prev)) s += fmt::format(": both are {} us", *t[i]);
      return s;
    }
    case TimeVerdict::Ahead:
      if (v.next == TimeVerdict::kNone)  // cannot happen: the row would lengthen the kept rows
        return fmt::format("time {} out of order", text(i));
      return fmt::format("time {} out of line: {} but {} the next row's {} (the rows around it are kept)", text(i),
                         v.prev == TimeVerdict::kNone ? std::string("the first row")
                                                      : "after the previous row's " + text(v.prev),
                         strict ? "not before" : "after", text(v.next));
    case TimeVerdict::Kept: break;
  }
  return "";
}


void checkFilterValue(const std::string& flag, const std::string& key, const std::string& value) {
  app::parseSystemConfig("fusion:\n  filter:\n    " + key + ": " + value + "\n", flag);
}

}  // namespace lcmloc::import
