#include "lcmloc/app/process_table.hpp"

#include <algorithm>
#include <set>

#include <fmt/format.h>

#include "lcmloc/app/text.hpp"

namespace lcmloc::app {

namespace {
constexpr std::size_t kMaxSamples = 50;  ///< clock offset samples kept per host
const std::string kChildPrefix = "proc.";

int64_t counter(const lcmloc::heartbeat_t& m, std::initializer_list<const char*> names) {
  for (const char* want : names)
    for (std::size_t i = 0; i < m.counter_names.size() && i < m.counters.size(); ++i)
      if (m.counter_names[i] == want) return m.counters[i];
  return -1;
}

double rate(const lcmloc::heartbeat_t& now, const lcmloc::heartbeat_t& before,
            std::initializer_list<const char*> names) {
  const int64_t a = counter(now, names), b = counter(before, names);
  const double dt = static_cast<double>(now.utime - before.utime) * 1e-6;
  if (a < 0 || b < 0 || a < b || dt <= 0) return -1;
  return static_cast<double>(a - b) / dt;
}

struct LauncherChild {
  std::string name;
  int64_t pid = -1, state = 0, restarts = 0;
};

/// A launcher's children in the order of its counters.
std::vector<LauncherChild> launcherChildren(const lcmloc::heartbeat_t& m) {
  std::vector<LauncherChild> out;
  for (std::size_t i = 0; i < m.counter_names.size() && i < m.counters.size(); ++i) {
    const std::string& n = m.counter_names[i];
    if (n.rfind(kChildPrefix, 0) != 0) continue;
    const auto dot = n.rfind('.');
    if (dot <= kChildPrefix.size()) continue;
    const std::string name = n.substr(kChildPrefix.size(), dot - kChildPrefix.size()), field = n.substr(dot + 1);
    auto it = std::find_if(out.begin(), out.end(), [&](const LauncherChild& c) { return c.name == name; });
    if (it == out.end()) it = out.insert(out.end(), LauncherChild{name});
    if (field == "pid") it->pid = m.counters[i];
    else if (field == "state") it->state = m.counters[i];
    else if (field == "restarts") it->restarts = m.counters[i];
  }
  return out;
}

void fillFromHeartbeat(ProcessRow& r, const lcmloc::heartbeat_t& m, const lcmloc::heartbeat_t* previous,
                       double age) {
  r.cpu_percent = m.cpu_percent;
  r.rss_bytes = m.rss_bytes;
  r.age = age;
  if (previous) {
    r.rate_in = rate(m, *previous, {"received", "in"});
    r.rate_out = rate(m, *previous, {"published", "written"});
  }
}
}  // namespace

const char* procStateName(ProcState s) {
  switch (s) {
    case ProcState::Starting: return "starting";
    case ProcState::Running: return "running";
    case ProcState::Restarting: return "restarting";
    case ProcState::Stopped: return "stopped";
    case ProcState::Failed: return "FAILED";
    case ProcState::Exited: return "exited";
  }
  return "?";
}

std::vector<std::pair<std::string, int64_t>> childCounters(const std::string& name, int64_t pid, ProcState state,
                                                           int64_t restarts) {
  const std::string p = kChildPrefix + name + ".";
  return {{p + "pid", pid}, {p + "state", static_cast<int64_t>(state)}, {p + "restarts", restarts}};
}

void ProcessTable::observe(const lcmloc::heartbeat_t& m, int64_t recv_utime, Clock::time_point now) {
  if (m.process == "lcmloc-launcher")
    for (const auto& c : launcherChildren(m))
      if (c.pid > 0) children_[{m.host, c.pid}] = true;
  Seen& s = procs_[{m.host, m.pid}];
  if (s.at != Clock::time_point{} && s.last.seq < m.seq) {
    s.previous = s.last;
    s.has_previous = true;
  }
  s.last = m;
  s.at = now;
  auto& v = offsets_[m.host];
  v.push_back(static_cast<double>(recv_utime - m.utime) * 1e-6);
  if (v.size() > kMaxSamples) v.erase(v.begin());
}

std::vector<ProcessRow> ProcessTable::rows(Clock::time_point now) const {
  std::vector<ProcessRow> out;
  std::set<std::pair<std::string, int64_t>> shown;
  const auto age = [&](const Seen& s) { return std::chrono::duration<double>(now - s.at).count(); };
  for (const auto& [key, s] : procs_) {
    if (s.last.process != "lcmloc-launcher") continue;
    ProcessRow self{"launcher", key.first, key.second, s.last.state};
    fillFromHeartbeat(self, s.last, s.has_previous ? &s.previous : nullptr, age(s));
    out.push_back(self);
    shown.insert(key);
    for (const auto& c : launcherChildren(s.last)) {
      ProcessRow r{c.name, key.first, c.pid, procStateName(static_cast<ProcState>(c.state)), c.restarts};
      const auto it = procs_.find({key.first, c.pid});
      if (c.pid > 0 && it != procs_.end()) {
        fillFromHeartbeat(r, it->second.last, it->second.has_previous ? &it->second.previous : nullptr,
                          age(it->second));
        shown.insert(it->first);
      }
      out.push_back(r);
    }
  }
  for (const auto& [key, s] : procs_) {
    if (shown.count(key) || children_.count(key)) continue;  // (a launcher child's earlier run)
    ProcessRow r{s.last.process, key.first, key.second, s.last.state};
    fillFromHeartbeat(r, s.last, s.has_previous ? &s.previous : nullptr, age(s));
    out.push_back(r);
  }
  return out;
}

std::map<std::string, HostClock> ProcessTable::clocks() const {
  std::map<std::string, HostClock> out;
  for (auto [host, v] : offsets_) {
    if (v.empty()) continue;
    std::sort(v.begin(), v.end());
    out[host] = {v[v.size() / 2], v.back() - v.front(), static_cast<int>(v.size())};
  }
  return out;
}

std::string formatProcessTable(const std::vector<ProcessRow>& rows) {
  std::string t = fmt::format("{:<16} {:<14} {:>8} {:<10} {:>8} {:>6} {:>9} {:>8} {:>8} {:>6}\n", "PROCESS", "HOST",
                              "PID", "STATE", "RESTARTS", "CPU%", "RSS_MB", "IN/s", "OUT/s", "AGE_s");
  const auto num = [](double v, const char* f) { return v < 0 ? std::string("-") : fmt::format(fmt::runtime(f), v); };
  for (const auto& r : rows)
    t += fmt::format("{:<16} {:<14} {:>8} {:<10} {:>8} {:>6} {:>9} {:>8} {:>8} {:>6}\n", printable(r.name),
                     printable(r.host), r.pid > 0 ? std::to_string(r.pid) : "-", printable(r.state),
                     r.restarts >= 0 ? std::to_string(r.restarts) : "-", num(r.cpu_percent, "{:.1f}"),
                     num(r.rss_bytes < 0 ? -1.0 : static_cast<double>(r.rss_bytes) / 1048576.0, "{:.1f}"),
                     num(r.rate_in, "{:.0f}"), num(r.rate_out, "{:.0f}"), num(r.age, "{:.1f}"));
  return t;
}

}  // namespace lcmloc::app
