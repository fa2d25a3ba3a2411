#include "lcmloc/core/ins.hpp"

#include <cmath>

#include "lcmloc/core/angles.hpp"

namespace lcmloc::core::ins {

Radii radii(double lat) {
  const double s2 = std::sin(lat) * std::sin(lat);
  const double w = 1.0 - kE2 * s2;
  Radii r;
  r.rn = kA / std::sqrt(w);
  r.rm = kA * (1.0 - kE2) / (w * std::sqrt(w));
  return r;
}

double normalGravity(double lat, double h) {
  const double s2 = std::sin(lat) * std::sin(lat);
  const double g0 = kGe * (1.0 + kSomiglianaK * s2) / std::sqrt(1.0 - kE2 * s2);
  return g0 * (1.0 - 2.0 / kA * (1.0 + kF + kM - 2.0 * kF * s2) * h + 3.0 * h * h / (kA * kA));
}

Vec3 earthRateEnu(double lat) { return {0.0, kOmegaIe * std::cos(lat), kOmegaIe * std::sin(lat)}; }

Vec3 transportRateEnu(double lat, double h, const Vec3& v) {
  const Radii r = radii(lat);
  return {-v.y() / (r.rm + h), v.x() / (r.rn + h), v.x() * std::tan(lat) / (r.rn + h)};
}

Mat3 skew(const Vec3& a) {
  Mat3 m;
  m << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return m;
}

Mat3 cbnFromHeading(double psi) {
  const double c = std::cos(psi), s = std::sin(psi);
  Mat3 m;
  m << c, s, 0, -s, c, 0, 0, 0, 1;
  return m;
}

double headingOf(const Mat3& cbn) { return std::atan2(cbn(0, 1), cbn(1, 1)); }

namespace {
Eigen::Quaterniond rotvecQuat(const Vec3& r) {
  const double a = r.norm();
  if (a < 1e-12) return Eigen::Quaterniond(1.0, 0.5 * r.x(), 0.5 * r.y(), 0.5 * r.z()).normalized();
  return Eigen::Quaterniond(Eigen::AngleAxisd(a, r / a));
}
}  // namespace

bool Ins::step(const Vec3& omega_ib_b, const Vec3& f_b, double dt) {
  if (!(dt > 0.0) || !std::isfinite(dt) || !omega_ib_b.allFinite() || !f_b.allFinite()) return false;
  InsState& s = s_;
  const Vec3 wie = earthRateEnu(s.lat);
  const Vec3 wen = transportRateEnu(s.lat, s.h, s.v);
  const Vec3 win = wie + wen;
  // Attitude: C_b^n(t+dt) = R_n(-win dt) C_b^n R_b(omega_ib dt).
  const Eigen::Quaterniond q_old = s.q_bn;
  s.q_bn = (rotvecQuat(-win * dt) * s.q_bn * rotvecQuat(omega_ib_b * dt)).normalized();
  // Velocity with the mid-interval attitude.
  const Mat3 cmid = q_old.slerp(0.5, s.q_bn).toRotationMatrix();
  const Vec3 g(0.0, 0.0, -normalGravity(s.lat, s.h));
  Vec3 a = cmid * f_b + g - (2.0 * wie + wen).cross(s.v);
  if (hold_height_) a.z() = 0.0;
  const Vec3 v_old = s.v;
  s.v += a * dt;
  const Vec3 vm = 0.5 * (v_old + s.v);
  // Position (trapezoidal velocity; radii at the start latitude).
  const Radii r = radii(s.lat);
  const double lat_mid = s.lat + 0.5 * vm.y() / (r.rm + s.h) * dt;
  const Radii rmid = radii(lat_mid);
  s.lat += vm.y() / (rmid.rm + s.h) * dt;
  s.lon += vm.x() / ((rmid.rn + s.h) * std::cos(lat_mid)) * dt;
  if (!hold_height_) s.h += vm.z() * dt;
  return true;
}

void idealImu(const InsState& s, const Vec3& a_n, const Vec3& omega_nb_b, Vec3* omega_ib_b, Vec3* f_b) {
  const Vec3 wie = earthRateEnu(s.lat);
  const Vec3 wen = transportRateEnu(s.lat, s.h, s.v);
  const Mat3 cnb = s.cbn().transpose();
  const Vec3 g(0.0, 0.0, -normalGravity(s.lat, s.h));
  *omega_ib_b = cnb * (wie + wen) + omega_nb_b;
  *f_b = cnb * (a_n + (2.0 * wie + wen).cross(s.v) - g);
}

StateMat errorDynamics(const InsState& s, const Vec3& f_n, const ImuGrade& g) {
  StateMat F = StateMat::Zero();
  const Radii r = radii(s.lat);
  const double rm = r.rm + s.h, rn = r.rn + s.h;
  const double sl = std::sin(s.lat), cl = std::cos(s.lat), tl = std::tan(s.lat);
  const double sec2 = 1.0 / (cl * cl);
  const double W = kOmegaIe;
  const double vE = s.v.x(), vN = s.v.y();
  const double fE = f_n.x(), fN = f_n.y(), fU = f_n.z();
  const Mat3 C = s.cbn();
  // Velocity errors.
  F(kDvE, kDvE) = vN * tl / rn;
  F(kDvE, kDvN) = 2 * W * sl + vE * tl / rn;
  F(kDvE, kPhiN) = -fU;
  F(kDvE, kPhiU) = fN;
  F(kDvE, kDL) = 2 * W * cl * vN + vE * vN * sec2 / rn;
  F(kDvN, kDvE) = -2 * (W * sl + vE * tl / rn);
  F(kDvN, kPhiE) = fU;
  F(kDvN, kPhiU) = -fE;
  F(kDvN, kDL) = -(2 * W * cl + vE * sec2 / rn) * vE;
  for (int j = 0; j < 2; ++j) {
    F(kDvE, kNabX + j) = C(0, j);
    F(kDvN, kNabX + j) = C(1, j);
  }
  // Attitude errors: phi' = phi x w_in + d w_in - C eps.
  F(kPhiE, kDvN) = -1.0 / rm;
  F(kPhiE, kPhiN) = W * sl + vE * tl / rn;
  F(kPhiE, kPhiU) = -(W * cl + vE / rn);
  F(kPhiN, kDvE) = 1.0 / rn;
  F(kPhiN, kPhiE) = -(W * sl + vE * tl / rn);
  F(kPhiN, kPhiU) = -vN / rm;
  F(kPhiN, kDL) = -W * sl;
  F(kPhiU, kDvE) = tl / rn;
  F(kPhiU, kPhiE) = W * cl + vE / rn;
  F(kPhiU, kPhiN) = vN / rm;
  F(kPhiU, kDL) = W * cl + vE * sec2 / rn;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) F(kPhiE + i, kEpsX + j) = -C(i, j);
  // Position errors.
  F(kDL, kDvN) = 1.0 / rm;
  F(kDLon, kDvE) = 1.0 / (rn * cl);
  F(kDLon, kDL) = vE * tl / (rn * cl);
  // Sensor errors (first-order Markov) and odometer scale (eq. 4).
  for (int i = 0; i < 3; ++i) F(kEpsX + i, kEpsX + i) = -1.0 / g.gyro_tau;
  for (int i = 0; i < 2; ++i) F(kNabX + i, kNabX + i) = -1.0 / g.accel_tau;
  F(kKr, kKr) = -1.0 / g.odo_tau;
  return F;
}

