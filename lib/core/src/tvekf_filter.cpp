// The time-varying EKF of Choi and Kong (seeds/002, "tvekf"): the GNSS filter as a cascade of
// three small filters. What it shares with "ukf_gps" is in gnss_filter_base.hpp; derivations and
// measured results: docs/tvekf.md.
#include <algorithm>
#include <cmath>
#include <memory>

#include "gnss_filter_base.hpp"
#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/gnss_model.hpp"
#include "lcmloc/core/ukf.hpp"

namespace lcmloc::core::gnss_filter {
namespace {

/// The time-varying EKF of §2 as a cascade of three small filters with their own covariances
/// (the paper's decoupling; cross-covariances between the blocks are neglected):
///  §2.1 kinematic KF of [s, v] from the forward acceleration, corrected by the encoder distance;
///  §2.2 heading predicted by eq. 10 from v and the steering, corrected by the magnetometer
///       heading with the scalar gain L = P_theta^- / (P_theta^- + R_mag) of every step;
///  §2.3 position predicted by eq. 17 from v and theta, corrected by GPS with the gain
///       J = P_p^- (P_p^- + R_gps)^-1 of every step (eq. 21 when the axes are uncorrelated).
/// The self-calibration states (GnssCalibration), when switched on, join the block that observes
/// them: the odometer scale k the position block (GPS sees it through the travelled distance),
/// the steering bias s and the magnetometer bias m the heading block [theta, s, m] (the
/// magnetometer measures theta + m; a bias of the steering shows as a heading rate the
/// magnetometer does not follow), the accelerometer bias b_a the kinematic block [s, v, b_a]
/// (the encoder distance sees it). Without them the blocks are the paper's, computed as before.
class TvEkf final : public GnssFilterBase {
 public:
  explicit TvEkf(const FilterConfig& c) : GnssFilterBase(c) {
    use_course_ = true;
    Eigen::VectorXd x;
    Eigen::MatrixXd P;
    initialState(x, P);
    setState(x, P);
  }
  const std::string& name() const override {
    static const std::string n = "tvekf";
    return n;
  }
  double heading() const override { return th_; }

 protected:
  void fillState(Eigen::VectorXd& x, Eigen::MatrixXd& P) const override {
    const int n = cal_.size();
    x.resize(n);
    x.head<kN>() << p_, th_, sv_[1], sv_[0];
    P = Eigen::MatrixXd::Zero(n, n);
    P.topLeftCorner<2, 2>() = Pp_;
    P(kTheta, kTheta) = Pth_;
    P(kSpeed, kSpeed) = Psv_(1, 1);
    P(kDistance, kDistance) = Psv_(0, 0);
    P(kSpeed, kDistance) = P(kDistance, kSpeed) = Psv_(0, 1);
    if (const int b = cal_.accel_bias; b >= 0) {
      x[b] = ba_;
      P(b, b) = Pbb_;
      P(b, kDistance) = P(kDistance, b) = Psb_[0];
      P(b, kSpeed) = P(kSpeed, b) = Psb_[1];
    }
    if (const int k = cal_.odo_scale; k >= 0) {
      x[k] = k_;
      P(k, k) = Pkk_;
      P.block<2, 1>(0, k) = Pxk_;
      P.block<1, 2>(k, 0) = Pxk_.transpose();
    }
    const int hb[3] = {kTheta, cal_.steering_bias, cal_.mag_bias};
    for (int i = 0; i < 3 && headingBlock(); ++i) {
      if (hb[i] < 0) continue;
      if (i > 0) x[hb[i]] = hx_[i];
      for (int j = 0; j < 3; ++j)
        if (hb[j] >= 0) P(hb[i], hb[j]) = P(hb[j], hb[i]) = Ph_(i, j);
      P.block<2, 1>(0, hb[i]) = Cph_.col(i);
      P.block<1, 2>(hb[i], 0) = Cph_.col(i).transpose();
    }
  }
  void setState(const Eigen::VectorXd& x, const Eigen::MatrixXd& P) override {
    p_ = x.head<2>();
    Pp_ = P.topLeftCorner<2, 2>();
    th_ = wrapAngle(x[kTheta]);
    Pth_ = P(kTheta, kTheta);
    sv_ << x[kDistance], x[kSpeed];
    Psv_ << P(kDistance, kDistance), P(kDistance, kSpeed), P(kSpeed, kDistance), P(kSpeed, kSpeed);
    if (const int b = cal_.accel_bias; b >= 0) {
      ba_ = x[b];
      Pbb_ = P(b, b);
      Psb_ << P(kDistance, b), P(kSpeed, b);
    }
    if (const int k = cal_.odo_scale; k >= 0) {
      k_ = x[k];
      Pkk_ = P(k, k);
      Pxk_ = P.block<2, 1>(0, k);
    }
    // The heading block: theta, then s and m (a state switched off: 0 with no variance).
    const int hb[3] = {kTheta, cal_.steering_bias, cal_.mag_bias};
    hx_.setZero();
    Ph_.setZero();
    Cph_.setZero();
    for (int i = 0; i < 3; ++i) {
      if (hb[i] < 0) continue;
      hx_[i] = i == 0 ? th_ : x[hb[i]];
      Cph_.col(i) = P.block<2, 1>(0, hb[i]);
      for (int j = 0; j < 3; ++j)
        if (hb[j] >= 0) Ph_(i, j) = P(hb[i], hb[j]);
    }
  }
  bool headingBlock() const { return cal_.steering_bias >= 0 || cal_.mag_bias >= 0; }

