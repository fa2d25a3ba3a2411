#pragma once
// The self-calibration states of "ukf_landmarks" (FilterConfig::Calibration): which of them a
// configuration switches on, where each sits in the augmented state, their names, priors and
// random walks, and the augmented process model. Written once for every state size.
#include <optional>
#include <string>
#include <vector>

#include "lcmloc/core/filter.hpp"
#include "lcmloc/core/vehicle_model.hpp"

namespace lcmloc::core::detail {

/// Per-beacon range-bias states: at most this many (a map with more entries takes the shared one).
inline constexpr int kMaxBeaconBiasStates = FilterConfig::Calibration::kMaxPerBeacon;

/// Where each calibration state sits in the augmented state (-1: switched off).
struct CalibrationLayout {
  int odo_scale = -1, yaw_rate_scale = -1, yaw_rate_bias = -1;
  int bias0 = -1;             ///< first beacon-bias state
  std::vector<int> bias_ids;  ///< per-beacon: the map id of each bias state (empty: shared)
  std::vector<std::string> names;  ///< x, y, theta, then the calibration states' names
  Eigen::VectorXd x0, p0;     ///< prior means and variances of the calibration states (after the pose)
  int size() const { return static_cast<int>(names.size()); }

  /// The layout of c.calibration over the map (per-beacon: one state per map entry, in map
  /// order). Throws std::invalid_argument when the map has more than kMaxBeaconBiasStates
  /// entries for per-beacon biases.
  static CalibrationLayout of(const FilterConfig& c, const MarkerMap& map);
  /// The state index of beacon id's range bias, -1 when it has none.
  int biasIndex(int beacon_id) const;
  /// Random-walk variances of the calibration states (after the pose) for one odometry step of
  /// ds metres turning dtheta over dt seconds.
  void addProcessNoise(const FilterConfig::Calibration& c, double ds, double dtheta, double dt,
                       Eigen::Ref<Eigen::VectorXd> q) const;
  /// The step's corrected travel and turn for a (sigma-point) state s.
  template <class V>
  void correct(const V& s, double ds, double dtheta, double dt, double& ds_c, double& dth_c) const {
    ds_c = odo_scale >= 0 ? (1.0 + s[odo_scale]) * ds : ds;
    dth_c = yaw_rate_scale >= 0 ? (1.0 + s[yaw_rate_scale]) * dtheta : dtheta;
    if (yaw_rate_bias >= 0) dth_c -= s[yaw_rate_bias] * dt;
  }
};

}  // namespace lcmloc::core::detail