HMat measurementMatrix(const Vec3& v_n, bool attitude_term, bool paper_exact) {
  HMat H = HMat::Zero();
  H(0, kDvE) = 1.0;
  H(1, kDvN) = 1.0;
  H(0, kKc) = -v_n.x();
  H(1, kKc) = -v_n.y();
  if (!paper_exact) {
    H(0, kKr) = -v_n.x();
    H(1, kKr) = -v_n.y();
    if (attitude_term) {
      H(0, kPhiU) = -v_n.y();
      H(1, kPhiU) = v_n.x();
    }
  }
  return H;
}

OdoInsFilter::OdoInsFilter(const InsState& s0, const Options& o) : o_(o), ins_(s0, true) {
  P_.setZero();
  const ImuGrade& g = o.grade;
  const Radii r = radii(s0.lat);
  P_(kDvE, kDvE) = P_(kDvN, kDvN) = o.init_vel_std * o.init_vel_std;
  for (int i = 0; i < 3; ++i) P_(kPhiE + i, kPhiE + i) = o.init_att_std[i] * o.init_att_std[i];
  P_(kDL, kDL) = std::pow(o.init_pos_std / r.rm, 2);
  P_(kDLon, kDLon) = std::pow(o.init_pos_std / (r.rn * std::cos(s0.lat)), 2);
  for (int i = 0; i < 3; ++i) P_(kEpsX + i, kEpsX + i) = g.gyro_markov * g.gyro_markov;
  for (int i = 0; i < 2; ++i) P_(kNabX + i, kNabX + i) = g.accel_markov * g.accel_markov;
  P_(kKc, kKc) = g.odo_scale * g.odo_scale;
  P_(kKr, kKr) = g.odo_white * g.odo_white;  // Markov part starts small, grows over tau
  if (!o.estimate_scale) P_(kKc, kKc) = P_(kKr, kKr) = 0.0;
}

