#include "lcmloc/app/heartbeat.hpp"

#include <unistd.h>

#include <climits>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "lcmloc/app/signals.hpp"
#include "lcmloc/heartbeat_t.hpp"

namespace lcmloc::app {

std::string hostName() {
  if (const char* env = std::getenv("LCMLOC_HOST"); env != nullptr && *env != '\0') return env;
  char name[HOST_NAME_MAX + 1] = {};
  if (::gethostname(name, sizeof name - 1) != 0) return "?";
  return name;
}

ProcessUsage processUsage() {
  ProcessUsage u;
  const long ticks = ::sysconf(_SC_CLK_TCK), page = ::sysconf(_SC_PAGESIZE);
  std::ifstream stat("/proc/self/stat");
  std::string line;
  if (ticks > 0 && std::getline(stat, line)) {
    // pid (comm) state ...: comm may hold spaces and parentheses; the fields follow the last ')'.
    const auto close = line.rfind(')');
    if (close != std::string::npos) {
      std::istringstream in(line.substr(close + 2));
      std::string field;
      unsigned long long utime = 0, stime = 0;
      for (int i = 3; i <= 13 && in >> field; ++i) {}  // fields 3..13 (state .. majflt... cmajflt)
      if (in >> utime >> stime) u.cpu_seconds = static_cast<double>(utime + stime) / static_cast<double>(ticks);
    }
  }
  std::ifstream statm("/proc/self/statm");
  long long size = 0, resident = 0;
  if (page > 0 && statm >> size >> resident) u.rss_bytes = resident * page;
  return u;
}

Heartbeat::Heartbeat(bus::MessageBus& bus, std::string channel, std::string process,
                     std::function<Counters()> counters)
    : bus_(bus), channel_(std::move(channel)), process_(std::move(process)), host_(hostName()),
      counters_(std::move(counters)) {}

void Heartbeat::tick() {
  const auto now = std::chrono::steady_clock::now();
  if (sent_ && now - last_ < std::chrono::duration<double>(kPeriodSeconds)) return;
  publish(stopRequested() ? "stopping" : "running");
}

void Heartbeat::publish(const std::string& state) {
  lcmloc::heartbeat_t m;
  m.utime = bus::wallMicros();
  m.seq = seq_++;
  m.process = process_;
  m.pid = static_cast<int32_t>(::getpid());
  m.state = state;
  if (counters_) {
    for (const auto& [name, value] : counters_()) {
      m.counter_names.push_back(name);
      m.counters.push_back(value);
    }
  }
  m.num_counters = static_cast<int32_t>(m.counters.size());
  m.host = host_;
  const auto now = std::chrono::steady_clock::now();
  const ProcessUsage usage = processUsage();
  const double wall = std::chrono::duration<double>(now - last_).count();
  m.cpu_percent = sent_ && last_cpu_ >= 0 && usage.cpu_seconds >= 0 && wall > 0
                      ? static_cast<float>(100.0 * (usage.cpu_seconds - last_cpu_) / wall)
                      : -1.0f;
  m.rss_bytes = usage.rss_bytes;
  last_cpu_ = usage.cpu_seconds;
  bus_.publish(channel_, m);
  last_ = now;
  sent_ = true;
}

}  // namespace lcmloc::app