  void timeUpdate(const Step& st) override {
    const bool scaled = cal_.odo_scale >= 0;
    const double T = st.T, ke = scaled ? 1.0 + k_ : 1.0, v = sv_[1] * ke;
    const double Pv = scaled ? Psv_(1, 1) * ke * ke : Psv_(1, 1);
    if (headingBlock()) Pth_ = Ph_(0, 0);
    // §2.3, eq. 17 with v(k), theta(k); covariance through its Jacobian in (v, theta) (eq. 22-24).
    const double c = std::cos(th_), s = std::sin(th_);
    Mat2 G;
    G << T * c, -v * T * s, T * s, v * T * c;
    p_ = gnss::positionStep(p_, v, th_, T);
    if (scaled) {  // the position block [p, k]: p depends on k through the travelled distance
      const Vec2 gk = sv_[1] * T * Vec2(c, s);
      Pp_ += Pxk_ * gk.transpose() + gk * Pxk_.transpose() + Pkk_ * gk * gk.transpose();
      Pxk_ += Pkk_ * gk;
      Pkk_ += cal_.cfg.odo_scale_rw * cal_.cfg.odo_scale_rw * std::abs(sv_[1] * T);
    }
    if (headingBlock()) {  // the position's covariance with the heading block (see predictHeadingBlock)
      const Vec2 gth = G.col(1);
      Pp_ += gth * Cph_.col(0).transpose() + Cph_.col(0) * gth.transpose();
      Cph_ += gth * Ph_.row(0);
    }
    Pp_ = Pp_ + G * Vec2(Pv, Pth_).asDiagonal() * G.transpose();
    Pp_.diagonal().array() += g_.position_rw * g_.position_rw * T;
    // §2.2, eq. 10 (a priori heading) and eq. 13 (its variance).
    if (headingBlock()) {
      predictHeadingBlock(st, v, Pv);
    } else {
      Pth_ += headingNoise(st, v, Pv);
      th_ = wrapAngle(th_ + headingIncrement(st, v));
    }
    // §2.1, eq. 6: a priori [s, v]; process noise of the acceleration through B.
    const Mat2 A = gnss::kinematicA(T);
    const Vec2 B = gnss::kinematicB(T);
    const bool biased = cal_.accel_bias >= 0;
    sv_ = gnss::kinematicStep(sv_, biased && st.has_accel ? st.a - ba_ : st.a, T);
    Psv_ = A * Psv_ * A.transpose() + B * B.transpose() * (st.a_std * st.a_std);
    if (biased) {  // [s, v, b_a]: d[s, v]/d b_a = -B (0 without an accelerometer reading); b_a a random walk
      const Vec2 Bb = st.has_accel ? B : Vec2::Zero();
      const Vec2 APsb = A * Psb_;
      Psv_ += Pbb_ * Bb * Bb.transpose() - APsb * Bb.transpose() - Bb * APsb.transpose();
      Psb_ = APsb - Pbb_ * Bb;
      Pbb_ += cal_.cfg.accel_bias_rw * cal_.cfg.accel_bias_rw * T;
    }
    // eq. 7: correction by the encoder distance s(k+1) = C x + noise; F = P C' (C P C' + R)^-1.
    const double S = Psv_(0, 0) + g_.encoder_std * g_.encoder_std;
    const Vec2 F = Psv_.col(0) / S;
    const double innovation = enc_sum_ - sv_[0];
    if (biased) {
      const double Fb = Psb_[0] / S;
      ba_ += Fb * innovation;
      Pbb_ -= Fb * Psb_[0];
      Psb_ -= F * Psb_[0];
    }
    sv_ += F * innovation;
    Psv_ -= F * Psv_.row(0);
    Psv_ = 0.5 * (Psv_ + Psv_.transpose()).eval();
  }

