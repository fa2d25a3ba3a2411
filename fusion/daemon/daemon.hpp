#pragma once
// The fusion daemon: LCM in (ODOMETRY, MAGRULER channels, FUSION_CONTROL), validation and
// conversion, core::FusionEngine, LCM out (POSE, POSE_<TYPE>, GATE, FUSION_STATUS).
// Bad input never stops it: each rejected message gets a log line (rate-limited) and a status
// event, and is counted.
#include <cstdint>
#include <map>
#include <memory>
#include <string>

#include "lcmloc/common/config.hpp"
#include "lcmloc/common/geodesy.hpp"
#include "lcmloc/common/process.hpp"
#include "lcmloc/common/transport.hpp"
#include "lcmloc/core/engine.hpp"
#include "lcmloc/fusion_control_t.hpp"
#include "lcmloc/gps_fix_t.hpp"
#include "lcmloc/imu_t.hpp"
#include "lcmloc/magruler_t.hpp"
#include "lcmloc/odometry_t.hpp"

namespace lcmloc::fusion {

class FusionDaemon {
 public:
  FusionDaemon(const common::SystemConfig& cfg, common::Bus& bus);
  /// Processes everything still in the reorder window and publishes a final status.
  void shutdown();
  common::Heartbeat::Counters counters() const;

 private:
  void onOdometry(const std::string& ch, const lcmloc::odometry_t& m);
  void onRuler(const std::string& ch, const lcmloc::magruler_t& m);
  void onControl(const std::string& ch, const lcmloc::fusion_control_t& m);
  void onImu(const std::string& ch, const lcmloc::imu_t& m);
  void onGps(const std::string& ch, const lcmloc::gps_fix_t& m);
  void onDecodeError(const std::string& ch, const std::string& why);

  bool received(const std::string& ch, int64_t seq);     ///< counts and checks the seq gap
  void push(core::EngineInput in);
  void reject(const std::string& ch, int64_t seq, int64_t utime, const std::string& why);
  void publishState(const std::string& filter, bool active, const core::FilterState& s);
  void publishStatus(const std::string& event, const std::string& detail, int64_t utime);
  std::string poseChannel(const std::string& filter, bool active) const;

  const common::SystemConfig& cfg_;
  common::Bus& bus_;
  std::unique_ptr<core::FusionEngine> engine_;
  common::SeqTracker gaps_;
  common::LocalFrame frame_;  ///< lat/lon of GPS fixes -> local metric frame (cfg.datum)
  std::map<std::string, int64_t> out_seq_;  ///< per output channel
  std::map<std::string, int64_t> log_count_;
  int64_t messages_in_ = 0, rejected_ = 0, last_utime_ = 0, next_status_utime_ = INT64_MIN;
  core::FilterStatus last_status_ = core::FilterStatus::Uninitialized;
  bool event_seen_ = false;
};

}  // namespace lcmloc::fusion
