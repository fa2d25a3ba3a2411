#pragma once
// A real receiver through gpsd (libgps): connects, enables JSON watching, and turns each TPV
// report into a gps_fix_t (mode < 2 -> fix_type 1, "no fix").
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "lcmloc/gps_fix_t.hpp"

namespace lcmloc::gps {

class GpsdError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class GpsdSource {
 public:
  /// Connects to gpsd at host:port; throws GpsdError (with gpsd's reason) when it cannot.
  /// use_fix_time: utime from the fix's own time (falls back to receipt time when absent).
  GpsdSource(const std::string& host, const std::string& port, bool use_fix_time);
  ~GpsdSource();
  /// Waits up to timeout_ms for a report. Returns a fix for a TPV report, nullopt otherwise.
  /// Throws GpsdError when the connection is lost.
  std::optional<lcmloc::gps_fix_t> poll(int timeout_ms);
  int64_t reports() const { return reports_; }
 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  bool use_fix_time_;
  int64_t reports_ = 0;
};

}  // namespace lcmloc::gps
