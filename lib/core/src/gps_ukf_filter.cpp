// The UKF over the GNSS filters' sensors ("ukf_gps"). What it shares with "tvekf" is in
// gnss_filter_base.hpp; measured results: docs/tvekf.md.
#include <cmath>
#include <initializer_list>
#include <memory>
#include <stdexcept>
#include <string>

#include "gnss_filter_base.hpp"
#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/gnss_model.hpp"
#include "lcmloc/core/ukf.hpp"

namespace lcmloc::core::gnss_filter {
namespace {

/// A UKF over the same sensors and the same models (gnss_model.hpp), with the full 5x5
/// covariance: GPS fixes then also correct heading and speed through their correlations.
/// The encoder distance is an ungated 1-D update (a gate on an accumulated distance would
/// reject every later sample after one slip); magnetometer heading and GPS are gated.
/// N = 5 + the self-calibration states switched on (GnssCalibration): odometer scale, steering
/// bias, magnetometer bias and accelerometer bias in the process and magnetometer models.
template <int N>
class GpsUkf final : public GnssFilterBase {
  using U = Ukf<N>;

 public:
  explicit GpsUkf(const FilterConfig& c) : GnssFilterBase(c), ukf_(c.sigma, 1u << kTheta) {
    Eigen::VectorXd x;
    Eigen::MatrixXd P;
    initialState(x, P);
    setState(x, P);
  }
  const std::string& name() const override {
    static const std::string n = "ukf_gps";
    return n;
  }
  double heading() const override { return ukf_.x()[kTheta]; }

 protected:
  void fillState(Eigen::VectorXd& x, Eigen::MatrixXd& P) const override {
    x = ukf_.x();
    P = ukf_.P();
  }
  void setState(const Eigen::VectorXd& x, const Eigen::MatrixXd& P) override {
    ukf_.reset(x, P);
  }

  void timeUpdate(const Step& st) override {
    const double L = cfg_.wheelbase;
    const GnssCalibration& cal = cal_;
    const double decay = cal.mag_bias >= 0 ? cal.magDecay(st.T) : 1.0;
    auto f = [&st, &cal, L, decay](const typename U::Vector& s) {
      typename U::Vector o = s;  // the calibration states: constant over the step (m decays)
      const double k = cal.scale(s);  // speed and distance states in the encoder's units
      const double v = k * s[kSpeed];
      o.template head<2>() = gnss::positionStep(s.template head<2>(), v, s[kTheta], st.T);
      o[kTheta] = wrapAngle(s[kTheta] + (st.has_steering ? st.T * gnss::headingRate(v, st.psi - cal.steeringBias(s), L)
                                                         : st.delta_theta));
      // The forward acceleration (less its bias b_a when that is a state) drives the encoder-unit
      // speed as it is: an accelerometer's bias (a fraction of a percent of g) is no reference
      // for a percent of scale.
      const double a = st.has_accel ? st.a - cal.accelBias(s) : st.a;
      const Vec2 sv = gnss::kinematicStep(Vec2(s[kDistance], s[kSpeed]), a, st.T);
      o[kDistance] = sv[0];
      o[kSpeed] = sv[1];
      if (cal.mag_bias >= 0) o[cal.mag_bias] = decay * s[cal.mag_bias];
      return o;
    };
    typename U::Matrix Q = U::Matrix::Zero();
    Q(kX, kX) = Q(kY, kY) = g_.position_rw * g_.position_rw * st.T;
    // Steering noise and heading random walk (the speed's share comes from the sigma points).
    Step no_speed = st;
    Q(kTheta, kTheta) = headingNoise(no_speed, ukf_.x()[kSpeed], 0.0);
    const Vec2 B = gnss::kinematicB(st.T);
    const Mat2 Qsv = B * B.transpose() * (st.a_std * st.a_std);
    Q(kDistance, kDistance) = Qsv(0, 0);
    Q(kDistance, kSpeed) = Q(kSpeed, kDistance) = Qsv(0, 1);
    Q(kSpeed, kSpeed) = Qsv(1, 1);
    cal_.addProcessNoise(st.T, ukf_.x()[kSpeed] * st.T, Q);
    if (!ukf_.predict(f, Q)) return;
    Innovation<N, 1> in;
    const Eigen::Matrix<double, 1, 1> R = Eigen::Matrix<double, 1, 1>::Constant(
        g_.encoder_std * g_.encoder_std);
    const Eigen::Matrix<double, 1, 1> z = Eigen::Matrix<double, 1, 1>::Constant(enc_sum_);
    if (ukf_.template innovate<1>([](const typename U::Vector& s) { return Eigen::Matrix<double, 1, 1>(s[kDistance]); },
                                  R, z, 0u, in))
      ukf_.correct(in);
  }

