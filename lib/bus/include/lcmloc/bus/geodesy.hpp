#pragma once
// Latitude/longitude <-> the local metric frame (x east, y north, z up) about a configurable
// datum, through GeographicLib's LocalCartesian (WGS-84). Used by the GPS driver (local truth
// -> lat/lon), the fusion daemon (lat/lon -> local GpsInput) and the Victoria Park import.
#include <memory>

namespace lcmloc::bus {

struct Datum {
  double latitude = -33.8830;   ///< [deg] (default: Sydney, near Victoria Park)
  double longitude = 151.1950;  ///< [deg]
  double altitude = 0.0;        ///< height above the WGS-84 ellipsoid [m]
};

class LocalFrame {
 public:
  /// Throws std::invalid_argument when the datum is out of range.
  explicit LocalFrame(const Datum& datum);
  ~LocalFrame();
  LocalFrame(LocalFrame&&) noexcept;
  LocalFrame& operator=(LocalFrame&&) noexcept;
  /// lat/lon [deg], h [m] -> local x east, y north, z up [m].
  void toLocal(double lat, double lon, double h, double& x, double& y, double& z) const;
  /// local [m] -> lat/lon [deg], h [m].
  void toGeodetic(double x, double y, double z, double& lat, double& lon, double& h) const;
  const Datum& datum() const { return datum_; }
 private:
  Datum datum_;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lcmloc::bus
