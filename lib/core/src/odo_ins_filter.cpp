// The odometry/INS filters of Wang & Wang §II behind the Filter interface:
//   "odo_ins"        the 14-state closed-loop Kalman filter with online odometer scale
//                    calibration (ins::OdoInsFilter, eq. 2-8);
//   "odo_ins_uncal"  the traditional odometry/INS integration that ignores the scale error
//                    (the same filter with dKc, dKr held at 0).
// IMU samples (Filter::update(ImuInput)) drive the INS; odometry increments (predict) are queued
// and applied as velocity measurements once the INS has reached their time, with the INS mean
// velocity over the same interval. See docs/ins_experiment.md.
#include <cmath>
#include <deque>
#include <optional>
#include <stdexcept>

#include "filter_internal.hpp"
#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/ins.hpp"
#include "lcmloc/core/time_guard.hpp"

namespace lcmloc::core {
namespace {

using ins::StateMat;

constexpr double kDeg = M_PI / 180.0;
constexpr double kG = 9.78;  ///< g of the sensor grade (as ins::ImuGrade)
constexpr int64_t kMaxStepUs = 20000;  ///< longest INS step while bridging a gap [us]
/// Longest gap the INS bridges step by step [us]: 3000 steps. Beyond, the held samples say
/// nothing (a forward time jump of hours took hours of CPU to bridge in 20 ms steps).
constexpr int64_t kMaxBridgeUs = 60000000;
constexpr std::size_t kMaxPending = 10000;

/// The states published after x, y, theta, odo_scale_error, each with the error state whose
/// covariance it has: the INS velocity (ENU) and the gyro drift and accelerometer bias estimates
/// (INS body frame: x right, y forward, z up). A hand-over or hot swap between odo_ins filters
/// restores them (initialize), so a daemon taking over a moving vehicle starts at its speed with
/// the calibrated biases; other filters drop them.
struct ExtraState {
  const char* name;
  int index;
};
constexpr ExtraState kExtraStates[] = {{"v_east", ins::kDvE},          {"v_north", ins::kDvN},
                                       {"gyro_bias_right", ins::kEpsX}, {"gyro_bias_forward", ins::kEpsY},
                                       {"gyro_bias_up", ins::kEpsZ},    {"accel_bias_right", ins::kNabX},
                                       {"accel_bias_forward", ins::kNabY}};
constexpr int kExtra = static_cast<int>(sizeof kExtraStates / sizeof kExtraStates[0]);

void check(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("filter config: " + what);
}

class OdoInsAdapter : public Filter {
 public:
  OdoInsAdapter(const FilterConfig& cfg, bool estimate_scale)
      : cfg_(cfg), name_(cfg.type), kf_(startState(cfg), options(cfg, estimate_scale)) {
    const InsFilterConfig& c = cfg.ins;
    lat0_ = c.latitude * kDeg;
    lon0_ = c.longitude * kDeg;
    const ins::Radii r = ins::radii(lat0_);
    sy_ = r.rm + c.height;
    sx_ = (r.rn + c.height) * std::cos(lat0_);
    // Start position from initial_pose (x, y) in the local frame.
    ins::InsState& s = kf_.mutableState();
    s.lat = lat0_ + cfg.initial_pose[1] / sy_;
    s.lon = lon0_ + cfg.initial_pose[0] / sx_;
    names_ = {"x", "y", "theta", "odo_scale_error"};
    for (const auto& e : kExtraStates) names_.push_back(e.name);
  }

  const std::string& name() const override { return name_; }

