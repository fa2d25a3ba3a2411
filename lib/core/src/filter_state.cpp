// States as they pass between filters: the checks a state must pass (unusableState), the copy
// of the states two filters share by name (hot swap), and the caps of lock-out inflation.
#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>

#include "filter_internal.hpp"
#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/filter.hpp"

namespace lcmloc::core {

std::vector<detail::InflateCap> detail::lockoutCaps(const FilterConfig& cfg, const std::vector<std::string>& names) {
  std::vector<InflateCap> caps;
  for (std::size_t i = 0; i < names.size(); ++i) {
    const std::string& n = names[i];
    const double cap = n == "x" || n == "y"  ? cfg.lockout_max_std
                       : n == "theta"        ? kLockoutMaxHeadingStd
                       : n == "odo_scale"    ? cfg.scale_std0
                       : n == "steer_bias"   ? cfg.steer_bias_std0
                                             : 0.0;  // (no other state is inflated)
    caps.push_back({static_cast<int>(i), cap});
  }
  return caps;
}

std::string unusableState(const FilterState& s) {
  const auto n = s.x.size();
  if (n < 3 || s.P.rows() != n || s.P.cols() != n) return "state must have >= 3 entries and a matching P";
  if (!s.x.allFinite() || !s.P.allFinite()) return "state or covariance not finite";
  if (std::abs(s.x(0)) > kMaxAbsPosition || std::abs(s.x(1)) > kMaxAbsPosition) {
    std::ostringstream o;
    o << std::setprecision(6) << "position (" << s.x(0) << ", " << s.x(1) << ") m is beyond " << kMaxAbsPosition << " m";
    return o.str();
  }
  if (s.P.diagonal().maxCoeff() > kMaxVariance) {
    std::ostringstream o;
    o << std::setprecision(6) << "a variance (" << s.P.diagonal().maxCoeff() << ") is beyond " << kMaxVariance;
    return o.str();
  }
  for (int i = 0; i < 3; ++i)
    if (!(s.P(i, i) > 0.0)) return "the variance of " + std::string(i == 0 ? "x" : i == 1 ? "y" : "theta") + " is not > 0";
  const double scale = s.P.diagonal().cwiseAbs().maxCoeff();
  if (!(s.P - s.P.transpose()).isZero(1e-9 * scale)) return "covariance not symmetric";
  const double min_eig = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(s.P, Eigen::EigenvaluesOnly).eigenvalues().minCoeff();
  if (min_eig < -1e-9 * scale) return "covariance not positive semi-definite (an eigenvalue is " + std::to_string(min_eig) + ")";
  return "";
}

/// Hot swap: starts from the filter's initial values and copies every state of `from` that has
/// the same name (x, y, theta always: a source without names is read as x, y, theta, ...),
/// with the covariance among copied states; cross-covariances to other states are zero.
void detail::copyMatching(const FilterState& from, const std::vector<std::string>& names,
                  Eigen::VectorXd& x, Eigen::MatrixXd& P) {
  const auto n_from = from.x.size();
  if (const std::string why = unusableState(from); !why.empty()) throw std::invalid_argument("initialize: " + why);
  const bool named = static_cast<Eigen::Index>(from.names.size()) == n_from;
  std::vector<int> src(names.size(), -1);
  for (size_t i = 0; i < names.size(); ++i) {
    if (i < 3) { src[i] = static_cast<int>(i); continue; }
    for (Eigen::Index j = 3; named && j < n_from; ++j)
      if (from.names[j] == names[i]) src[i] = static_cast<int>(j);
  }
  for (size_t i = 0; i < names.size(); ++i) {
    if (src[i] < 0) continue;
    x[i] = from.x[src[i]];
    for (size_t j = 0; j < names.size(); ++j) {
      if (src[j] < 0) continue;
      P(i, j) = from.P(src[i], src[j]);
    }
    for (size_t j = 0; j < names.size(); ++j)
      if (src[j] < 0) P(i, j) = P(j, i) = 0.0;
  }
  x[2] = wrapAngle(x[2]);
}

}  // namespace lcmloc::core