  void headingUpdate(double z, double r, GateDecision& d, bool magnetic) override {
    if (headingBlock()) {
      headingBlockUpdate(z, r, d, magnetic && cal_.mag_bias >= 0);
      return;
    }
    const double v = wrapAngle(z - th_);
    const double S = Pth_ + r;
    d.innovation = Eigen::VectorXd::Constant(1, v);
    d.mahalanobis = v * v / S;
    if (!(d.mahalanobis <= gate1_)) {
      d.reason = "gate";
      return;
    }
    const double L = Pth_ / S;  // eq. 11-12: the time-varying gain, recomputed every sample
    th_ = wrapAngle(th_ + L * v);
    Pth_ *= 1.0 - L;
    d.accepted = true;
    d.reason = std::isfinite(gate1_) ? "accepted" : "ungated";
  }

  void positionUpdate(const Vec2& z, double r, GateDecision& d) override {
    const Vec2 v = z - p_;
    const Mat2 S = Pp_ + r * Mat2::Identity();
    Mat2 S_inv;
    if (!inverseSpd<2>(S, S_inv)) {
      d.reason = "bad_input";
      return;
    }
    d.innovation = v;
    d.mahalanobis = v.dot(S_inv * v);
    if (!(d.mahalanobis <= gate2_)) {
      d.reason = "gate";
      return;
    }
    const Mat2 J = Pp_ * S_inv;  // eq. 20-21, recomputed every fix
    p_ += J * v;
    if (cal_.odo_scale >= 0) {  // the scale's gain and covariance (before Pp_ changes)
      const Eigen::RowVector2d Jk = Pxk_.transpose() * S_inv;
      k_ += Jk * v;
      Pkk_ -= Jk * Pxk_;
      Pxk_ -= J * Pxk_;
    }
    if (headingBlock()) Cph_ -= J * Cph_;  // the heading block itself is not corrected (the cascade)
    Pp_ = (Mat2::Identity() - J) * Pp_;
    Pp_ = 0.5 * (Pp_ + Pp_.transpose()).eval();
    d.accepted = true;
    d.reason = std::isfinite(gate2_) ? "accepted" : "ungated";
  }

  void inflateHeading() override {
    Pth_ = std::max(Pth_, std::min(Pth_ * cfg_.lockout_inflation, kLockoutMaxHeadingStd * kLockoutMaxHeadingStd));
    if (headingBlock()) Ph_(0, 0) = Pth_;
  }
  void growPosition(double dt) override {
    Pp_.diagonal().array() += g_.position_rw * g_.position_rw * dt;
  }

