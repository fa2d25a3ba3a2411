#pragma once
// Runs simulated time against wall time with a real-time factor (the simulated drivers).
#include <chrono>
#include <cstdint>
#include <functional>

namespace lcmloc::app {

/// Paces simulated time against wall time: sim time t is due at wall start + (t - t0) / factor.
/// factor <= 0 means as fast as possible.
class Pacer {
 public:
  explicit Pacer(double realtime_factor);
  /// Blocks until sim_utime is due, calling idle() at least every 100 ms while waiting.
  /// Returns false when a stop was requested meanwhile.
  bool waitUntil(int64_t sim_utime, const std::function<void()>& idle = nullptr);
 private:
  double factor_;
  bool started_ = false;
  int64_t t0_ = 0;
  std::chrono::steady_clock::time_point wall0_;
};

}  // namespace lcmloc::app
