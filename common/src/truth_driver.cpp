#include "lcmloc/common/truth_driver.hpp"

#include <spdlog/spdlog.h>

namespace lcmloc::common {

TruthDriver::TruthDriver(Bus& bus, const SystemConfig& cfg, std::string process, OnTruth on_truth,
                         std::function<Heartbeat::Counters()> extra)
    : bus_(bus),
      heartbeat_(bus, cfg.channels.heartbeat, std::move(process), [this, extra = std::move(extra)] {
        Heartbeat::Counters c{{"received", received_},
                              {"published", published_},
                              {"gaps", gaps_.gaps()},
                              {"decode_errors", bus_.decodeErrors()}};
        if (extra)
          for (auto& kv : extra()) c.push_back(std::move(kv));
        return c;
      }) {
  bus.subscribe<lcmloc::ground_truth_t>(
      cfg.channels.ground_truth,
      [this, on_truth = std::move(on_truth)](const std::string& ch, const lcmloc::ground_truth_t& m, int64_t) {
        ++received_;
        if (const auto gap = gaps_.observe(ch, m.seq))
          if (throttle_.allow(ch)) spdlog::warn("{}", gap.describe(ch));
        on_truth(ch, m);
      });
}

int TruthDriver::run(const std::function<std::string()>& out) {
  while (!stopRequested()) {
    heartbeat_.tick();
    bus_.handle(100);
  }
  spdlog::info("stopping: {} ground-truth samples in, {}, {} gaps", received_, out(), gaps_.gaps());
  heartbeat_.publish("stopping");
  return kExitOk;
}

}  // namespace lcmloc::common
