#pragma once
// Re-localization of "ukf_landmarks" from evidence (not from an inflated covariance): the
// observations of known landmarks its gate refused in a row, each placed in a dead-reckoned
// frame by the odometry since. When observations of at least two landmarks agree on one
// transform of that frame onto the map (at least kAgree of them and more than half of those
// kept, each within its noise), the pose they give is taken. An observation without identity is never evidence: a distractor
// cannot move the estimate. Not installed; src/ only.
#include <cstdint>
#include <deque>
#include <optional>

#include "lcmloc/core/types.hpp"

namespace lcmloc::core::detail {

class LandmarkEvidence {
 public:
  static constexpr int kAgree = 4;            ///< observations that must agree (two place the frame, two check it)
  static constexpr std::size_t kMax = 16;     ///< observations kept
  static constexpr int64_t kMaxAgeUs = 20000000;  ///< none older than the newest by more than this

  /// What the agreeing observations say.
  struct Found {
    Pose pose;            ///< at the newest observation's time
    Mat3 P;               ///< its covariance
    int observations = 0; ///< that agreed
    int landmarks = 0;    ///< distinct landmarks among them
    int64_t first_utime = 0;
    double spread = 0;    ///< largest distance of an agreeing observation from its landmark [m]
  };

  /// Odometry: the dead-reckoned frame moves with the vehicle.
  void move(double ds, double dth);
  /// An accepted observation: the estimate agrees with the map again.
  void clear() { seen_.clear(); }
  /// A refused observation of landmark id at (lx, ly): range and bearing from the vehicle with
  /// their sigmas. Returns the pose when the kept observations agree (then forgets them).
  std::optional<Found> add(int64_t utime, int id, double lx, double ly, double range, double bearing, double range_std,
                           double bearing_std, double gate2);

 private:
  struct Seen {
    int64_t utime = 0;
    int id = 0;
    Vec2 world;     ///< the landmark in the map
    Vec2 dr;        ///< where the observation puts it in the dead-reckoned frame
    double var = 0; ///< variance of that position per axis [m^2]
  };
  Pose dr_ = Pose::Zero();  ///< the vehicle in the dead-reckoned frame
  std::deque<Seen> seen_;
};

}  // namespace lcmloc::core::detail
