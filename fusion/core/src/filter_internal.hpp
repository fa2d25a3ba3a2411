#pragma once
// Helpers shared by the filter implementations (not installed; src/ only).
#include <memory>
#include <string>
#include <vector>

#include "lcmloc/core/filter.hpp"

namespace lcmloc::core::detail {

/// Hot swap: copies every state of `from` that has the same name as one of `names` (x, y,
/// theta always) into x, P (pre-filled with the filter's initial values), with the covariance
/// among copied states; cross-covariances to other states are zero. Throws
/// std::invalid_argument when `from` is malformed or not finite.
void copyMatching(const FilterState& from, const std::vector<std::string>& names,
                  Eigen::VectorXd& x, Eigen::MatrixXd& P);

/// The GNSS filters ("tvekf", "ukf_gps"); nullptr for another type. Throws
/// std::invalid_argument for an invalid configuration.
std::unique_ptr<Filter> makeGnssFilter(const FilterConfig& cfg);

/// The landmark/beacon filter ("ukf_landmarks") over the map; nullptr for another type.
std::unique_ptr<Filter> makeLandmarkFilter(const FilterConfig& cfg, const MarkerMap& map);

/// Pose process noise of one odometry step (x, y, theta variances): Pw over pw_distance of
/// travel plus pw_turn |dtheta| on the heading.
Vec3 poseProcessNoise(const FilterConfig& c, double ds, double dtheta);
/// The odometry/INS filters ("odo_ins", "odo_ins_uncal"); nullptr for another type. Throws
/// std::invalid_argument for an invalid configuration.
std::unique_ptr<Filter> makeOdoInsFilter(const FilterConfig& cfg);

}  // namespace lcmloc::core::detail
