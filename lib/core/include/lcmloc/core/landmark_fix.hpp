#pragma once
// Three-landmark position and heading fix (§III of Wang & Wang): bearings measured from the
// vehicle's longitudinal body axis to three known landmarks. Local plane: x east, y north [m];
// heading psi clockwise from north; bearing alpha clockwise from the body axis, so the
// landmark's azimuth is psi + alpha. Middleware free. See docs/ins_landmarks.md.
#include <Eigen/Core>
#include <map>
#include <string>
#include <vector>

namespace lcmloc::core::landmark {

using Vec2 = Eigen::Vector2d;

struct Bearing {
  int landmark_id = 0;
  double alpha = 0.0;  ///< [rad] clockwise from the body axis
};

struct FixResult {
  bool ok = false;
  std::string error;          ///< why the fix was refused (ok == false)
  Vec2 position = Vec2::Zero();
  double heading = 0.0;       ///< [rad], (-pi, pi]
  double condition = 0.0;     ///< condition number of the range-scaled bearing Jacobian
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  ///< (x, y, psi) from sigma_bearing
  int iterations = 0;
  double triangle_size = 0.0;  ///< error triangle (sum of squared sides) [m^2], triangle method
};

struct FixOptions {
  double sigma_bearing = 30.0 * M_PI / 180.0 / 3600.0;  ///< [rad] 1-sigma
  /// Refuse beyond (vehicle on or near the danger circle). 100 refuses within about 3 % of the
  /// circle's radius, where the position std is already about 30 x bearing std [rad] x radius
  /// (2.8 m at 577 m and 30"; 0.02 m at the centre); 1e4 let fixes with a ~100 m std through.
  double max_condition = 100.0;
  double search_half_width = 5.0 * M_PI / 180.0;  ///< heading search half width around the INS [rad]
  int max_iterations = 50;
};

/// Predicted bearing of landmark lm from pose (p, psi).
double predictBearing(const Vec2& p, double psi, const Vec2& lm);

/// Jacobian of the three bearings with respect to (x, y, psi) at pose (p, psi).
Eigen::Matrix3d bearingJacobian(const Vec2& p, const std::vector<Vec2>& lms);

/// Cramér-Rao bound (covariance of x, y, psi) for bearings with std sigma at pose p.
Eigen::Matrix3d cramerRao(const Vec2& p, const std::vector<Vec2>& lms, double sigma);

/// Error-triangle method: the three azimuth lines (psi_ins + alpha_i through landmark i) form a
/// triangle whose size grows with the heading error; the heading correction minimising the size
/// (coarse scan + golden-section search) is applied and the position is the least-squares point
/// of the three corrected lines. The INS position is used only for the geometry check.
FixResult triangleFix(const std::map<int, Vec2>& map, const std::vector<Bearing>& bearings,
                      const Vec2& p_ins, double psi_ins, const FixOptions& o = {});

/// Damped least squares (Levenberg-Marquardt) on (x, y, psi) from the INS pose.
FixResult leastSquaresFix(const std::map<int, Vec2>& map, const std::vector<Bearing>& bearings,
                          const Vec2& p_ins, double psi_ins, const FixOptions& o = {});

/// Undamped Gauss-Newton from the same start (for comparison: diverges from far starts).
FixResult gaussNewtonFix(const std::map<int, Vec2>& map, const std::vector<Bearing>& bearings,
                         const Vec2& p_ins, double psi_ins, const FixOptions& o = {});

}  // namespace lcmloc::core::landmark
