#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "lcmloc/common/csv.hpp"
#include "lcmloc/common/geodesy.hpp"
#include "lcmloc/import/event_log.hpp"
#include "lcmloc/gps_fix_t.hpp"
#include "lcmloc/odometry_t.hpp"
#include "lcmloc/vp/vp.hpp"

namespace lcmloc::vp {
namespace {
using common::csv::parseRow;
std::ifstream openCsv(const std::string& path, const std::string& header) {
  return common::csv::openWithHeader(path, header);
}
}  // namespace

ImportResult importVictoriaPark(const ImportOptions& opt) {
  if (!(opt.wheelbase > 0) || !std::isfinite(opt.encoder_offset))
    throw std::invalid_argument("wheelbase must be > 0 and the encoder offset finite");
  if (opt.holdout_every < 0 || (opt.holdout_every > 0 && (opt.holdout_phase < 0 || opt.holdout_phase >= opt.holdout_every)))
    throw std::invalid_argument("holdout: every must be >= 0 and phase in [0, every)");
  ImportResult r;
  import::EventLog events;
  const common::LocalFrame frame(opt.datum);
  auto refuse = [&](const std::string& file, int64_t line, const std::string& why) {
    r.refusals.push_back({file, line, why});
  };
  auto stopped = [&] { return opt.stop && opt.stop(); };
  int64_t last_odo_utime = 0;

  // Odometry: the speed and steering of a row hold over the interval up to the next accepted row.
  {
    auto in = openCsv(opt.odometry_csv, "time_ms,speed_mps,steering_rad");
    std::string line, why;
    std::vector<double> v;
    int64_t lineno = 1, seq = 0;
    bool have_prev = false;
    double t_prev = 0, speed_prev = 0, steer_prev = 0;
    while (std::getline(in, line)) {
      ++lineno;
      if (line.empty() || line == "\r") continue;
      if (opt.max_rows > 0 && r.odometry_rows >= opt.max_rows) break;
      if ((r.odometry_rows & 4095) == 0 && stopped()) { r.interrupted = true; break; }
      ++r.odometry_rows;
      if (!parseRow(line, 3, v, why)) { refuse(opt.odometry_csv, lineno, why); continue; }
      const double t = v[0], speed = v[1], steer = v[2];
      if (t < 0) { refuse(opt.odometry_csv, lineno, fmt::format("negative time {} ms", t)); continue; }
      if (have_prev && !(t > t_prev)) {
        refuse(opt.odometry_csv, lineno, fmt::format("time {} ms not after the previous row's {} ms", t, t_prev));
        continue;
      }
      if (std::abs(speed) > opt.max_speed) {
        refuse(opt.odometry_csv, lineno, fmt::format("|speed| {} m/s above {} m/s", speed, opt.max_speed));
        continue;
      }
      if (std::abs(steer) > opt.max_steering) {
        refuse(opt.odometry_csv, lineno, fmt::format("|steering| {} rad above {} rad", steer, opt.max_steering));
        continue;
      }
      lcmloc::odometry_t m{};
      m.utime = std::llround(t * 1000.0);
      m.seq = seq++;
      m.ticks = 0;
      m.has_steering = true;
      if (have_prev) {
        const double dt = (t - t_prev) * 1e-3;
        if (dt > 0.5) ++r.odometry_gaps;
        // encoder on the rear left wheel, H to the left of the axle centre M (README):
        // v_M = v_e / (1 - tan(psi) H / L)
        const double vc = speed_prev / (1.0 - std::tan(steer_prev) * opt.encoder_offset / opt.wheelbase);
        m.delta_s = vc * dt;
        m.steering = steer_prev;
        m.delta_theta = m.delta_s * std::tan(steer_prev) / opt.wheelbase;  // eq. 2
      } else {
        m.delta_s = 0;  // the first row only starts the interval
        m.steering = steer;
        m.delta_theta = 0;
      }
      r.distance_m += std::abs(m.delta_s);
      have_prev = true;
      t_prev = t;
      speed_prev = speed;
      steer_prev = steer;
      ++r.odometry_written;
      events.add(m.utime, 0, opt.odometry_channel, m);
      last_odo_utime = m.utime;
    }
    r.odometry_refused = r.odometry_rows - r.odometry_written;
  }

  // GPS: local metres -> lat/lon about the datum; every k-th accepted fix held out.
  if (!r.interrupted) {
    auto in = openCsv(opt.gps_csv, "time_ms,Lo_m,La_m");
    std::string line, why;
    std::vector<double> v;
    int64_t lineno = 1, seq = 0, hseq = 0, index = 0;
    bool have_prev = false;
    double t_prev = 0;
    while (std::getline(in, line)) {
      ++lineno;
      if (line.empty() || line == "\r") continue;
      if (!parseRow(line, 3, v, why)) {
        ++r.gps_rows;
        refuse(opt.gps_csv, lineno, why);
        continue;
      }
      const double t = v[0], x = v[1], y = v[2];
      // a slice (max_rows): the GPS rows of the odometry's time span only
      if (opt.max_rows > 0 && std::llround(t * 1000.0) > last_odo_utime) break;
      ++r.gps_rows;
      if (t < 0) { refuse(opt.gps_csv, lineno, fmt::format("negative time {} ms", t)); continue; }
      if (have_prev && !(t > t_prev)) {
        refuse(opt.gps_csv, lineno, fmt::format("time {} ms not after the previous row's {} ms", t, t_prev));
        continue;
      }
      if (std::abs(x) > 1e5 || std::abs(y) > 1e5) {
        refuse(opt.gps_csv, lineno, fmt::format("position ({}, {}) m more than 100 km from the origin", x, y));
        continue;
      }
      have_prev = true;
      t_prev = t;
      const bool held = opt.holdout_every > 0 && index % opt.holdout_every == opt.holdout_phase;
      ++index;
      lcmloc::gps_fix_t m{};
      m.utime = std::llround(t * 1000.0);
      m.seq = held ? hseq++ : seq++;
      double h = 0;
      frame.toGeodetic(x, y, 0.0, m.latitude, m.longitude, h);
      m.altitude = h;
      m.fix_type = 2;
      m.satellites = 0;
      m.hdop = NAN;
      m.position_std = opt.gps_std;
      r.fixes.push_back({m.utime, x, y, held});
      (held ? r.heldout_written : r.gps_written)++;
      events.add(m.utime, 1, held ? opt.heldout_channel : opt.gps_channel, m);
    }
    r.gps_refused = r.gps_rows - r.gps_written - r.heldout_written;
  }

  events.sort();
  if (!events.empty()) {
    r.first_utime = events.firstUtime();
    r.last_utime = events.lastUtime();
  }
  if (!opt.output.empty()) events.write(opt.output);
  return r;
}

std::string importSummary(const ImportOptions& opt, const ImportResult& r, int max_refusals) {
  std::string s = fmt::format(
      "odometry: {} rows read, {} refused, {} messages on {} ({} intervals > 0.5 s), {:.1f} m travelled\n"
      "gps: {} rows read, {} refused, {} fixes on {}, {} held out on {} (every {}th, phase {})\n"
      "time span: {:.3f} s .. {:.3f} s ({:.1f} s)\n",
      r.odometry_rows, r.odometry_refused, r.odometry_written, opt.odometry_channel, r.odometry_gaps, r.distance_m,
      r.gps_rows, r.gps_refused, r.gps_written, opt.gps_channel, r.heldout_written, opt.heldout_channel,
      opt.holdout_every, opt.holdout_phase, r.first_utime * 1e-6, r.last_utime * 1e-6,
      (r.last_utime - r.first_utime) * 1e-6);
  int n = 0;
  for (const auto& f : r.refusals) {
    if (n++ >= max_refusals) {
      s += fmt::format("... and {} more refused rows\n", r.refusals.size() - static_cast<std::size_t>(max_refusals));
      break;
    }
    s += fmt::format("refused {}:{}: {}\n", f.file, f.line, f.reason);
  }
  if (r.interrupted) s += "interrupted: the output holds what was read so far\n";
  return s;
}

}  // namespace lcmloc::vp
