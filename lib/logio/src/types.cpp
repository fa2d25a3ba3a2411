#include "lcmloc/logio/types.hpp"

#include <cstdio>
#include <new>
#include <stdexcept>

#include "lcmloc/fault_event_t.hpp"
#include "lcmloc/fusion_control_t.hpp"
#include "lcmloc/fusion_status_t.hpp"
#include "lcmloc/fusion_timing_t.hpp"
#include "lcmloc/gate_decision_t.hpp"
#include "lcmloc/gps_fix_t.hpp"
#include "lcmloc/ground_truth_t.hpp"
#include "lcmloc/heartbeat_t.hpp"
#include "lcmloc/imu_t.hpp"
#include "lcmloc/landmark_bearings_t.hpp"
#include "lcmloc/logger_status_t.hpp"
#include "lcmloc/magruler_t.hpp"
#include "lcmloc/odometry_t.hpp"
#include "lcmloc/pose_t.hpp"
#include "lcmloc/landmark_obs_t.hpp"
#include "lcmloc/beacon_range_t.hpp"
#include "lcmloc/wire.hpp"

namespace lcmloc::logger {
namespace {

/// Collects named values; vectors expand to name_i (and name_i_j).
class Visitor {
 public:
  explicit Visitor(Fields* out) : out_(out) {}
  void operator()(const std::string& n, double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.17g", v);
    add(n, b);
  }
  void operator()(const std::string& n, float v) { (*this)(n, static_cast<double>(v)); }
  void operator()(const std::string& n, int64_t v) { add(n, std::to_string(v)); }
  void operator()(const std::string& n, int32_t v) { add(n, std::to_string(v)); }
  void operator()(const std::string& n, int16_t v) { add(n, std::to_string(v)); }
  void operator()(const std::string& n, int8_t v) { add(n, std::to_string(static_cast<int>(v))); }
  void operator()(const std::string& n, bool v) { add(n, v ? "1" : "0"); }
  void operator()(const std::string& n, const std::string& v) { out_->push_back({n, v, true}); }
  template <typename T>
  void operator()(const std::string& n, const std::vector<T>& v) {
    for (std::size_t i = 0; i < v.size(); ++i) (*this)(n + "_" + std::to_string(i), v[i]);
  }
  template <typename T, std::size_t N>
  void operator()(const std::string& n, const T (&v)[N]) {
    for (std::size_t i = 0; i < N; ++i) (*this)(n + "_" + std::to_string(i), v[i]);
  }

