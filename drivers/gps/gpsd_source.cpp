#include "gpsd_source.hpp"

#include <gps.h>

#include <cerrno>
#include <cmath>
#include <cstring>

#include "lcmloc/bus/transport.hpp"

namespace lcmloc::gps {

struct GpsdSource::Impl {
  gps_data_t data{};
  bool open = false;
};

GpsdSource::GpsdSource(const std::string& host, const std::string& port, bool use_fix_time)
    : impl_(std::make_unique<Impl>()), use_fix_time_(use_fix_time) {
  if (gps_open(host.c_str(), port.c_str(), &impl_->data) != 0)
    throw GpsdError("cannot connect to gpsd at " + host + ":" + port + ": " + gps_errstr(errno));
  impl_->open = true;
  if (gps_stream(&impl_->data, WATCH_ENABLE | WATCH_JSON, nullptr) != 0)
    throw GpsdError("gpsd at " + host + ":" + port + " refused WATCH: " + gps_errstr(errno));
}

GpsdSource::~GpsdSource() {
  if (impl_ && impl_->open) {
    gps_stream(&impl_->data, WATCH_DISABLE, nullptr);
    gps_close(&impl_->data);
  }
}

std::optional<lcmloc::gps_fix_t> GpsdSource::poll(int timeout_ms) {
  if (!gps_waiting(&impl_->data, timeout_ms * 1000)) {
    if (errno != 0 && errno != EINTR && errno != EAGAIN)
      throw GpsdError(std::string("gpsd connection: ") + gps_errstr(errno));
    return std::nullopt;
  }
  errno = 0;
  if (gps_read(&impl_->data, nullptr, 0) < 0) throw GpsdError("gpsd closed the connection");
  const gps_data_t& d = impl_->data;
  if (!(d.set & MODE_SET)) return std::nullopt;  // not a TPV report
  impl_->data.set = 0;
  ++reports_;
  lcmloc::gps_fix_t m{};
  const bool time_ok = d.fix.time.tv_sec > 0;
  if (use_fix_time_ && !time_ok) return std::nullopt;  // a report without time cannot be ordered
  m.utime = use_fix_time_
                ? static_cast<int64_t>(d.fix.time.tv_sec) * 1000000 + d.fix.time.tv_nsec / 1000
                : bus::wallMicros();
  const int mode = d.fix.mode;
  m.fix_type = static_cast<int8_t>(mode >= MODE_2D && std::isfinite(d.fix.latitude) &&
                                           std::isfinite(d.fix.longitude)
                                       ? mode
                                       : 1);
  m.latitude = std::isfinite(d.fix.latitude) ? d.fix.latitude : 0.0;
  m.longitude = std::isfinite(d.fix.longitude) ? d.fix.longitude : 0.0;
  m.altitude = std::isfinite(d.fix.altHAE) ? d.fix.altHAE : 0.0;
  m.satellites = static_cast<int16_t>(d.satellites_used);
  m.hdop = std::isfinite(d.dop.hdop) ? d.dop.hdop : 0.0;
  // gpsd's eph is a 95 % horizontal error; 1 sigma per axis ~ eph / 2.45 (2-D Gaussian).
  m.position_std = std::isfinite(d.fix.eph) && d.fix.eph > 0 ? d.fix.eph / 2.45 : 0.0;
  return m;
}

}  // namespace lcmloc::gps