 private:
  /// The heading block [theta, s, m] over a step: eq. 10 with the steering minus s, m decays.
  void predictHeadingBlock(const Step& st, double v, double Pv) {
    const double b = hx_[1];
    Step unbiased = st;
    unbiased.psi = st.psi - b;
    Eigen::Matrix3d F = Eigen::Matrix3d::Identity();
    if (st.has_steering && cal_.steering_bias >= 0) {
      const double c = std::cos(unbiased.psi);
      F(0, 1) = -st.T * v / (cfg_.wheelbase * c * c);
    }
    const double decay = cal_.mag_bias >= 0 ? cal_.magDecay(st.T) : 1.0;
    F(2, 2) = decay;
    hx_[0] = wrapAngle(hx_[0] + headingIncrement(unbiased, v));
    hx_[2] *= decay;
    Eigen::Matrix3d Q = Eigen::Matrix3d::Zero();
    Q(0, 0) = headingNoise(unbiased, v, Pv);
    if (cal_.steering_bias >= 0) Q(1, 1) = cal_.cfg.steering_bias_rw * cal_.cfg.steering_bias_rw * st.T;
    if (cal_.mag_bias >= 0) Q(2, 2) = cal_.cfg.mag_bias_std * cal_.cfg.mag_bias_std * (1.0 - decay * decay);
    Ph_ = F * Ph_ * F.transpose() + Q;
    Cph_ = Cph_ * F.transpose();
    th_ = hx_[0];
    Pth_ = Ph_(0, 0);
  }
  /// A heading measurement of the heading block: theta (+ m when with_bias).
  void headingBlockUpdate(double z, double r, GateDecision& d, bool with_bias) {
    const Eigen::RowVector3d H(1.0, 0.0, with_bias ? 1.0 : 0.0);
    const double v = wrapAngle(z - (hx_[0] + (with_bias ? hx_[2] : 0.0)));
    const double S = (H * Ph_ * H.transpose())(0, 0) + r;
    d.innovation = Eigen::VectorXd::Constant(1, v);
    d.mahalanobis = v * v / S;
    if (!(d.mahalanobis <= gate1_)) {
      d.reason = "gate";
      return;
    }
    const Eigen::Vector3d K = Ph_ * H.transpose() / S;
    hx_ += K * v;
    hx_[0] = wrapAngle(hx_[0]);
    Cph_ -= (Cph_ * H.transpose()) * K.transpose();
    Ph_ -= K * (H * Ph_);
    Ph_ = 0.5 * (Ph_ + Ph_.transpose()).eval();
    th_ = hx_[0];
    Pth_ = Ph_(0, 0);
    d.accepted = true;
    d.reason = std::isfinite(gate1_) ? "accepted" : "ungated";
  }

  Vec2 p_;
  Mat2 Pp_;
  double k_ = 0, Pkk_ = 0;        ///< odometer scale (GnssCalibration) and its variance
  Vec2 Pxk_ = Vec2::Zero();       ///< its covariance with the position
  Eigen::Vector3d hx_ = Eigen::Vector3d::Zero();  ///< heading block [theta, s, m] (with s or m on)
  Eigen::Matrix3d Ph_ = Eigen::Matrix3d::Zero();
  /// Covariance of the position with the heading block, carried with it (a Schmidt "consider"
  /// covariance: GPS corrects the position only, but the position's covariance grows with the
  /// heading error that persists over many steps, not as if it were new at every step).
  Eigen::Matrix<double, 2, 3> Cph_ = Eigen::Matrix<double, 2, 3>::Zero();
  double th_ = 0, Pth_ = 0;
  Vec2 sv_;   ///< [s, v]
  Mat2 Psv_;
  double ba_ = 0, Pbb_ = 0;       ///< accelerometer bias (GnssCalibration) and its variance
  Vec2 Psb_ = Vec2::Zero();       ///< its covariance with [s, v]
};

}  // namespace

std::unique_ptr<Filter> makeTvEkf(const FilterConfig& cfg) { return std::make_unique<TvEkf>(cfg); }

}  // namespace lcmloc::core::gnss_filter
