#include "lcmloc/app/pacer.hpp"

#include <algorithm>
#include <thread>

#include "lcmloc/app/signals.hpp"

namespace lcmloc::app {

Pacer::Pacer(double realtime_factor) : factor_(realtime_factor) {}

bool Pacer::waitUntil(int64_t sim_utime, const std::function<void()>& idle) {
  using namespace std::chrono;
  if (!started_) {
    started_ = true;
    t0_ = sim_utime;
    wall0_ = steady_clock::now();
  }
  if (factor_ <= 0.0) {
    if (idle) idle();
    return !stopRequested();
  }
  // (a very small factor: the wait saturates at about 30 years instead of overflowing the clock)
  const double wait_us = std::min(static_cast<double>(sim_utime - t0_) / factor_, 1e15);
  const auto due = wall0_ + duration_cast<steady_clock::duration>(duration<double, std::micro>(wait_us));
  while (!stopRequested()) {
    if (idle) idle();
    const auto now = steady_clock::now();
    if (now >= due) return true;
    std::this_thread::sleep_for(std::min<steady_clock::duration>(due - now, milliseconds(100)));
  }
  return false;
}

}  // namespace lcmloc::app