  void headingUpdate(double zth, double r, GateDecision& d, bool magnetic) override {
    Innovation<N, 1> in;
    const Eigen::Matrix<double, 1, 1> R = Eigen::Matrix<double, 1, 1>::Constant(r);
    const Eigen::Matrix<double, 1, 1> z = Eigen::Matrix<double, 1, 1>::Constant(zth);
    const int m = magnetic ? cal_.mag_bias : -1;
    auto h = [m](const typename U::Vector& s) {
      return Eigen::Matrix<double, 1, 1>(m >= 0 ? wrapAngle(s[kTheta] + s[m]) : s[kTheta]);
    };
    if (!ukf_.template innovate<1>(h, R, z, 1u, in)) {
      d.reason = "bad_input";
      return;
    }
    apply(in, gate1_, d);
  }

  void positionUpdate(const Vec2& zp, double r, GateDecision& d) override {
    Innovation<N, 2> in;
    const Mat2 R = r * Mat2::Identity();
    if (!ukf_.template innovate<2>([](const typename U::Vector& s) { return Vec2(s.template head<2>()); }, R, zp, 0u,
                                   in)) {
      d.reason = "bad_input";
      return;
    }
    apply(in, gate2_, d);
  }

  void inflateHeading() override { inflateStates({{kTheta, kLockoutMaxHeadingStd}}); }
  void growPosition(double dt) override {
    typename U::Matrix P = ukf_.P();
    P(kX, kX) += g_.position_rw * g_.position_rw * dt;
    P(kY, kY) += g_.position_rw * g_.position_rw * dt;
    ukf_.reset(ukf_.x(), P);
  }

 private:
  template <int M>
  void apply(const Innovation<N, M>& in, double gate, GateDecision& d) {
    d.innovation = in.v;
    d.mahalanobis = in.mahalanobis;
    if (!(in.mahalanobis <= gate)) {
      d.reason = "gate";
      return;
    }
    ukf_.correct(in);
    d.accepted = true;
    d.reason = std::isfinite(gate) ? "accepted" : "ungated";
  }
  void inflateStates(std::initializer_list<detail::InflateCap> states) {
    typename U::Matrix P = ukf_.P();
    detail::inflateCapped(P, states, cfg_.lockout_inflation);
    ukf_.reset(ukf_.x(), P);
  }

  U ukf_;
};

}  // namespace

std::unique_ptr<Filter> makeGpsUkf(const FilterConfig& cfg) {
  switch (const int n = GnssCalibration::of(cfg).size()) {
    case kN: return std::make_unique<GpsUkf<kN>>(cfg);
    case kN + 1: return std::make_unique<GpsUkf<kN + 1>>(cfg);
    case kN + 2: return std::make_unique<GpsUkf<kN + 2>>(cfg);
    case kN + 3: return std::make_unique<GpsUkf<kN + 3>>(cfg);
    case kN + 4: return std::make_unique<GpsUkf<kN + 4>>(cfg);
    default:  // (a state added to GnssCalibration without its size here: never a smaller filter)
      throw std::logic_error("ukf_gps: no filter of " + std::to_string(n) + " states");
  }
}

}  // namespace lcmloc::core::gnss_filter
