#pragma once
// The frame every simulated sensor driver shares (lcmloc-odometry, -magruler, -imu, -gps in sim
// mode, -vision, -fault-injector): GROUND_TRUTH in, counted, with its sequence gaps counted and
// warned about (first 5, then 1 in 1000); a heartbeat with "received", "published", "gaps",
// "decode_errors" and the driver's own counters; the loop until SIGINT/SIGTERM; a last line and
// the "stopping" heartbeat. The driver's model and what it publishes stay in its main.
#include <cstdint>
#include <functional>
#include <string>

#include "lcmloc/common/config.hpp"
#include "lcmloc/common/process.hpp"
#include "lcmloc/ground_truth_t.hpp"

namespace lcmloc::common {

class TruthDriver {
 public:
  using OnTruth = std::function<void(const std::string& channel, const lcmloc::ground_truth_t&)>;
  /// Subscribes to cfg.channels.ground_truth; on_truth sees every decoded message, after the
  /// gap check. extra: the driver's own heartbeat counters (after the common ones).
  TruthDriver(Bus& bus, const SystemConfig& cfg, std::string process, OnTruth on_truth,
              std::function<Heartbeat::Counters()> extra = nullptr);
  /// The seq of the next message the driver publishes (and one more "published").
  int64_t nextSeq() { return published_++; }
  int64_t received() const { return received_; }
  int64_t published() const { return published_; }
  /// Runs until a stop is requested, then logs "stopping: N ground-truth samples in, M <out>,
  /// G gaps" (out: e.g. "odometry messages out (3 saturated)") and publishes the "stopping"
  /// heartbeat. Returns kExitOk.
  int run(const std::function<std::string()>& out);

 private:
  Bus& bus_;
  SeqTracker gaps_;
  LogThrottle throttle_;
  int64_t received_ = 0, published_ = 0;
  Heartbeat heartbeat_;
};

}  // namespace lcmloc::common