 private:
  void add(const std::string& n, std::string v) { out_->push_back({n, std::move(v), false}); }
  Fields* out_;
};

#define F(x) v(#x, m.x)
void visit(const fault_event_t& m, Visitor& v) { F(utime); F(seq); F(kind); F(channel); F(measurement_seq); F(x); F(y); F(lateral_offset); }
void visit(const fusion_control_t& m, Visitor& v) { F(utime); F(seq); F(command); F(filter); F(parameters); F(pose); F(pose_std); }
void visit(const fusion_status_t& m, Visitor& v) {
  F(utime); F(seq); F(filter); F(status); F(event); F(detail); F(messages_in); F(messages_used);
  F(messages_rejected); F(sequence_gaps);
}
void visit(const fusion_timing_t& m, Visitor& v) {
  F(utime); F(seq); F(window); F(num_channels); F(channel); F(delay_p50); F(delay_max); F(age); F(rate); F(count);
  F(late); F(late_max); F(steps); F(step_p50); F(step_p99); F(step_max); F(horizon); F(released_early);
}
void visit(const gate_decision_t& m, Visitor& v) {
  F(utime); F(seq); F(filter); F(sensor); F(measurement_seq); F(dim); F(innovation); F(mahalanobis); F(gate);
  F(accepted); F(marker_id); F(reason);
}
void visit(const gps_fix_t& m, Visitor& v) {
  F(utime); F(seq); F(latitude); F(longitude); F(altitude); F(fix_type); F(satellites); F(hdop); F(position_std);
}
void visit(const ground_truth_t& m, Visitor& v) { F(utime); F(seq); F(x); F(y); F(heading); F(speed); F(steering); F(distance); }
void visit(const heartbeat_t& m, Visitor& v) {
  F(utime); F(seq); F(process); F(pid); F(state); F(num_counters);
  // Counters by name: one column per counter, far easier to plot than parallel arrays.
  for (std::size_t i = 0; i < m.counters.size() && i < m.counter_names.size(); ++i)
    v("counter_" + m.counter_names[i], m.counters[i]);
}
void visit(const imu_t& m, Visitor& v) { F(utime); F(seq); F(accel); F(gyro); F(mag); }
void visit(const landmark_bearings_t& m, Visitor& v) { F(utime); F(seq); F(count); F(landmark_ids); F(bearings); F(bearing_std); }
void visit(const logger_status_t& m, Visitor& v) {
  F(utime); F(seq); F(state); F(file); F(files); F(bytes_written); F(received); F(written); F(dropped);
  F(write_lost); F(gaps); F(flushed_events); F(queue_depth); F(queue_capacity); F(num_channels); F(channels);
  F(channel_received); F(channel_dropped); F(channel_gaps);
}
void visit(const magruler_t& m, Visitor& v) {
  F(utime); F(seq); F(num_sensors); F(readings); F(detected); F(lateral_offset); F(quality);
}
void visit(const odometry_t& m, Visitor& v) { F(utime); F(seq); F(delta_s); F(ticks); F(steering); F(has_steering); F(delta_theta); }
void visit(const pose_t& m, Visitor& v) {
  F(utime); F(seq); F(filter); F(status); F(dim); F(state); F(state_names);
  for (std::size_t i = 0; i < m.covariance.size(); ++i) v("covariance_" + std::to_string(i), m.covariance[i]);
}
void visit(const landmark_obs_t& m, Visitor& v) {
  F(utime); F(seq); F(landmark_id); F(range); F(bearing); F(range_std); F(bearing_std);
}
void visit(const beacon_range_t& m, Visitor& v) { F(utime); F(seq); F(beacon_id); F(range); F(range_std); }
#undef F

template <typename T>
TypeInfo entry() {
  TypeInfo t;
  t.hash = T::getHash();
  t.name = std::string("lcmloc.") + T::getTypeName();
  t.fields = [](const uint8_t* data, std::size_t size, Fields* out) {
    T m{};
    try {
      if (m.decode(data, 0, static_cast<int>(size)) < 0) return false;
    } catch (const std::bad_alloc&) {
      return false;  // absurd array length
    } catch (const std::length_error&) {
      return false;  // negative array length
    }
    if (out) {
      Visitor v(out);
      visit(m, v);
    }
    return true;
  };
  return t;
}

}  // namespace

const std::vector<TypeInfo>& knownTypes() {
  static const std::vector<TypeInfo> types{
      entry<fault_event_t>(),  entry<fusion_control_t>(), entry<fusion_status_t>(), entry<fusion_timing_t>(),
      entry<gate_decision_t>(),
      entry<gps_fix_t>(),      entry<ground_truth_t>(),   entry<heartbeat_t>(),     entry<imu_t>(),
      entry<landmark_bearings_t>(), entry<logger_status_t>(), entry<magruler_t>(), entry<odometry_t>(),
      entry<pose_t>(), entry<landmark_obs_t>(), entry<beacon_range_t>()};
  return types;
}

bool readFingerprint(const uint8_t* data, std::size_t size, int64_t* hash) {
  if (size < 8) return false;
  *hash = static_cast<int64_t>(wire::loadBig64(data));
  return true;
}

const TypeInfo* findType(const uint8_t* data, std::size_t size) {
  int64_t h = 0;
  if (!readFingerprint(data, size, &h)) return nullptr;
  for (const auto& t : knownTypes())
    if (t.hash == h) return &t;
  return nullptr;
}

bool readSeq(const uint8_t* data, std::size_t size, int64_t* seq) {
  if (size < 24) return false;
  *seq = static_cast<int64_t>(wire::loadBig64(data + 16));
  return true;
}

}  // namespace lcmloc::logger