double OdoInsFilter::scaleStd() const {
  return std::sqrt(std::max(0.0, P_(kKc, kKc) + P_(kKr, kKr) + 2 * P_(kKc, kKr)));
}

bool OdoInsFilter::propagate(const Vec3& gyro_b, const Vec3& accel_b, double dt) {
  if (!(dt > 0.0) || dt > 1.0 || !gyro_b.allFinite() || !accel_b.allFinite()) return false;
  const Vec3 w = gyro_b - gyro_bias_;
  Vec3 f = accel_b;
  f.head<2>() -= accel_bias_.head<2>();
  if (!ins_.step(w, f, dt)) return false;
  const InsState& s = ins_.state();
  last_f_n_ = s.cbn() * f;
  const StateMat F = errorDynamics(s, last_f_n_, o_.grade);
  const StateMat Phi = StateMat::Identity() + F * dt + 0.5 * F * F * dt * dt;
  StateMat Q = StateMat::Zero();
  const ImuGrade& g = o_.grade;
  const Mat3 C = s.cbn();
  // White sensor noise mapped to nav frame (std given for a 1 s sample: PSD = sigma^2 * 1 s).
  const Mat3 Qphi = C * (g.gyro_white * g.gyro_white * Mat3::Identity()) * C.transpose();
  Q.block<3, 3>(kPhiE, kPhiE) = Qphi * dt;
  Eigen::Matrix2d Ca = C.block<2, 2>(0, 0);
  Q.block<2, 2>(kDvE, kDvE) = Ca * Ca.transpose() * g.accel_white * g.accel_white * dt;
  for (int i = 0; i < 3; ++i) Q(kEpsX + i, kEpsX + i) = 2 * g.gyro_markov * g.gyro_markov / g.gyro_tau * dt;
  for (int i = 0; i < 2; ++i) Q(kNabX + i, kNabX + i) = 2 * g.accel_markov * g.accel_markov / g.accel_tau * dt;
  Q(kKr, kKr) = o_.estimate_scale ? 2 * g.odo_markov * g.odo_markov / g.odo_tau * dt : 0.0;
  P_ = Phi * P_ * Phi.transpose() + Q;
  P_ = 0.5 * (P_ + P_.transpose());
  return true;
}

Vec3 OdoInsFilter::calibratedOdometerVelocity(double raw_speed) const {
  return ins_.state().cbn() * Vec3(0.0, raw_speed / (1.0 + k_), 0.0);
}

bool OdoInsFilter::updateOdometer(double raw_speed) {
  return updateOdometerMean(raw_speed, ins_.state().v);
}

bool OdoInsFilter::updateOdometerMean(double raw_speed, const Vec3& v_ins_mean) {
  if (!std::isfinite(raw_speed) || !v_ins_mean.allFinite()) return false;
  InsState& s = ins_.state();
  const Vec3 v_odo = calibratedOdometerVelocity(raw_speed);
  const Vec2 z = v_ins_mean.head<2>() - v_odo.head<2>();
  const HMat H = measurementMatrix(s.v, o_.attitude_term, o_.paper_exact_h);
  const double rv = o_.meas_vel_std * o_.meas_vel_std + std::pow(o_.grade.odo_white * raw_speed, 2);
  const Eigen::Matrix2d S = H * P_ * H.transpose() + rv * Eigen::Matrix2d::Identity();
  const Eigen::Matrix<double, kN, 2> K = P_ * H.transpose() * S.inverse();
  const StateVec x = K * z;
  const StateMat IKH = StateMat::Identity() - K * H;
  P_ = IKH * P_ * IKH.transpose() + K * (rv * Eigen::Matrix2d::Identity()) * K.transpose();
  P_ = 0.5 * (P_ + P_.transpose());
  // Feedback and reset.
  s.v.x() -= x(kDvE);
  s.v.y() -= x(kDvN);
  s.q_bn = (rotvecQuat(Vec3(x(kPhiE), x(kPhiN), x(kPhiU))) * s.q_bn).normalized();
  s.lat -= x(kDL);
  s.lon -= x(kDLon);
  gyro_bias_ += x.segment<3>(kEpsX);
  accel_bias_.head<2>() += x.segment<2>(kNabX);
  k_ += x(kKc) + x(kKr);
  // After feedback the dKc/dKr states are residuals; their covariance stays.
  return true;
}

}  // namespace lcmloc::core::ins