  void stateInto(FilterState& out) const override {
    const ins::InsState& s = kf_.state();
    out.utime = utime_;
    out.x.resize(4);
    // The INS stands at ins_utime_; inputs already taken (e.g. the odometer increment of the next
    // IMU interval, queued until that sample) label the state utime_: the pose at utime_ is the
    // INS position carried forward with its velocity over the difference.
    const double lead = leadS(utime_);
    out.x.resize(4 + kExtra);
    out.x.head<4>() << (s.lon - lon0_) * sx_ + s.v.x() * lead, (s.lat - lat0_) * sy_ + s.v.y() * lead, theta(),
        kf_.scaleEstimate();
    const ins::Vec3 gb = kf_.gyroBias(), ab = kf_.accelBias();
    out.x.tail<kExtra>() << s.v.x(), s.v.y(), gb.x(), gb.y(), gb.z(), ab.x(), ab.y();
    Eigen::Matrix<double, 4 + kExtra, ins::kN> J = Eigen::Matrix<double, 4 + kExtra, ins::kN>::Zero();
    J(0, ins::kDLon) = sx_;
    J(1, ins::kDL) = sy_;
    J(2, ins::kPhiU) = -1.0;
    J(3, ins::kKc) = J(3, ins::kKr) = 1.0;
    for (int k = 0; k < kExtra; ++k) J(4 + k, kExtraStates[k].index) = 1.0;
    out.P = J * kf_.covariance() * J.transpose();
    detail::setNames(out, names_);
    out.status = status_;
  }

  void initialize(const FilterState& from) override {
    if (const std::string why = unusableState(from); !why.empty())
      throw std::invalid_argument(name_ + ": initialize: " + why);
    setPose(from.x.head<3>(), from.P.topLeftCorner<3, 3>(), from.utime);
    // The other states by name: the scale, and velocity and biases when the source is an odo_ins
    // filter (their variances and the covariances among them; cross terms to the rest zeroed).
    int src[kExtra];
    for (int k = 0; k < kExtra; ++k) src[k] = -1;
    int speed = -1;  // a forward speed (tvekf, ukf_gps): the velocity when there is no v_east / v_north
    for (std::size_t i = 3; i < from.names.size() && static_cast<Eigen::Index>(i) < from.x.size(); ++i) {
      if (from.names[i] == "odo_scale_error" && estimate_scale_) kf_.setScaleEstimate(from.x[i]);
      if (from.names[i] == "speed" && std::isfinite(from.x[i])) speed = static_cast<int>(i);
      for (int k = 0; k < kExtra; ++k)
        if (from.names[i] == kExtraStates[k].name) src[k] = static_cast<int>(i);
    }
    ins::InsState& s = kf_.mutableState();
    ins::Vec3 gb = kf_.gyroBias(), ab = kf_.accelBias();
    double* value[kExtra] = {&s.v.x(), &s.v.y(), &gb.x(), &gb.y(), &gb.z(), &ab.x(), &ab.y()};
    StateMat& P = kf_.mutableCovariance();
    for (int k = 0; k < kExtra; ++k) {
      if (src[k] < 0) continue;
      *value[k] = from.x[src[k]];
      P.row(kExtraStates[k].index).setZero();
      P.col(kExtraStates[k].index).setZero();
    }
    for (int a = 0; a < kExtra; ++a)
      for (int b = 0; b < kExtra; ++b)
        if (src[a] >= 0 && src[b] >= 0) P(kExtraStates[a].index, kExtraStates[b].index) = from.P(src[a], src[b]);
    if (src[0] < 0 && src[1] < 0) startVelocity(from, speed);
    // A state that was never run (a filter's configured start: reset, a restart after a broken
    // state, a hand-over from a filter that had not started) says nothing about the velocity.
    velocity_unknown_ = from.status == FilterStatus::Uninitialized || (src[0] < 0 && src[1] < 0 && speed < 0);
    kf_.setBiases(gb, ab);
    placeAt(from.x.head<2>(), from.utime);  // with the new velocity
    utime_ = std::max(utime_, from.utime);
  }

  bool applyFix(const PoseFix& fix) override {
    if (!detail::usableFix(fix)) return false;
    setPose(fix.pose, fix.cov, fix.utime);
    utime_ = std::max(utime_, fix.utime);
    return true;
  }

  void predict(const OdometryInput& odo) override {
    if (!std::isfinite(odo.delta_s)) return;
    utime_ = std::max(utime_, odo.utime);
    last_odo_seen_ = std::max(last_odo_seen_, odo.utime);
    if (!have_imu_) return;  // the INS has not started: nothing to compare the odometer with
    if (odo.utime <= last_odo_utime_) return;
    pending_.push_back(odo);
    if (pending_.size() > kMaxPending) pending_.pop_front();
    if (pending_.front().utime <= ins_utime_) {
      applyPending();
      return;
    }
    // IMU missing for longer than max_imu_gap: coast on the last sample and keep correcting.
    if (apartBy(odo.utime, ins_utime_, gapUs())) {
      if (status_ != FilterStatus::DeadReckoning) coast_started_ = ins_utime_;
      status_ = FilterStatus::DeadReckoning;
      advanceTo(odo.utime, last_gyro_, last_accel_, coast_started_ + maxCoastUs());
    }
  }

