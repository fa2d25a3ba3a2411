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
    x.resize(kN);
    x << p_, th_, sv_[1], sv_[0];
    P = Eigen::MatrixXd::Zero(kN, kN);
    P.topLeftCorner<2, 2>() = Pp_;
    P(kTheta, kTheta) = Pth_;
    P(kSpeed, kSpeed) = Psv_(1, 1);
    P(kDistance, kDistance) = Psv_(0, 0);
    P(kSpeed, kDistance) = P(kDistance, kSpeed) = Psv_(0, 1);
  }
  void setState(const Eigen::VectorXd& x, const Eigen::MatrixXd& P) override {
    p_ = x.head<2>();
    Pp_ = P.topLeftCorner<2, 2>();
    th_ = wrapAngle(x[kTheta]);
    Pth_ = P(kTheta, kTheta);
    sv_ << x[kDistance], x[kSpeed];
    Psv_ << P(kDistance, kDistance), P(kDistance, kSpeed), P(kSpeed, kDistance), P(kSpeed, kSpeed);
  }

  void timeUpdate(const Step& st) override {
    const double T = st.T, v = sv_[1], Pv = Psv_(1, 1);
    // §2.3, eq. 17 with v(k), theta(k); covariance through its Jacobian in (v, theta) (eq. 22-24).
    const double c = std::cos(th_), s = std::sin(th_);
    Mat2 G;
    G << T * c, -v * T * s, T * s, v * T * c;
    p_ = gnss::positionStep(p_, v, th_, T);
    Pp_ = Pp_ + G * Vec2(Pv, Pth_).asDiagonal() * G.transpose();
    Pp_.diagonal().array() += g_.position_rw * g_.position_rw * T;
    // §2.2, eq. 10 (a priori heading) and eq. 13 (its variance).
    Pth_ += headingNoise(st, v, Pv);
    th_ = wrapAngle(th_ + headingIncrement(st, v));
    // §2.1, eq. 6: a priori [s, v]; process noise of the acceleration through B.
    const Mat2 A = gnss::kinematicA(T);
    const Vec2 B = gnss::kinematicB(T);
    sv_ = gnss::kinematicStep(sv_, st.a, T);
    Psv_ = A * Psv_ * A.transpose() + B * B.transpose() * (st.a_std * st.a_std);
    // eq. 7: correction by the encoder distance s(k+1) = C x + noise; F = P C' (C P C' + R)^-1.
    const double S = Psv_(0, 0) + g_.encoder_std * g_.encoder_std;
    const Vec2 F = Psv_.col(0) / S;
    sv_ += F * (enc_sum_ - sv_[0]);
    Psv_ -= F * Psv_.row(0);
    Psv_ = 0.5 * (Psv_ + Psv_.transpose()).eval();
  }

  void headingUpdate(double z, double r, GateDecision& d) override {
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
    Pp_ = (Mat2::Identity() - J) * Pp_;
    Pp_ = 0.5 * (Pp_ + Pp_.transpose()).eval();
    d.accepted = true;
    d.reason = std::isfinite(gate2_) ? "accepted" : "ungated";
  }

  void inflateHeading() override {
    Pth_ = std::max(Pth_, std::min(Pth_ * cfg_.lockout_inflation, kLockoutMaxHeadingStd * kLockoutMaxHeadingStd));
  }
  void growPosition(double dt) override {
    Pp_.diagonal().array() += g_.position_rw * g_.position_rw * dt;
  }

 private:
  Vec2 p_;
  Mat2 Pp_;
  double th_ = 0, Pth_ = 0;
  Vec2 sv_;   ///< [s, v]
  Mat2 Psv_;
};

}  // namespace

std::unique_ptr<Filter> makeTvEkf(const FilterConfig& cfg) { return std::make_unique<TvEkf>(cfg); }

}  // namespace lcmloc::core::gnss_filter
