#pragma once
// Strapdown INS in the local-level ENU navigation frame (x east, y north, z up) on the WGS-84
// ellipsoid, and the odometry/INS Kalman filter of Wang & Wang (eq. 2-8) with online odometer
// scale calibration. Body frame as in the paper: x right, y forward (longitudinal), z up.
// Middleware free (Eigen only). See docs/ins_landmarks.md.
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace lcmloc::core::ins {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

// ---- WGS-84 ----------------------------------------------------------------------------------
constexpr double kA = 6378137.0;                 ///< semi-major axis [m]
constexpr double kF = 1.0 / 298.257223563;       ///< flattening
constexpr double kE2 = kF * (2.0 - kF);          ///< first eccentricity squared
constexpr double kOmegaIe = 7.292115e-5;         ///< Earth rate [rad/s]
constexpr double kGe = 9.7803253359;             ///< normal gravity at the equator [m/s^2]
constexpr double kSomiglianaK = 0.00193185265241;
constexpr double kM = 0.00344978600308;          ///< omega^2 a^2 b / GM
constexpr double kDegPerHour = M_PI / 180.0 / 3600.0;  ///< 1 deg/h in rad/s
constexpr double kArcMin = M_PI / 180.0 / 60.0;
constexpr double kArcSec = M_PI / 180.0 / 3600.0;

/// Meridian (R_M) and prime-vertical (R_N) radii of curvature at latitude lat [rad].
struct Radii {
  double rm = 0.0, rn = 0.0;
};
Radii radii(double lat);

/// WGS-84 normal gravity (Somigliana, second-order height correction) [m/s^2]: magnitude of
/// gravitation plus centrifugal acceleration, pointing down (-z of ENU).
double normalGravity(double lat, double h);

/// Earth rate in ENU at latitude lat: (0, W cos L, W sin L).
Vec3 earthRateEnu(double lat);
/// Transport rate omega_en^n in ENU: (-vN/(RM+h), vE/(RN+h), vE tanL/(RN+h)).
Vec3 transportRateEnu(double lat, double h, const Vec3& v);

/// Skew-symmetric matrix [a x].
Mat3 skew(const Vec3& a);

/// Body-to-ENU rotation for heading psi (clockwise from north), pitch and roll = 0 (body y
/// forward along (sin psi, cos psi), body x right along (cos psi, -sin psi)).
Mat3 cbnFromHeading(double psi);
/// Heading (clockwise from north, (-pi, pi]) of the body y axis of C_b^n.
double headingOf(const Mat3& cbn);

/// Navigation state.
struct InsState {
  double lat = 0.0, lon = 0.0, h = 0.0;  ///< [rad, rad, m]
  Vec3 v = Vec3::Zero();                 ///< ENU velocity [m/s]
  Eigen::Quaterniond q_bn = Eigen::Quaterniond::Identity();  ///< C_b^n as a unit quaternion
  Mat3 cbn() const { return q_bn.toRotationMatrix(); }
};

/// Strapdown mechanization. step() integrates one IMU interval with the body angular rate
/// omega_ib^b [rad/s] and specific force f^b [m/s^2] held over dt (first-order attitude by the
/// rotation vector, velocity at the interval's attitude, trapezoidal position).
/// The vertical channel is free (unstable as in every INS); hold_height keeps h and vU at
/// their values (the land-vehicle 2-D channel of the paper's 12-state error model).
class Ins {
public:
  explicit Ins(const InsState& s = {}, bool hold_height = true) : s_(s), hold_height_(hold_height) {}
  /// Returns false (state unchanged) on non-finite input or dt <= 0.
  bool step(const Vec3& omega_ib_b, const Vec3& f_b, double dt);
  const InsState& state() const { return s_; }
  InsState& state() { return s_; }

private:
  InsState s_;
  bool hold_height_;
};

/// Angular rate and specific force an ideal IMU measures on a vehicle with state s, ENU
/// acceleration a_n (dv/dt) and body rotation rate relative to the nav frame omega_nb_b.
void idealImu(const InsState& s, const Vec3& a_n, const Vec3& omega_nb_b, Vec3* omega_ib_b, Vec3* f_b);

/// Sensor grade of §II of the paper (1-sigma): gyro Markov drift + white, accelerometer Markov
/// bias + white, odometer scale Markov + white.
struct ImuGrade {
  double gyro_markov = 0.1 * kDegPerHour;  ///< [rad/s]
  double gyro_tau = 1800.0;                ///< [s]
  double gyro_white = 0.03 * kDegPerHour;  ///< [rad/s] (per sample std at 1 Hz equivalent)
  double accel_markov = 1e-4 * 9.78;       ///< [m/s^2]
  double accel_tau = 800.0;                ///< [s]
  double accel_white = 1e-4 * 9.78;        ///< [m/s^2]
  double odo_scale = 0.005;                ///< initial scale error std (constant part)
  double odo_tau = 3600.0;                 ///< [s]
  double odo_markov = 0.005;               ///< Markov part (dKr) 1 sigma (drives its process noise)
  double odo_white = 0.0003;               ///< white scale noise
};

// ---- Error-state model (eq. 2-8) -------------------------------------------------------------
/// State indices: [dvE dvN phiE phiN phiU dL dlambda epsX epsY epsZ nablaX nablaY dKc dKr].
enum Idx { kDvE = 0, kDvN, kPhiE, kPhiN, kPhiU, kDL, kDLon, kEpsX, kEpsY, kEpsZ, kNabX, kNabY, kKc, kKr, kN };
using StateVec = Eigen::Matrix<double, kN, 1>;
using StateMat = Eigen::Matrix<double, kN, kN>;
using HMat = Eigen::Matrix<double, 2, kN>;

/// Continuous-time error dynamics F (14x14) at the navigation state s with ENU specific force
/// f_n: psi-angle ENU error model (phi: the computed nav frame is rotated by phi from true,
/// C_b^n' = (I - [phi x]) C_b^n), gyro drift and accel bias as body-frame first-order Markov
/// processes, odometer scale as constant + Markov (eq. 4-5).
StateMat errorDynamics(const InsState& s, const Vec3& f_n, const ImuGrade& g);

/// Measurement matrix of eq. 8 for Z = v_INS^n - C_b^n v_D^b (east, north). v_n is the
/// filter-corrected INS velocity (not the raw odometer velocity: that biases the scale).
/// Columns of dKc and dKr are -vE, -vN (dK = dKc + dKr). With attitude_term the heading
/// coupling of the rotated odometer velocity (phi x v: -phiU vN, +phiU vE) is included; the
/// paper's H omits it and sets the dKr column to 0 (paper_exact).
HMat measurementMatrix(const Vec3& v_n, bool attitude_term = true, bool paper_exact = false);

/// Closed-loop odometry/INS Kalman filter: INS propagates at IMU rate, the filter updates with
/// the odometer's forward speed, feeds back velocity, attitude, position, sensor biases and the
/// odometer scale, and resets its error state to zero.
class OdoInsFilter {
public:
  struct Options {
    ImuGrade grade;
    Vec3 init_att_std{0.5 * kArcMin, 0.5 * kArcMin, 3.0 * kArcMin};
    double init_vel_std = 0.01;   ///< [m/s]
    double init_pos_std = 0.1;    ///< [m]
    double meas_vel_std = 0.01;   ///< additive velocity noise [m/s]
    bool attitude_term = true;
    bool paper_exact_h = false;
    /// false: the traditional integration that ignores the scale error (dKc, dKr held at 0).
    bool estimate_scale = true;
  };
  OdoInsFilter(const InsState& s0, const Options& o);

  /// INS step with raw IMU data (the filter's bias estimates are removed first) and covariance
  /// propagation. Returns false on bad input.
  bool propagate(const Vec3& gyro_b, const Vec3& accel_b, double dt);
  /// Odometer update with the raw forward speed [m/s] along body y. Returns false on bad input.
  bool updateOdometer(double raw_speed);
  /// Odometer update over an interval: raw_speed is the odometer's mean speed over it and
  /// v_ins_mean the INS's mean ENU velocity over the same interval (removes the lag between an
  /// odometer increment and the INS velocity at its end under acceleration). The measurement
  /// matrix uses the current filter-corrected INS velocity. Returns false on bad input.
  bool updateOdometerMean(double raw_speed, const Vec3& v_ins_mean);

  /// Mutable access for re-initialization (landmark fix): the navigation state and the error
  /// covariance.
  InsState& mutableState() { return ins_.state(); }
  StateMat& mutableCovariance() { return P_; }
  void setScaleEstimate(double k) { k_ = k; }
  /// Sets the gyro drift and accelerometer bias estimates (INS body frame; hand-over).
  void setBiases(const Vec3& gyro, const Vec3& accel) {
    gyro_bias_ = gyro;
    accel_bias_ = accel;
  }

  const InsState& state() const { return ins_.state(); }
  /// Estimated total odometer scale error K: true speed = raw / (1 + K).
  double scaleEstimate() const { return k_; }
  double scaleStd() const;  ///< 1-sigma of the scale error remaining (dKc + dKr)
  const StateMat& covariance() const { return P_; }
  Vec3 gyroBias() const { return gyro_bias_; }
  Vec3 accelBias() const { return accel_bias_; }
  /// Odometer velocity in ENU after calibration, rotated with the INS attitude (dead reckoning).
  Vec3 calibratedOdometerVelocity(double raw_speed) const;

private:
  Options o_;
  Ins ins_;
  StateMat P_;
  double k_ = 0.0;
  Vec3 gyro_bias_ = Vec3::Zero(), accel_bias_ = Vec3::Zero();
  Vec3 last_f_n_ = Vec3::Zero();
};

}  // namespace lcmloc::core::ins