  bool uses(Measurement m) const override { return m == Measurement::Imu; }

  /// An odometry gap: the INS carries position, velocity and attitude over it with the IMU, and
  /// its covariance grows as the IMU's errors say; what it must not do is take the first
  /// increment after the gap, over the interval since the last one before it, as a speed (it
  /// covers its own period only: the vehicle would read as standing still).
  std::string bridgeOdometryGap(const OdometryGap& gap) override {
    skip_odo_utime_ = gap.next_utime;
    return name_ + ": the INS bridges the gap with the IMU; the first odometer increment after it is not "
                   "taken as a speed";
  }

  std::optional<GateDecision> update(const ImuInput& m) override {
    GateDecision d = detail::decision(m.utime, m.sensor, m.seq, std::numeric_limits<double>::infinity());
    if (!m.gyro.allFinite() || !m.accel.allFinite()) {
      d.reason = "bad_input";
      return d;
    }
    // imu_t body frame (x forward, y left, z up) -> INS body frame (x right, y forward, z up).
    const ins::Vec3 w(-m.gyro.y(), m.gyro.x(), m.gyro.z());
    const ins::Vec3 f(-m.accel.y(), m.accel.x(), m.accel.z());
    if (!have_imu_) {
      have_imu_ = true;
      if (placed_utime_ && m.utime > *placed_utime_) {  // a pose handed over before: carried to now
        ins::InsState& s = kf_.mutableState();
        const double dt = (m.utime - *placed_utime_) * 1e-6;
        s.lat += s.v.y() * dt / sy_;
        s.lon += s.v.x() * dt / sx_;
      }
      ins_utime_ = last_imu_utime_ = m.utime;
      last_odo_utime_ = std::max(last_odo_utime_, m.utime);
      odo_interval_known_ = last_odo_seen_ == m.utime;  // else the next increment began unseen
      while (!pending_.empty() && pending_.front().utime <= m.utime) pending_.pop_front();
      last_gyro_ = w;
      last_accel_ = f;
      status_ = FilterStatus::Ok;
      utime_ = std::max(utime_, m.utime);
      return std::nullopt;
    }
    if (m.utime <= last_imu_utime_) {
      d.reason = "bad_input";  // time does not advance
      return d;
    }
    const bool gap = apartBy(m.utime, last_imu_utime_, gapUs());
    const int64_t gap_from = status_ == FilterStatus::DeadReckoning ? coast_started_ : last_imu_utime_;
    if (m.utime > ins_utime_) advanceTo(m.utime, w, f, gap ? gap_from + maxCoastUs() : INT64_MAX);
    last_imu_utime_ = m.utime;
    last_gyro_ = w;
    last_accel_ = f;
    utime_ = std::max(utime_, m.utime);
    if (!gap) return std::nullopt;
    status_ = FilterStatus::Ok;
    ++gaps_;
    d.reason = "imu_gap";
    d.accepted = true;  // used, after coasting over the gap
    d.innovation = Eigen::VectorXd::Constant(1, (static_cast<double>(m.utime) - static_cast<double>(gap_from)) * 1e-6);  // gap [s]
    return d;
  }

 private:
  static ins::InsState startState(const FilterConfig& cfg) {
    ins::InsState s;
    s.lat = cfg.ins.latitude * kDeg;
    s.lon = cfg.ins.longitude * kDeg;
    s.h = cfg.ins.height;
    s.q_bn = Eigen::Quaterniond(ins::cbnFromHeading(M_PI / 2 - cfg.initial_pose[2]));
    return s;
  }

