#include "lcmloc/import/event_log.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include "lcmloc/logio/event_file.hpp"

namespace lcmloc::import {

void EventLog::sort() {
  if (sorted_) return;
  std::sort(events_.begin(), events_.end(), [](const Event& a, const Event& b) {
    if (a.utime != b.utime) return a.utime < b.utime;
    if (a.order != b.order) return a.order < b.order;
    return a.index < b.index;
  });
  sorted_ = true;
}

int64_t EventLog::firstUtime() const {
  int64_t t = 0;
  for (std::size_t i = 0; i < events_.size(); ++i) t = i == 0 ? events_[i].utime : std::min(t, events_[i].utime);
  return t;
}

int64_t EventLog::lastUtime() const {
  int64_t t = 0;
  for (std::size_t i = 0; i < events_.size(); ++i) t = i == 0 ? events_[i].utime : std::max(t, events_[i].utime);
  return t;
}

void EventLog::write(const std::string& path) {
  sort();
  logger::EventFile f(path);
  for (const auto& e : events_)
    if (int err = f.append(e.utime, e.channel, e.bytes.data(), e.bytes.size()))
      throw std::runtime_error("cannot write '" + path + "': " + std::strerror(err));
  if (int err = f.close(true)) throw std::runtime_error("cannot write '" + path + "': " + std::strerror(err));
}

}  // namespace lcmloc::import
