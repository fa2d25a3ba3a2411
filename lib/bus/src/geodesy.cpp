#include "lcmloc/bus/geodesy.hpp"

#include <GeographicLib/LocalCartesian.hpp>

#include <cmath>
#include <stdexcept>

namespace lcmloc::bus {

struct LocalFrame::Impl {
  GeographicLib::LocalCartesian lc;
};

LocalFrame::LocalFrame(const Datum& d) : datum_(d) {
  if (!(std::abs(d.latitude) <= 90.0) || !(std::abs(d.longitude) <= 180.0) ||
      !std::isfinite(d.altitude))
    throw std::invalid_argument("datum: latitude must be in [-90, 90], longitude in [-180, 180]");
  impl_ = std::make_unique<Impl>(Impl{GeographicLib::LocalCartesian(d.latitude, d.longitude, d.altitude)});
}
LocalFrame::~LocalFrame() = default;
LocalFrame::LocalFrame(LocalFrame&&) noexcept = default;
LocalFrame& LocalFrame::operator=(LocalFrame&&) noexcept = default;

void LocalFrame::toLocal(double lat, double lon, double h, double& x, double& y, double& z) const {
  impl_->lc.Forward(lat, lon, h, x, y, z);
}

void LocalFrame::toGeodetic(double x, double y, double z, double& lat, double& lon, double& h) const {
  impl_->lc.Reverse(x, y, z, lat, lon, h);
}

}  // namespace lcmloc::bus