  static ins::OdoInsFilter::Options options(const FilterConfig& cfg, bool estimate_scale) {
    const InsFilterConfig& c = cfg.ins;
    check(std::abs(c.latitude) < 89.0, "ins.latitude must be within (-89, 89) deg");
    check(std::isfinite(c.longitude) && std::isfinite(c.height), "ins.longitude and ins.height must be finite");
    check(c.init_att_std.allFinite() && (c.init_att_std.array() > 0).all(), "ins.init_att_std must be > 0");
    check(c.init_vel_std > 0 && c.init_pos_std > 0 && c.meas_vel_std > 0,
          "ins.init_vel_std, ins.init_pos_std and ins.meas_vel_std must be > 0");
    check(c.gyro_tau > 0 && c.accel_tau > 0 && c.odo_tau > 0, "ins.*_tau must be > 0");
    check(c.gyro_markov >= 0 && c.gyro_white >= 0 && c.accel_markov >= 0 && c.accel_white >= 0 &&
              c.odo_scale >= 0 && c.odo_markov >= 0 && c.odo_white >= 0,
          "ins sensor grade values must be >= 0");
    check(c.max_imu_gap > 0, "ins.max_imu_gap must be > 0");
    check(c.max_coast >= 0, "ins.max_coast must be >= 0");
    ins::OdoInsFilter::Options o;
    o.grade.gyro_markov = c.gyro_markov * ins::kDegPerHour;
    o.grade.gyro_tau = c.gyro_tau;
    o.grade.gyro_white = c.gyro_white * ins::kDegPerHour;
    o.grade.accel_markov = c.accel_markov * kG;
    o.grade.accel_tau = c.accel_tau;
    o.grade.accel_white = c.accel_white * kG;
    o.grade.odo_scale = c.odo_scale;
    o.grade.odo_tau = c.odo_tau;
    o.grade.odo_markov = c.odo_markov;
    o.grade.odo_white = c.odo_white;
    o.init_att_std = c.init_att_std * ins::kArcMin;
    o.init_vel_std = c.init_vel_std;
    o.init_pos_std = c.init_pos_std;
    o.meas_vel_std = c.meas_vel_std;
    o.attitude_term = c.attitude_term;
    o.paper_exact_h = c.paper_exact_h;
    o.estimate_scale = estimate_scale;
    return o;
  }

  double theta() const { return wrapAngle(M_PI / 2 - ins::headingOf(kf_.state().cbn())); }
  int64_t gapUs() const { return static_cast<int64_t>(std::llround(cfg_.ins.max_imu_gap * 1e6)); }
  int64_t maxCoastUs() const { return static_cast<int64_t>(std::llround(cfg_.ins.max_coast * 1e6)); }

  /// The velocity from a state without v_east / v_north (a hand-over from dead_reckoning, a UKF,
  /// tvekf): its forward "speed" along theta where it has one, else unknown (0 with a standard
  /// deviation of kUnknownSpeedStd, which the first odometer update replaces with the measured
  /// speed). Keeping the INS's own velocity instead (0 m/s, 0.01 m/s sure, for a filter made at
  /// a standstill) ran a vehicle at 12 m/s up to 230 m off within 40 s of a switch.
  /// speed_index: of the forward speed in from (-1: none).
  void startVelocity(const FilterState& from, int speed_index) {
    static constexpr double kUnknownSpeedStd = 50.0;  // [m/s]
    double speed = 0.0, var = kUnknownSpeedStd * kUnknownSpeedStd;
    if (speed_index >= 0) {
      speed = from.x[speed_index];
      var = std::max(from.P(speed_index, speed_index), cfg_.ins.meas_vel_std * cfg_.ins.meas_vel_std);
    }
    ins::InsState& s = kf_.mutableState();
    s.v.x() = speed * std::cos(from.x[2]);
    s.v.y() = speed * std::sin(from.x[2]);
    StateMat& P = kf_.mutableCovariance();
    for (int i : {ins::kDvE, ins::kDvN}) {
      P.row(i).setZero();
      P.col(i).setZero();
      P(i, i) = var;
    }
  }

  /// Re-initializes position and heading (covariance: the given 3x3 over x, y, theta, cross terms
  /// to the other error states zeroed). The body-frame velocity is kept (rotated with the heading).
  /// Seconds from the INS time to t (> 0 only while the INS runs and t is ahead of it).
  double leadS(int64_t t) const { return have_imu_ && t > ins_utime_ ? (t - ins_utime_) * 1e-6 : 0.0; }

