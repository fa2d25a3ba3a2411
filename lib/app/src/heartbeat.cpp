#include "lcmloc/app/heartbeat.hpp"

#include <unistd.h>

#include "lcmloc/app/signals.hpp"
#include "lcmloc/heartbeat_t.hpp"

namespace lcmloc::app {

Heartbeat::Heartbeat(bus::MessageBus& bus, std::string channel, std::string process,
                     std::function<Counters()> counters)
    : bus_(bus), channel_(std::move(channel)), process_(std::move(process)),
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
  bus_.publish(channel_, m);
  last_ = std::chrono::steady_clock::now();
  sent_ = true;
}

}  // namespace lcmloc::app
