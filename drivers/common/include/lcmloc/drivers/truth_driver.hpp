#pragma once
// The frame every simulated sensor driver shares (lcmloc-odometry, -magruler, -imu, -gps in sim
// mode, -vision, -fault-injector): GROUND_TRUTH in, counted, with its sequence gaps counted and
// warned about (first 5, then 1 in 1000); each sample checked once, for every driver, before any
// sensor model sees it (truthProblem: a non-finite field, a utime outside [0, 2^62) us or a value
// no vehicle reaches is refused, counted as "bad_truth" and warned about, first 5 then 1 in 1000);
// its message time guarded (core::TimeBaseGuard with fusion.max_time_jump: a truth sample far
// from the others is dropped unless those in a row (three or more, over 0.2 s) confirm a new time base; one in the past is a
// simulator that started over, and the driver's model starts over with it, so the second run
// gives what the first gave); a heartbeat with "received", "published", "gaps", "dropped",
// "bad_truth", "decode_errors" and the driver's own counters; the loop until SIGINT/SIGTERM; a
// last line and the "stopping" heartbeat. The driver's model and what it publishes stay in its
// main.
#include <cstdint>
#include <functional>
#include <string>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/heartbeat.hpp"
#include "lcmloc/app/log_throttle.hpp"
#include "lcmloc/bus/seq_tracker.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/core/time_guard.hpp"
#include "lcmloc/ground_truth_t.hpp"

namespace lcmloc::drivers {

/// Message time [us] a usable ground-truth sample stays below (and >= 0): the offline tools'
/// limit (logio::kUtimeLimit, about 146,000 years), far from where utime arithmetic overflows.
inline constexpr int64_t kTruthUtimeLimit = int64_t{1} << 62;
/// |x|, |y|, |distance| [m] of a usable sample: a million kilometres, far beyond any run, and
/// small enough that the sensor models' arithmetic (e.g. a distance in encoder ticks) is exact.
inline constexpr double kTruthLengthLimit = 1e9;
/// |speed| [m/s] of a usable sample (products such as speed^2 tan(steering) stay finite).
inline constexpr double kTruthSpeedLimit = 1e5;

/// Why m is not usable ground truth ("" when it is): a non-finite field ("non-finite pose: x =
/// nan" for x, y, heading; "non-finite speed = inf", ...), utime outside [0, kTruthUtimeLimit),
/// or |x|, |y|, |distance| > kTruthLengthLimit, |speed| > kTruthSpeedLimit, |steering| >= pi/2.
/// The heading need only be finite (the models wrap it). The one rule every sensor driver applies (in TruthDriver).
std::string truthProblem(const lcmloc::ground_truth_t& m);

class TruthDriver {
 public:
  using OnTruth = std::function<void(const std::string& channel, const lcmloc::ground_truth_t&)>;
  /// Subscribes to cfg.channels.ground_truth; on_truth sees every decoded message that passes
  /// truthProblem and that the time guard takes, in order. restart: makes the driver's model anew
  /// (truth time went back: the simulator started over). extra: the driver's own heartbeat
  /// counters (after the common ones).
  TruthDriver(bus::Bus& bus, const app::SystemConfig& cfg, std::string process, OnTruth on_truth,
              std::function<void()> restart, std::function<app::Heartbeat::Counters()> extra = nullptr);
  /// The seq of the next message the driver publishes (and one more "published").
  int64_t nextSeq() { return published_++; }
  int64_t received() const { return received_; }
  int64_t published() const { return published_; }
  /// Samples refused by truthProblem (heartbeat counter "bad_truth").
  int64_t badTruth() const { return bad_truth_; }
  /// Runs until a stop is requested, then logs "stopping: N ground-truth samples in, M <out>,
  /// G gaps[, D dropped][, B refused]" (out: e.g. "odometry messages out (3 saturated)") and publishes the "stopping"
  /// heartbeat. Returns kExitOk.
  int run(const std::function<std::string()>& out);

 private:
  void onMessage(const std::string& channel, const lcmloc::ground_truth_t& m);

  bus::Bus& bus_;
  OnTruth on_truth_;
  std::function<void()> restart_;
  bus::SeqTracker gaps_;
  app::LogThrottle throttle_;
  core::TimeBaseGuard<lcmloc::ground_truth_t> guard_;
  int64_t received_ = 0, published_ = 0, dropped_ = 0, bad_truth_ = 0;
  app::Heartbeat heartbeat_;
};

}  // namespace lcmloc::drivers