  /// Sets the INS position to xy (valid at utime t) carried back to ins_utime_ with the velocity.
  void placeAt(const Vec2& xy, int64_t t) {
    if (!have_imu_) placed_utime_ = t;  // the INS starts at the next IMU sample (update)
    ins::InsState& s = kf_.mutableState();
    const double lead = leadS(t);
    s.lat = lat0_ + (xy[1] - s.v.y() * lead) / sy_;
    s.lon = lon0_ + (xy[0] - s.v.x() * lead) / sx_;
  }

  /// pose: valid at utime t (the INS position is set to it carried back to ins_utime_).
  void setPose(const Vec3& pose, const Mat3& cov, int64_t t) {
    ins::InsState& s = kf_.mutableState();
    const ins::Vec3 v_b = s.cbn().transpose() * s.v;
    const double dtheta = wrapAngle(pose[2] - theta());
    s.q_bn = (Eigen::Quaterniond(Eigen::AngleAxisd(dtheta, ins::Vec3::UnitZ())) * s.q_bn).normalized();
    s.v = s.cbn() * v_b;
    placeAt(pose.head<2>(), t);
    StateMat& P = kf_.mutableCovariance();
    const int idx[3] = {ins::kDLon, ins::kDL, ins::kPhiU};
    const double scale[3] = {1.0 / sx_, 1.0 / sy_, -1.0};
    for (int i : idx) {
      P.row(i).setZero();
      P.col(i).setZero();
    }
    const Mat3 c = 0.5 * (cov + cov.transpose());
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) P(idx[a], idx[b]) = scale[a] * scale[b] * c(a, b);
  }

  /// Propagates the INS to t with one sample (held over the interval, in steps of at most
  /// kMaxStepUs when bridging a gap) and applies the queued odometer increments on the way.
  /// Bridging a dropout, the sample is held until hold_until (ins.max_coast after the dropout
  /// began); beyond, the INS holds its attitude and velocity (the sample an ideal IMU measures
  /// on a vehicle neither turning nor accelerating), so that a yaw rate held from the last sample
  /// does not turn the estimate in circles, nor a held acceleration run it away, over a long gap.
  void advanceTo(int64_t t, const ins::Vec3& w, const ins::Vec3& f, int64_t hold_until = INT64_MAX) {
    if (apartBy(t, ins_utime_, kMaxBridgeUs)) return skipTo(t);
    while (ins_utime_ < t) {
      int64_t next = std::min(t, ins_utime_ + kMaxStepUs);
      if (!pending_.empty() && pending_.front().utime > ins_utime_ && pending_.front().utime < next)
        next = pending_.front().utime;
      if (ins_utime_ < hold_until && hold_until < next) next = hold_until;
      ins::Vec3 wi = w, fi = f;
      if (ins_utime_ >= hold_until) ins::idealImu(kf_.state(), ins::Vec3::Zero(), ins::Vec3::Zero(), &wi, &fi);
      const double dt = (next - ins_utime_) * 1e-6;
      const ins::Vec3 v0 = kf_.state().v;
      if (kf_.propagate(wi, fi, dt)) {
        v_sum_ += 0.5 * (v0 + kf_.state().v) * dt;
        t_sum_ += dt;
      }
      ins_utime_ = next;
      applyPending();
    }
  }

  /// The first odometer increment of a filter that does not know its velocity (a cold start, a
  /// reset, a hand-over without one) sets the INS velocity: the calibrated odometer speed along
  /// the INS heading, with the odometer's variance. Taken as a measurement against the configured
  /// start (0 m/s, init_vel_std 0.01 m/s) instead, the speed of a vehicle already moving went into
  /// the scale error: started at 19 m/s, odo_ins settled at a scale error of +123 % and 8.6 m/s.
  void velocityFromOdometer(double raw_speed) {
    velocity_unknown_ = false;
    ins::InsState& s = kf_.mutableState();
    s.v.head<2>() = kf_.calibratedOdometerVelocity(raw_speed).head<2>();
    const double sd = cfg_.ins.meas_vel_std, white = cfg_.ins.odo_white * raw_speed;
    StateMat& P = kf_.mutableCovariance();
    for (int i : {ins::kDvE, ins::kDvN}) {
      P.row(i).setZero();
      P.col(i).setZero();
      P(i, i) = sd * sd + white * white;
    }
  }

