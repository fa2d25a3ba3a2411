// lcmtypes <-> core structs, with NaN/Inf and range validation on the way in.
#include "lcmloc/bus/convert.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "lcmloc/wire.hpp"

namespace lcmloc::bus {

namespace {

constexpr double kHalfPi = 1.5707963267948966;
constexpr double kMaxStepDistance = 100.0;  // [m] per odometry increment: beyond is a broken sensor
constexpr double kMaxLateralOffset = 5.0;   // [m] far beyond any ruler's half width
// IMU readings beyond these are a broken sensor or a corrupt message, not motion: vehicle IMUs
// measure up to about 16 g and 35 rad/s (2000 deg/s), the earth's field is about 0.5 gauss.
constexpr double kMaxAccel = 1000.0;  // [m/s^2], about 100 g
constexpr double kMaxGyro = 100.0;    // [rad/s]
constexpr double kMaxMag = 100.0;     // [gauss]

// The checks run for every message; only a failure builds its reason (out of line: the fast
// path of a valid message is a few compares).
[[gnu::cold, gnu::noinline]] bool fail(std::string* why, const std::string& reason) {
  if (why) *why = reason;
  return false;
}

[[gnu::cold, gnu::noinline]] bool notFinite(double v, const char* name, std::string* why) {
  return fail(why, std::string(name) + " is " + (std::isnan(v) ? "NaN" : "Inf"));
}

inline bool finiteField(double v, const char* name, std::string* why) {
  return std::isfinite(v) || notFinite(v, name, why);
}

[[gnu::cold, gnu::noinline]] bool outOfRange(double v, double limit, const char* name, const char* unit,
                                             std::string* why) {
  char text[120];
  std::snprintf(text, sizeof text, "%s %g %s out of range (|%s| <= %g)", name, v, unit, name, limit);
  return fail(why, text);
}

inline bool withinField(double v, double limit, const char* name, const char* unit, std::string* why) {
  return std::abs(v) <= limit || outOfRange(v, limit, name, unit, why);
}

[[gnu::cold, gnu::noinline]] bool negativeUtime(int64_t utime, std::string* why) {
  return fail(why, "utime is negative (" + std::to_string(utime) + ")");
}

inline bool validUtime(int64_t utime, std::string* why) { return utime >= 0 || negativeUtime(utime, why); }

}  // namespace

bool toCore(const lcmloc::odometry_t& m, core::OdometryInput& out, std::string* why) {
  if (!validUtime(m.utime, why) || !finiteField(m.delta_s, "delta_s", why) ||
      !finiteField(m.steering, "steering", why) || !finiteField(m.delta_theta, "delta_theta", why))
    return false;
  if (std::abs(m.delta_s) > kMaxStepDistance) {
    fail(why, "delta_s " + std::to_string(m.delta_s) + " m out of range");
    return false;
  }
  if (m.has_steering && std::abs(m.steering) >= kHalfPi) {
    fail(why, "steering " + std::to_string(m.steering) + " rad out of range (-pi/2, pi/2)");
    return false;
  }
  if (!m.has_steering && std::abs(m.delta_theta) > M_PI) {
    fail(why, "delta_theta " + std::to_string(m.delta_theta) + " rad out of range [-pi, pi]");
    return false;
  }
  out.utime = m.utime;
  out.delta_s = m.delta_s;
  out.steering = m.steering;
  out.has_steering = m.has_steering;
  out.delta_theta = m.delta_theta;
  return true;
}

std::optional<core::OdometryInput> toCore(const lcmloc::odometry_t& m, std::string* why) {
  core::OdometryInput in;
  if (!toCore(m, in, why)) return std::nullopt;
  return in;
}

std::optional<core::RulerDetection> toCore(const lcmloc::magruler_t& m, const std::string& channel,
                                           std::string* why) {
  if (!m.detected) {
    if (why) why->clear();
    return std::nullopt;
  }
  if (!validUtime(m.utime, why) || !finiteField(m.lateral_offset, "lateral_offset", why) ||
      !finiteField(m.quality, "quality", why))
    return std::nullopt;
  for (std::size_t i = 0; i < m.readings.size(); ++i) {
    if (!std::isfinite(m.readings[i])) {
      fail(why, "readings[" + std::to_string(i) + "] is " + (std::isnan(m.readings[i]) ? "NaN" : "Inf"));
      return std::nullopt;
    }
  }
  if (std::abs(m.lateral_offset) > kMaxLateralOffset) {
    fail(why, "lateral_offset " + std::to_string(m.lateral_offset) + " m out of range");
    return std::nullopt;
  }
  if (m.quality < 0.0 || m.quality > 1.0) {
    fail(why, "quality " + std::to_string(m.quality) + " out of range [0, 1]");
    return std::nullopt;
  }
  core::RulerDetection d;
  d.utime = m.utime;
  d.lateral_offset = m.lateral_offset;
  d.quality = m.quality;
  d.sensor = channel;
  d.seq = m.seq;
  return d;
}


lcmloc::pose_t toLcm(const core::FilterState& s, const std::string& filter, int64_t seq) {
  lcmloc::pose_t m;
  const auto n = static_cast<int>(s.x.size());
  m.utime = s.utime;
  m.seq = seq;
  m.filter = filter;
  m.status = static_cast<int32_t>(s.status);
  m.dim = n;
  m.state.assign(s.x.data(), s.x.data() + n);
  m.state_names.resize(n);
  for (int i = 0; i < n; ++i)
    m.state_names[i] = i < static_cast<int>(s.names.size()) ? s.names[i] : "s" + std::to_string(i);
  m.covariance.assign(n, std::vector<double>(n, 0.0));
  for (int i = 0; i < n; ++i) {
    // P's part of the row, zeros beyond it (a P smaller than x)
    const int known = i < s.P.rows() ? std::min(n, static_cast<int>(s.P.cols())) : 0;
    for (int j = 0; j < known; ++j) m.covariance[i][j] = s.P(i, j);
  }
  return m;
}

namespace {

/// LCM's wire format: big-endian integers, IEEE doubles as their big-endian bit pattern, a string
/// as int32 strlen + 1 followed by its bytes and a NUL (lcm_coretypes.h).
struct WireWriter {
  uint8_t* p;
  void u64(uint64_t v) {
    wire::storeBig64(p, v);
    p += 8;
  }
  void u32(uint32_t v) {
    wire::storeBig32(p, v);
    p += 4;
  }
  void f64(double d) {
    uint64_t v;
    std::memcpy(&v, &d, 8);
    u64(v);
  }
  void str(const char* c, std::size_t len) {
    u32(static_cast<uint32_t>(len + 1));
    std::memcpy(p, c, len);
    p[len] = 0;
    p += len + 1;
  }
};

/// What lcm-gen's string encode writes of s: up to its first NUL (it encodes c_str()).
std::size_t wireLength(const std::string& s) { return std::strlen(s.c_str()); }

}  // namespace

std::size_t encodePose(const core::FilterState& s, const std::string& filter, int64_t seq,
                       std::vector<uint8_t>& out) {
  const auto n = static_cast<int>(s.x.size());
  const int named = std::min(n, static_cast<int>(s.names.size()));
  const int p_rows = std::min(n, static_cast<int>(s.P.rows()));
  const int p_cols = std::min(n, static_cast<int>(s.P.cols()));
  // Room for the strings at their full size (the encoding may stop a string at a NUL inside it:
  // the size returned is what was written).
  std::size_t room = 8 + 8 + 8 + (4 + filter.size() + 1) + 4 + 4 + 8 * static_cast<std::size_t>(n) * (n + 1);
  for (int i = 0; i < named; ++i) room += 4 + s.names[i].size() + 1;
  for (int i = named; i < n; ++i) room += 4 + std::to_string(i).size() + 2;  // "s<i>"
  if (out.size() < room) out.resize(room);
  WireWriter w{out.data()};
  w.u64(static_cast<uint64_t>(lcmloc::pose_t::getHash()));
  w.u64(static_cast<uint64_t>(s.utime));
  w.u64(static_cast<uint64_t>(seq));
  w.str(filter.c_str(), wireLength(filter));
  w.u32(static_cast<uint32_t>(static_cast<int32_t>(s.status)));
  w.u32(static_cast<uint32_t>(n));
  for (int i = 0; i < n; ++i) w.f64(s.x[i]);
  for (int i = 0; i < named; ++i) w.str(s.names[i].c_str(), wireLength(s.names[i]));
  for (int i = named; i < n; ++i) {
    const std::string name = "s" + std::to_string(i);
    w.str(name.c_str(), name.size());
  }
  // P's part of each row, zeros beyond it (a P smaller than x), as toLcm fills the rows.
  for (int i = 0; i < n; ++i) {
    const int known = i < p_rows ? p_cols : 0;
    for (int j = 0; j < known; ++j) w.f64(s.P(i, j));
    for (int j = known; j < n; ++j) w.f64(0.0);
  }
  return static_cast<std::size_t>(w.p - out.data());
}

lcmloc::gate_decision_t toLcm(const core::GateDecision& d, const std::string& filter, int64_t seq) {
  lcmloc::gate_decision_t m;
  m.utime = d.utime;
  m.seq = seq;
  m.filter = filter;
  m.sensor = d.sensor;
  m.measurement_seq = d.measurement_seq;
  m.dim = static_cast<int32_t>(d.innovation.size());
  m.innovation.assign(d.innovation.data(), d.innovation.data() + d.innovation.size());
  m.mahalanobis = d.mahalanobis;
  m.gate = d.gate;
  m.accepted = d.accepted;
  m.marker_id = d.marker_id;
  m.reason = d.reason;
  return m;
}

core::FilterState toCore(const lcmloc::pose_t& m) {
  core::FilterState s;
  const int n = std::max(0, std::min<int>(m.dim, static_cast<int>(m.state.size())));
  s.utime = m.utime;
  s.x = Eigen::VectorXd::Zero(n);
  s.P = Eigen::MatrixXd::Zero(n, n);
  for (int i = 0; i < n; ++i) {
    s.x[i] = m.state[i];
    if (i < static_cast<int>(m.state_names.size())) s.names.push_back(m.state_names[i]);
    for (int j = 0; j < n; ++j)
      if (i < static_cast<int>(m.covariance.size()) && j < static_cast<int>(m.covariance[i].size()))
        s.P(i, j) = m.covariance[i][j];
  }
  s.status = static_cast<core::FilterStatus>(m.status);
  return s;
}

std::optional<core::ImuInput> toCore(const lcmloc::imu_t& m, const std::string& channel,
                                     std::string* why) {
  if (!validUtime(m.utime, why)) return std::nullopt;
  static const char* const kAccel[] = {"accel[0]", "accel[1]", "accel[2]"};
  static const char* const kGyro[] = {"gyro[0]", "gyro[1]", "gyro[2]"};
  static const char* const kMag[] = {"mag[0]", "mag[1]", "mag[2]"};
  for (int i = 0; i < 3; ++i)
    if (!finiteField(m.accel[i], kAccel[i], why) || !finiteField(m.gyro[i], kGyro[i], why) ||
        !finiteField(m.mag[i], kMag[i], why) || !withinField(m.accel[i], kMaxAccel, kAccel[i], "m/s^2", why) ||
        !withinField(m.gyro[i], kMaxGyro, kGyro[i], "rad/s", why) || !withinField(m.mag[i], kMaxMag, kMag[i], "gauss", why))
      return std::nullopt;
  core::ImuInput in;
  in.utime = m.utime;
  in.accel = core::Vec3(m.accel[0], m.accel[1], m.accel[2]);
  in.gyro = core::Vec3(m.gyro[0], m.gyro[1], m.gyro[2]);
  in.mag = core::Vec3(m.mag[0], m.mag[1], m.mag[2]);
  in.sensor = channel;
  in.seq = m.seq;
  return in;
}

std::optional<core::GpsInput> toCore(const lcmloc::gps_fix_t& m, const std::string& channel,
                                     const LocalFrame& frame, std::string* why) {
  if (!validUtime(m.utime, why)) return std::nullopt;
  core::GpsInput in;
  in.utime = m.utime;
  in.sensor = channel;
  in.seq = m.seq;
  in.has_fix = m.fix_type >= 2;
  if (!in.has_fix) return in;
  if (!finiteField(m.latitude, "latitude", why) || !finiteField(m.longitude, "longitude", why))
    return std::nullopt;
  if (std::abs(m.latitude) > 90.0 || std::abs(m.longitude) > 180.0) {
    fail(why, "latitude/longitude out of range");
    return std::nullopt;
  }
  if (m.position_std < 0) {  // (NaN: not known, the filter's default; 0 too)
    fail(why, "position_std must be >= 0 (0 or NaN: not known)");
    return std::nullopt;
  }
  const double h = std::isfinite(m.altitude) ? m.altitude : frame.datum().altitude;
  double z = 0.0;
  frame.toLocal(m.latitude, m.longitude, h, in.x, in.y, z);
  in.position_std = std::isfinite(m.position_std) ? m.position_std : 0.0;
  return in;
}


std::optional<core::LandmarkObservation> toCore(const lcmloc::landmark_obs_t& m, const std::string& channel,
                                                std::string* why) {
  if (!validUtime(m.utime, why) || !finiteField(m.range, "range", why) || !finiteField(m.bearing, "bearing", why) ||
      !finiteField(m.range_std, "range_std", why) || !finiteField(m.bearing_std, "bearing_std", why))
    return std::nullopt;
  if (m.range < 0 || m.range_std < 0 || m.bearing_std < 0) {
    fail(why, "range and stds must be >= 0");
    return std::nullopt;
  }
  if (std::abs(m.bearing) > M_PI) {
    fail(why, "bearing " + std::to_string(m.bearing) + " rad out of range [-pi, pi]");
    return std::nullopt;
  }
  if (m.landmark_id < -1) {
    fail(why, "landmark_id " + std::to_string(m.landmark_id) + " (valid: >= 0, or -1 = unknown)");
    return std::nullopt;
  }
  core::LandmarkObservation o;
  o.utime = m.utime;
  o.landmark_id = m.landmark_id;
  o.range = m.range;
  o.bearing = m.bearing;
  o.range_std = m.range_std;
  o.bearing_std = m.bearing_std;
  o.sensor = channel;
  o.seq = m.seq;
  return o;
}

std::optional<core::BeaconRange> toCore(const lcmloc::beacon_range_t& m, const std::string& channel,
                                        std::string* why) {
  if (!validUtime(m.utime, why) || !finiteField(m.range, "range", why) || !finiteField(m.range_std, "range_std", why))
    return std::nullopt;
  if (m.range < 0 || m.range_std < 0) {
    fail(why, "range and range_std must be >= 0");
    return std::nullopt;
  }
  core::BeaconRange b;
  b.utime = m.utime;
  b.beacon_id = m.beacon_id;
  b.range = m.range;
  b.range_std = m.range_std;
  b.sensor = channel;
  b.seq = m.seq;
  return b;
}

std::optional<core::BearingsInput> toCore(const lcmloc::landmark_bearings_t& m, const std::string& channel,
                                          std::string* why) {
  if (!validUtime(m.utime, why)) return std::nullopt;
  if (m.count < 0 || static_cast<std::size_t>(m.count) != m.landmark_ids.size() ||
      static_cast<std::size_t>(m.count) != m.bearings.size()) {
    fail(why, "count does not match the landmark_ids/bearings arrays");
    return std::nullopt;
  }
  for (double b : m.bearings)
    if (!finiteField(b, "bearings[]", why)) return std::nullopt;
  if (m.bearing_std < 0) {  // (NaN or 0: the engine's default)
    fail(why, "bearing_std must be >= 0 (0 or NaN: the default)");
    return std::nullopt;
  }
  core::BearingsInput in;
  in.utime = m.utime;
  in.seq = m.seq;
  in.sensor = channel;
  in.ids.assign(m.landmark_ids.begin(), m.landmark_ids.end());
  in.bearings.assign(m.bearings.begin(), m.bearings.end());
  in.bearing_std = m.bearing_std;
  return in;
}


namespace {
/// A converted measurement into out, or Refused (why set by the conversion).
template <typename T>
Converted into(std::optional<T>&& v, core::InputPayload& out, std::string& why) {
  if (!v) {
    if (why.empty()) why = "refused";
    return Converted::Refused;
  }
  out = std::move(*v);
  return Converted::Input;
}
}  // namespace

Converted toInput(const lcmloc::odometry_t& m, const InputContext&, core::InputPayload& out, std::string& why) {
  // Converted in place (into the odometry input a reused item nearly always holds already): a
  // converted copy handed back and then moved in costs more than the conversion, as the copy's
  // bytes are read back right after they were written, before the CPU can forward them.
  auto* odo = std::get_if<core::OdometryInput>(&out);
  if (!odo) odo = &out.emplace<core::OdometryInput>();
  return toCore(m, *odo, &why) ? Converted::Input : Converted::Refused;
}
Converted toInput(const lcmloc::magruler_t& m, const InputContext& ctx, core::InputPayload& out, std::string& why) {
  auto det = toCore(m, ctx.channel, &why);
  if (!det && why.empty()) return Converted::Nothing;  // a raw reading without detection
  return into(std::move(det), out, why);
}
Converted toInput(const lcmloc::imu_t& m, const InputContext& ctx, core::InputPayload& out, std::string& why) {
  return into(toCore(m, ctx.channel, &why), out, why);
}
Converted toInput(const lcmloc::gps_fix_t& m, const InputContext& ctx, core::InputPayload& out, std::string& why) {
  return into(toCore(m, ctx.channel, ctx.frame, &why), out, why);
}
Converted toInput(const lcmloc::landmark_obs_t& m, const InputContext& ctx, core::InputPayload& out,
                  std::string& why) {
  return into(toCore(m, ctx.channel, &why), out, why);
}
Converted toInput(const lcmloc::beacon_range_t& m, const InputContext& ctx, core::InputPayload& out,
                  std::string& why) {
  return into(toCore(m, ctx.channel, &why), out, why);
}
Converted toInput(const lcmloc::landmark_bearings_t& m, const InputContext& ctx, core::InputPayload& out,
                  std::string& why) {
  return into(toCore(m, ctx.channel, &why), out, why);
}

}  // namespace lcmloc::bus
