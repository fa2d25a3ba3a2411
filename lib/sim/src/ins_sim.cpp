#include "lcmloc/sim/ins_sim.hpp"

#include <cmath>
#include <stdexcept>

#include "lcmloc/core/angles.hpp"
#include "lcmloc/sim/scenario_config.hpp"

namespace lcmloc::sim {
namespace {
constexpr double kDeg = M_PI / 180.0;
constexpr double kG = 9.78;  // as ins::ImuGrade
void require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("ins_sim: " + what);
}
}  // namespace

bool insStartValid(const std::string& start) {
  return start == "hard" || start == "gentle" || start == "gentle_turn" || start == "gentle_stopgo" ||
         start == "steady";
}

std::vector<InsMotionSegment> insProfile(const InsSimConfig& cfg) {
  if (cfg.profile == "custom") return cfg.segments;
  std::vector<InsMotionSegment> p;
  auto add = [&](double d, double a, double r) { p.push_back({d, a, r}); };
  add(2.0, 0.0, 0.0);  // standing
  if (cfg.start == "gentle") {
    add(60.0, 0.2, 0.0);  // steady gentle acceleration from rest to 12 m/s
  } else if (cfg.start == "gentle_turn") {
    add(2.0, 0.2, 0.0);   // the same with an early S-turn at walking speed
    add(3.0, 0.2, 15.0);
    add(3.0, 0.2, -15.0);
    add(52.0, 0.2, 0.0);
  } else if (cfg.start == "gentle_stopgo") {
    for (int i = 0; i < 2; ++i) {  // two moderate stop-and-go pulses, then 0.5 m/s^2 to 12 m/s
      add(3.0, 0.5, 0.0);
      add(3.0, -0.5, 0.0);
      add(1.0, 0.0, 0.0);
    }
    add(24.0, 0.5, 0.0);
  } else if (cfg.start == "steady") {
    add(12.0, 1.0, 0.0);  // 1 m/s^2 from rest to 12 m/s
  } else {
    add(4.0, 3.0, 0.0);    // hard start to 12 m/s
    add(3.0, 0.0, 10.0);   // early turn left 30 deg ...
    add(3.0, 0.0, -10.0);  // ... and back
    add(6.0, 0.0, 0.0);
    add(4.0, -3.0, 0.0);   // stop ...
    add(3.0, 0.0, 0.0);
    add(4.0, 3.0, 0.0);    // ... and go
  }
  {
    double t0 = 0.0;
    for (const auto& s : p) t0 += s.duration;
    add(std::max(1.0, 102.0 - t0), 0.0, 0.0);  // cruise at 12 m/s until 102 s
  }
  add(7.0, 1.0, 0.0);  // speeding up to 19 m/s
  double t = 0.0;
  for (const auto& s : p) t += s.duration;
  // Cruise with 90-degree turns every 300 s (left, left, right, right, ...), one traffic stop,
  // and a stop at the end.
  const double end = cfg.duration;
  int block = 0;
  while (t + 300.0 + 40.0 < end) {
    if (block == 5) {
      add(19.0, -1.0, 0.0);
      add(30.0, 0.0, 0.0);
      add(19.0, 1.0, 0.0);
      t += 68.0;
    }
    add(240.0, 0.0, 0.0);
    add(30.0, 0.0, (block / 2) % 2 == 0 ? 3.0 : -3.0);
    add(30.0, 0.0, 0.0);
    t += 300.0;
    ++block;
  }
  add(std::max(0.0, end - t - 40.0), 0.0, 0.0);
  add(19.0, -1.0, 0.0);
  add(21.0, 0.0, 0.0);
  return p;
}

InsSim::InsSim(const InsSimConfig& cfg, int64_t start_utime)
    : cfg_(cfg), start_utime_(start_utime),
      rng_imu_(componentSeed(cfg.seed, "ins_imu")), rng_odo_(componentSeed(cfg.seed, "ins_odometer")) {
  require(cfg.rate_hz > 0 && cfg.rate_hz <= 10000, "rate_hz must be in (0, 10000]");
  require(cfg.odometry_divider >= 1, "odometry_divider must be >= 1");
  require(cfg.duration > 0, "duration must be > 0");
  require(cfg.profile == "paper" || cfg.profile == "custom", "profile must be paper or custom");
  require(insStartValid(cfg.start), "start must be one of hard, gentle, gentle_turn, gentle_stopgo, steady");
  require(cfg.profile != "custom" || !cfg.segments.empty(), "the custom profile needs segments");
  require(std::abs(cfg.latitude) < 89.0, "latitude must be within (-89, 89)");
  require(cfg.gyro_tau > 0 && cfg.accel_tau > 0 && cfg.scale_tau > 0, "correlation times must be > 0");
  segs_ = insProfile(cfg);
  dt_ = 1.0 / cfg.rate_hz;
  n_steps_ = static_cast<int64_t>(std::llround(cfg.duration * cfg.rate_hz));
  ins::InsState s;
  s.lat = lat0_ = cfg.latitude * kDeg;
  s.lon = lon0_ = cfg.longitude * kDeg;
  s.h = cfg.height;
  s.q_bn = Eigen::Quaterniond(ins::cbnFromHeading(M_PI / 2 - cfg.heading));
  truth_ = ins::Ins(s, true);
  const ins::Radii r = ins::radii(lat0_);
  sy_ = r.rm + cfg.height;
  sx_ = (r.rn + cfg.height) * std::cos(lat0_);
  // Stationary start of the Markov sensor errors (the odometer's Markov part starts at 0).
  for (int i = 0; i < 3; ++i) gyro_bias_[i] = cfg.gyro_markov * ins::kDegPerHour * n01_(rng_imu_);
  for (int i = 0; i < 2; ++i) accel_bias_[i] = cfg.accel_markov * kG * n01_(rng_imu_);
}

