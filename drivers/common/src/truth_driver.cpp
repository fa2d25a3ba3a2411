#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/signals.hpp"
#include "lcmloc/drivers/truth_driver.hpp"

#include <cmath>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "lcmloc/app/text.hpp"

namespace lcmloc::drivers {

// Built on the application layer (configuration, process helpers).
using namespace lcmloc::app;

std::string truthProblem(const lcmloc::ground_truth_t& m) {
  if (m.utime < 0 || m.utime >= kTruthUtimeLimit)
    return "utime outside [0, 2^62) us";
  struct Field {
    const char* name;
    double value, limit;  // limit 0: finite is enough
    const char* what;     // of a non-finite value
    const char* unit;
  };
  const Field fields[] = {{"x", m.x, kTruthLengthLimit, "pose: x", "m"},
                          {"y", m.y, kTruthLengthLimit, "pose: y", "m"},
                          {"heading", m.heading, 0.0, "pose: heading", "rad"},
                          {"speed", m.speed, kTruthSpeedLimit, "speed", "m/s"},
                          {"steering", m.steering, 0.0, "steering", "rad"},
                          {"distance", m.distance, kTruthLengthLimit, "distance", "m"}};
  for (const auto& f : fields) {
    if (!std::isfinite(f.value)) return fmt::format("non-finite {} = {}", f.what, f.value);
    if (f.limit > 0 && std::abs(f.value) > f.limit)
      return fmt::format("{} = {:g} {} beyond +-{:g} {}", f.name, f.value, f.unit, f.limit, f.unit);
  }
  // tan(steering) of the odometry model: a wheel turned by pi/2 or more is no steering angle (a
  // steering of 1e308 quantized to Inf and gave a NaN heading increment).
  if (!(std::abs(m.steering) < M_PI / 2)) return fmt::format("steering = {:g} rad at or beyond +-pi/2", m.steering);
  return {};
}

TruthDriver::TruthDriver(bus::Bus& bus, const SystemConfig& cfg, std::string process, OnTruth on_truth,
                         std::function<void()> restart, std::function<Heartbeat::Counters()> extra)
    : bus_(bus),
      on_truth_(std::move(on_truth)),
      restart_(std::move(restart)),
      guard_(static_cast<int64_t>(std::llround(cfg.fusion.max_time_jump * 1e6))),
      heartbeat_(bus, cfg.channels.heartbeat, std::move(process), [this, extra = std::move(extra)] {
        Heartbeat::Counters c{{"received", received_},
                              {"published", published_},
                              {"gaps", gaps_.gaps()},
                              {"dropped", dropped_},
                              {"bad_truth", bad_truth_},
                              {"decode_errors", bus_.decodeErrors()}};
        if (extra)
          for (auto& kv : extra()) c.push_back(std::move(kv));
        return c;
      }) {
  bus.subscribe<lcmloc::ground_truth_t>(
      cfg.channels.ground_truth,
      [this](const std::string& ch, const lcmloc::ground_truth_t& m, int64_t) { onMessage(ch, m); });
}

void TruthDriver::onMessage(const std::string& ch, const lcmloc::ground_truth_t& m) {
  ++received_;
  const auto gap = gaps_.observe(ch, m.seq);
  if (gap.ignored && throttle_.allow(ch + ":ignored")) spdlog::warn("{}", app::printable(gap.describeIgnored(ch)));
  if (gap && throttle_.allow(ch)) spdlog::warn("{}", app::printable(gap.describe(ch)));
  // One rule for every driver, before the time guard and any sensor model: a NaN or a corrupt
  // utime would otherwise poison a model's state for good (an odometer stuck at NaN) or overflow
  // its time arithmetic.
  if (const std::string why = truthProblem(m); !why.empty()) {
    ++bad_truth_;
    if (throttle_.allow(ch + ":bad"))
      spdlog::warn("{} seq {} utime {}: {}: refused, no measurement from it ({} refused so far)", ch, m.seq,
                   m.utime, why, bad_truth_);
    return;
  }
  guard_.offer(
      lcmloc::ground_truth_t(m), m.utime,
      [&](lcmloc::ground_truth_t&& t) {
        guard_.took(t.utime);
        on_truth_(ch, t);
        return true;
      },
      [&](const lcmloc::ground_truth_t& t, int side, int64_t newest) {
        ++dropped_;
        if (throttle_.allow(ch + ":dropped"))
          spdlog::warn("{} seq {} utime {}: {} s {} the newest sample (utime {}), not followed by its time base: dropped",
                       ch, t.seq, t.utime, side > 0 ? core::secondsApart(t.utime, newest) : core::secondsApart(newest, t.utime),
                       side > 0 ? "ahead of" : "behind", newest);
      },
      [&](int side, const lcmloc::ground_truth_t& first, int64_t newest) {
        if (side > 0) {
          spdlog::info("{} seq {}: new time base: utime {} after {}", ch, first.seq, first.utime, newest);
          return;
        }
        spdlog::info("{} seq {}: time went back {} s (utime {} after {}): the simulator started over; so does the "
                     "sensor model",
                     ch, first.seq, core::secondsApart(newest, first.utime), first.utime, newest);
        restart_();
      });
}

int TruthDriver::run(const std::function<std::string()>& out) {
  while (!stopRequested()) {
    heartbeat_.tick();
    bus_.handle(100);
  }
  guard_.flush([&](const lcmloc::ground_truth_t&, int, int64_t) { ++dropped_; });
  spdlog::info("stopping: {} ground-truth samples in, {}, {} gaps{}{}", received_, out(), gaps_.gaps(),
               dropped_ ? ", " + std::to_string(dropped_) + " dropped (time far from the others)" : "",
               bad_truth_ ? ", " + std::to_string(bad_truth_) + " refused (bad ground truth)" : "");
  heartbeat_.publish("stopping");
  return kExitOk;
}

}  // namespace lcmloc::drivers
