#pragma once
// Measurement model of the magnetic ruler (paper eq. 3-6).
#include "lcmloc/core/types.hpp"

namespace lcmloc::core {

/// eq. 6: range-bearing (d, alpha) of a marker seen by the ruler at lateral offset d_m,
/// the ruler being L1 [m] ahead of M. alpha = atan2(d_m, L1).
Vec2 rulerObservation(double lateral_offset, double ruler_offset_l1);

/// eq. 3/5: predicted range-bearing (d, alpha) of marker (xm, ym) from pose; alpha wrapped.
Vec2 predictRangeBearing(const Pose& pose, double xm, double ym);

/// Marker position in the body frame (forward, left) [m].
Vec2 markerInBody(const Pose& pose, double xm, double ym);

}  // namespace lcmloc::core