core::Vec2 InsSim::toLocal(double lat, double lon) const {
  return {(lon - lon0_) * sx_, (lat - lat0_) * sy_};
}

InsSimStep InsSim::initial() const {
  InsSimStep out;
  out.truth_nav = truth_.state();
  out.truth.utime = start_utime_;
  out.truth.heading = core::wrapAngle(M_PI / 2 - ins::headingOf(truth_.state().cbn()));
  out.scale_error = cfg_.scale_error;
  return out;
}

InsSimStep InsSim::step() {
  // Motion command of this step.
  double acc = 0.0, yaw = 0.0;
  while (seg_ < segs_.size() && seg_t_ >= segs_[seg_].duration - 1e-9) {
    seg_t_ = 0.0;
    ++seg_;
  }
  if (seg_ < segs_.size()) {
    acc = segs_[seg_].accel;
    yaw = segs_[seg_].yaw_rate * kDeg;
  }
  seg_t_ += dt_;
  if (speed_ + acc * dt_ < 0.0) acc = -speed_ / dt_;
  // Ideal IMU of the level vehicle: forward acceleration, centripetal acceleration to the left
  // for a CCW turn, rotation about up (INS body frame x right, y forward, z up).
  const ins::InsState& s = truth_.state();
  const ins::Mat3 C = s.cbn();
  const ins::Vec3 a_b(-yaw * speed_, acc, 0.0);
  ins::Vec3 w, f;
  ins::idealImu(s, C * a_b, ins::Vec3(0, 0, yaw), &w, &f);
  truth_.step(w, f, dt_);
  speed_ += acc * dt_;
  // No side slip: the truth velocity is the speed along the body forward axis.
  truth_.state().v = truth_.state().cbn() * ins::Vec3(0, speed_, 0);
  distance_ += speed_ * dt_ - 0.5 * acc * dt_ * dt_;
  ++k_;

  InsSimStep out;
  const int64_t utime = start_utime_ + static_cast<int64_t>(std::llround(k_ * 1e6 / cfg_.rate_hz));
  out.truth_nav = truth_.state();
  const core::Vec2 p = toLocal(out.truth_nav.lat, out.truth_nav.lon);
  out.truth.utime = utime;
  out.truth.x = p.x();
  out.truth.y = p.y();
  out.truth.heading = core::wrapAngle(M_PI / 2 - ins::headingOf(out.truth_nav.cbn()));
  out.truth.speed = speed_;
  out.truth.distance = distance_;

  // Sensor errors: first-order Markov updates and white noise (std of a 1 s average -> per sample).
  const double sq = std::sqrt(dt_);
  const double eg = std::exp(-dt_ / cfg_.gyro_tau), ea = std::exp(-dt_ / cfg_.accel_tau);
  const double gm = cfg_.gyro_markov * ins::kDegPerHour, am = cfg_.accel_markov * kG;
  for (int i = 0; i < 3; ++i) gyro_bias_[i] = eg * gyro_bias_[i] + gm * std::sqrt(1 - eg * eg) * n01_(rng_imu_);
  for (int i = 0; i < 2; ++i) accel_bias_[i] = ea * accel_bias_[i] + am * std::sqrt(1 - ea * ea) * n01_(rng_imu_);
  ins::Vec3 wm = w + gyro_bias_, fm = f + accel_bias_;
  for (int i = 0; i < 3; ++i) wm[i] += cfg_.gyro_white * ins::kDegPerHour / sq * n01_(rng_imu_);
  for (int i = 0; i < 2; ++i) fm[i] += cfg_.accel_white * kG / sq * n01_(rng_imu_);
  bool dropped = false;
  const double t = k_ * dt_;
  for (const auto& d : cfg_.imu_dropouts)
    if (t >= d.first && t < d.first + d.second) dropped = true;
  if (!dropped) {
    ImuSample m;
    m.utime = utime;
    // INS body (x right, y forward, z up) -> imu_t body (x forward, y left, z up).
    m.gyro = core::Vec3(wm.y(), -wm.x(), wm.z());
    m.accel = core::Vec3(fm.y(), -fm.x(), fm.z());
    m.mag = core::Vec3::Zero();
    out.imu = m;
  }

  // Odometer.
  const double es = std::exp(-dt_ / cfg_.scale_tau);
  scale_markov_ = es * scale_markov_ + cfg_.scale_markov * std::sqrt(1 - es * es) * n01_(rng_odo_);
  out.scale_error = cfg_.scale_error + scale_markov_;
  if (k_ % cfg_.odometry_divider == 0) {
    const double ds_true = distance_ - odo_distance_true_;
    odo_distance_true_ = distance_;
    const double k = out.scale_error + cfg_.scale_white * n01_(rng_odo_);
    OdometrySample o;
    o.input.utime = utime;
    o.input.delta_s = ds_true * (1.0 + k);
    o.input.has_steering = false;
    o.input.delta_theta = 0.0;  // the odometer of this method measures distance only
    o.ticks = 0;  // no encoder ticks: a continuous distance
    out.odometry = o;
  }
  return out;
}

}  // namespace lcmloc::sim