  /// A gap too long to bridge (kMaxBridgeUs): the INS time moves to t with position, attitude
  /// and velocity as they were (what happened meanwhile is unknown: a clock set forward, or an
  /// outage); the covariance is not grown (the INS error model is one of small errors: inflated
  /// by the distance the held speed could have gone, the odometer updates moved the position by
  /// tens of metres through it). The odometer increments up to t are dropped (one spanning the
  /// gap would read as a standstill) and the next one sets the velocity (velocityFromOdometer).
  void skipTo(int64_t t) {
    ins_utime_ = t;
    while (!pending_.empty() && pending_.front().utime <= t) pending_.pop_front();
    last_odo_utime_ = std::max(last_odo_utime_, t);
    odo_interval_known_ = last_odo_seen_ == t;
    v_sum_.setZero();
    t_sum_ = 0.0;
    velocity_unknown_ = true;
  }

  void applyPending() {
    while (!pending_.empty() && pending_.front().utime <= ins_utime_) {
      const OdometryInput o = pending_.front();
      pending_.pop_front();
      const double dt = (o.utime - last_odo_utime_) * 1e-6;
      if (dt <= 0) continue;
      last_odo_utime_ = o.utime;
      if (!odo_interval_known_ || o.utime == skip_odo_utime_) {
        // Its interval began at an odometer message before the INS started (or before a skipped
        // gap), at a time not known here: the distance over (last_odo_utime_, o.utime] would read
        // as a wrong speed (twice the truth, 0.05 s into a 0.1 s interval). From here on it is known.
        odo_interval_known_ = true;
        v_sum_.setZero();
        t_sum_ = 0.0;
        continue;
      }
      const double raw_speed = o.delta_s / dt;
      if (velocity_unknown_) {
        velocityFromOdometer(raw_speed);
        v_sum_.setZero();
        t_sum_ = 0.0;
        continue;
      }
      const ins::Vec3 v_mean = t_sum_ > 0.5 * dt ? ins::Vec3(v_sum_ / t_sum_) : kf_.state().v;
      kf_.updateOdometerMean(raw_speed, v_mean);
      v_sum_.setZero();
      t_sum_ = 0.0;
    }
  }

  FilterConfig cfg_;
  std::string name_;
  ins::OdoInsFilter kf_;
  bool estimate_scale_ = cfg_.type == "odo_ins";
  std::optional<int64_t> placed_utime_;  ///< time of a pose placed before the INS started
  double lat0_ = 0, lon0_ = 0, sx_ = 1, sy_ = 1;
  std::vector<std::string> names_;
  int64_t utime_ = 0, ins_utime_ = 0, last_imu_utime_ = 0, last_odo_utime_ = INT64_MIN, coast_started_ = 0;
  bool have_imu_ = false;
  bool velocity_unknown_ = true;  ///< set by the next odometer increment (velocityFromOdometer)
  int64_t last_odo_seen_ = INT64_MIN;  ///< latest odometer message received (also before the INS ran)
  bool odo_interval_known_ = false;    ///< last_odo_utime_ is an odometer message's time
  ins::Vec3 last_gyro_ = ins::Vec3::Zero(), last_accel_ = ins::Vec3::Zero();
  ins::Vec3 v_sum_ = ins::Vec3::Zero();
  double t_sum_ = 0.0;
  std::deque<OdometryInput> pending_;
  FilterStatus status_ = FilterStatus::Uninitialized;
  int64_t gaps_ = 0;
  int64_t skip_odo_utime_ = INT64_MIN;  ///< the increment after an odometry gap (not a speed)
};

}  // namespace

namespace detail {
std::unique_ptr<Filter> makeOdoInsFilter(const FilterConfig& cfg) {
  if (cfg.type == "odo_ins") return std::make_unique<OdoInsAdapter>(cfg, true);
  if (cfg.type == "odo_ins_uncal") return std::make_unique<OdoInsAdapter>(cfg, false);
  return nullptr;
}
}  // namespace detail

}  // namespace lcmloc::core
