#pragma once
// One run of the default magnetic system under lcmloc-launcher (config/system.yaml), watched from
// outside over LCM: every POSE (message time, wall time of arrival, finite or not), the ground
// truth, the daemon's FUSION_STATUS events, and the daemon's RSS from /proc once per second.
// Beside the system, on the same URL, one of:
//  - nothing (the clean run);
//  - a second publisher that sends each kind of bad message (lcmloc/hostile/messages.hpp) on
//    every input channel, round robin, with its own seq stream and times near the live time (on
//    the odometry's and the ruler's channels once the system's own stream is there, unless
//    hostile_first);
//  - a corrupter that republishes a corrupted copy of a random fraction of the messages on the
//    daemon's input channels (one byte flipped, the body cut, or random bytes of the same size).
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace lcmloc::hostile {

enum class Disturbance { kNone, kHostile, kCorrupt };

struct LiveRunOptions {
  std::string bin_dir;       ///< where lcmloc-launcher, lcmloc-sim and the processes are
  std::string system;        ///< the launcher's system file (config/system.yaml)
  std::string scenario;      ///< the base scenario (config/paper.yaml, config/oval.yaml)
  std::string out_dir;       ///< scenario.yaml, map.csv, run.lcmlog, launcher.out of this run
  std::string lcm_url = "udpm://239.255.76.67:7693?ttl=0";
  double factor = 1.0;       ///< real-time factor (the reorder window and time-jump guard scaled by it above 1)
  int laps = 1;              ///< the base path driven this many times (markers all along); 0: enough for duration_s
  double duration_s = 0;     ///< [s, wall] stop the system after this long; 0: when the simulation ends
  Disturbance disturbance = Disturbance::kNone;
  double hostile_rate = 1000;  ///< hostile messages per second [1/s, wall]
  /// false: on a channel the system's drivers publish on (odometry, ruler) the hostile publisher
  /// starts after the system's own stream (a second publisher); true: from the start (it may be
  /// the first there).
  bool hostile_first = false;
  double corrupt_fraction = 0.01;
  uint64_t seed = 1;
};

struct LiveRunResult {
  bool from_log = false;                   ///< the POSE figures are the logger's log's (else the watcher's)
  int64_t poses = 0, non_finite = 0;       ///< POSE messages, of which with a NaN or Inf
  double rmse = 0, max_error = 0;          ///< [m] POSE against the interpolated ground truth
  int64_t scored = 0;                      ///< poses scored (within the truth)
  double max_gap_msg_s = 0;                ///< longest step of POSE's message time [s]
  double max_silence_wall_s = 0;           ///< longest wall time between two POSE arrivals while the odometry came [s]
  double pose_period_s = 0;                ///< the odometry's period (POSE comes per odometry) [s]
  int64_t gaps_over = 0;                   ///< steps of POSE's message time above 2 periods
  int64_t silences_over = 0;               ///< wall times between POSE arrivals above 2 periods / factor
  int64_t sent = 0;                        ///< disturbing messages sent
  std::map<std::string, int64_t> sent_per_channel;
  std::set<std::string> live_channels;     ///< input channels the system itself published on
  /// channel -> the status's words on its other stream ("second_publisher: ..." or, when the
  /// system's own publisher was silent long enough to be taken for restarted, "source_replaced: ...")
  std::map<std::string, std::string> second_publisher;
  std::string last_status;                 ///< detail of the daemon's last periodic status
  std::vector<std::pair<double, int64_t>> rss_kb;  ///< (wall s since start, daemon VmRSS kB)
  int daemon_pids = 0;                     ///< lcmloc-fusion processes seen (1: never restarted)
  int launcher_exit = -1;
  double wall_s = 0;
};

/// Runs the system once. Throws std::runtime_error when it cannot be started or gives no POSE.
LiveRunResult runLive(const LiveRunOptions& o);

}  // namespace lcmloc::hostile
