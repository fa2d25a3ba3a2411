#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "lcmloc/app/config.hpp"
#include "lcmloc/app/csv.hpp"
#include "lcmloc/bus/geodesy.hpp"
#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/files.hpp"
#include "lcmloc/app/signals.hpp"
#include "lcmloc/import/checks.hpp"
#include "lcmloc/import/event_log.hpp"
#include "lcmloc/gps_fix_t.hpp"
#include "lcmloc/odometry_t.hpp"
#include "lcmloc/vp/vp.hpp"

namespace lcmloc::vp {
namespace {

/// The data rows of one file, read whole (the time-order rule looks at the next row): each row's
/// three numbers, its time in microseconds, and why it is refused so far ("" = usable).
struct Rows {
  std::vector<int64_t> line;
  std::vector<std::vector<double>> v;
  std::vector<std::optional<int64_t>> utime;  ///< nullopt: no usable time
  std::vector<std::string> why;
  std::size_t size() const { return line.size(); }
};

/// Reads the rows after header (at most max_rows non-empty rows; 0 = all): not a number, not
/// finite, wrong column count, negative or out-of-range time, then the time-order rule
/// (import::checkTimeOrder: strictly increasing, a single time far ahead refused alone).
Rows readRows(const std::string& path, const std::string& header, int64_t max_rows) {
  auto in = app::csv::openWithHeader(path, header);
  Rows r;
  std::string text, why;
  std::vector<double> v;
  for (int64_t lineno = 2; std::getline(in, text); ++lineno) {
    if (text.empty() || text == "\r") continue;
    if (max_rows > 0 && static_cast<int64_t>(r.size()) >= max_rows) break;
    r.line.push_back(lineno);
    r.utime.emplace_back();
    if (!app::csv::parseRow(text, 3, v, why)) {
      r.v.emplace_back();
      r.why.push_back(why);
      continue;
    }
    r.v.push_back(v);
    r.why.emplace_back();
    if (v[0] < 0) r.why.back() = fmt::format("negative time {} ms", v[0]);
    else if (!(r.utime.back() = import::toMicros(v[0], 1e3))) r.why.back() = fmt::format("time {} ms out of range", v[0]);
  }
  const auto order = import::checkTimeOrder(r.utime, true);
  for (std::size_t i = 0; i < r.size(); ++i)
    if (order[i].kind != import::TimeVerdict::Kept)
      r.why[i] = import::timeOrderReason(r.utime, i, order[i], true,
                                         [&](std::size_t k) { return fmt::format("{} ms", r.v[k][0]); });
  return r;
}

}  // namespace

void checkImportOptions(const ImportOptions& opt) {
  auto refuse = [](const std::string& flag, const std::string& why) { throw app::ConfigError(flag, "", why); };
  if (!(opt.wheelbase > 0)) refuse("--wheelbase", fmt::format("{} is not > 0", opt.wheelbase));
  const double h = opt.encoder_offset;
  if (!(h >= kEncoderOffset.lo && h <= kEncoderOffset.hi))
    refuse("--encoder-offset", fmt::format("{} m is not in [{}, {}] m (half a vehicle's track at most)", h,
                                           kEncoderOffset.lo, kEncoderOffset.hi));
  // v_M = v_e / (1 - tan(psi) H / L): finite for every steering angle the import accepts
  if (std::abs(h) * std::tan(opt.max_steering) >= opt.wheelbase)
    refuse("--encoder-offset", fmt::format("{} m with --wheelbase {} m: the speed correction 1 / (1 - tan(psi) H / L) "
                                           "is infinite at a steering angle within {} rad",
                                           h, opt.wheelbase, opt.max_steering));
  if (opt.holdout_every < 0) refuse("--holdout-every", fmt::format("{} is not >= 0", opt.holdout_every));
  if (opt.holdout_phase < 0 || (opt.holdout_every > 0 && opt.holdout_phase >= opt.holdout_every))
    refuse("--holdout-phase",
           opt.holdout_every > 0 ? fmt::format("{} is not in [0, {}] (fix i is held out when i % --holdout-every {} == "
                                               "phase)", opt.holdout_phase, opt.holdout_every - 1, opt.holdout_every)
                                 : fmt::format("{} is not >= 0", opt.holdout_phase));
  const std::string& held = opt.heldout_channel;
  if (held.empty() || held.find_first_of(" \t\n") != std::string::npos)
    refuse("--heldout-channel", "'" + held + "': a channel name must be non-empty and without blanks");
  if (held == opt.gps_channel)
    refuse("--heldout-channel",
           "'" + held + "' is the GPS channel (channels.gps) the filters read: nothing would be held out");
  if (held == opt.odometry_channel)
    refuse("--heldout-channel",
           "'" + held + "' is the odometry channel (channels.odometry): the held-out fixes would be mixed into it");
}

ImportResult importVictoriaPark(const ImportOptions& opt) {
  checkImportOptions(opt);
  if (!opt.output.empty()) app::refuseOutputOverInputs("--output", opt.output, {opt.odometry_csv, opt.gps_csv});
  ImportResult r;
  import::EventLog events;
  const bus::LocalFrame frame(opt.datum);
  auto refuse = [&](const std::string& file, int64_t line, const std::string& why) {
    r.refusals.push_back({file, line, why});
  };
  auto stopped = [&] { return opt.stop && opt.stop(); };
  int64_t last_odo_utime = 0;

  // Odometry: the speed and steering of a row hold over the interval up to the next accepted row.
  {
    const Rows rows = readRows(opt.odometry_csv, "time_ms,speed_mps,steering_rad", opt.max_rows);
    int64_t seq = 0;
    bool have_prev = false;
    double t_prev = 0, speed_prev = 0, steer_prev = 0;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      if ((r.odometry_rows & 4095) == 0 && stopped()) { r.interrupted = true; break; }
      ++r.odometry_rows;
      if (!rows.why[i].empty()) { refuse(opt.odometry_csv, rows.line[i], rows.why[i]); continue; }
      const double t = rows.v[i][0], speed = rows.v[i][1], steer = rows.v[i][2];
      if (std::abs(speed) > opt.max_speed) {
        refuse(opt.odometry_csv, rows.line[i], fmt::format("|speed| {} m/s above {} m/s", speed, opt.max_speed));
        continue;
      }
      if (std::abs(steer) > opt.max_steering) {
        refuse(opt.odometry_csv, rows.line[i], fmt::format("|steering| {} rad above {} rad", steer, opt.max_steering));
        continue;
      }
      lcmloc::odometry_t m{};
      m.utime = *rows.utime[i];
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
    const Rows rows = readRows(opt.gps_csv, "time_ms,Lo_m,La_m", 0);
    int64_t seq = 0, hseq = 0, index = 0;
    for (std::size_t i = 0; i < rows.size(); ++i) {
      // a slice (max_rows): the GPS rows of the odometry's time span only (a row refused for its
      // time, an outlier say, does not end it)
      if (opt.max_rows > 0 && rows.why[i].empty() && *rows.utime[i] > last_odo_utime) break;
      ++r.gps_rows;
      if (!rows.why[i].empty()) { refuse(opt.gps_csv, rows.line[i], rows.why[i]); continue; }
      const double x = rows.v[i][1], y = rows.v[i][2];
      if (std::abs(x) > 1e5 || std::abs(y) > 1e5) {
        refuse(opt.gps_csv, rows.line[i], fmt::format("position ({}, {}) m more than 100 km from the origin", x, y));
        continue;
      }
      const bool held = opt.holdout_every > 0 && index % opt.holdout_every == opt.holdout_phase;
      ++index;
      lcmloc::gps_fix_t m{};
      m.utime = *rows.utime[i];
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

int importCommand(const app::SystemConfig& cfg, ImportOptions io, const std::string& dir, int max_refusals,
                  bool overwrite) {
  if (io.odometry_csv.empty() && !dir.empty()) io.odometry_csv = dir + "/vp_odometry.csv";
  if (io.gps_csv.empty() && !dir.empty()) io.gps_csv = dir + "/vp_gps.csv";
  if (io.odometry_csv.empty() || io.gps_csv.empty())
    throw app::UsageError("give --dir DIR or both --odometry FILE and --gps FILE");
  app::requireInputFile(io.odometry_csv, "--odometry");
  app::requireInputFile(io.gps_csv, "--gps");
  app::refuseExistingOutput(io.output, overwrite);
  io.datum = cfg.datum;
  io.odometry_channel = cfg.channels.odometry;
  io.gps_channel = cfg.channels.gps;
  io.stop = [] { return app::stopRequested(); };
  spdlog::info("importing {} and {} -> {}", io.odometry_csv, io.gps_csv, io.output);
  const auto r = importVictoriaPark(io);
  std::cout << importSummary(io, r, max_refusals);
  return app::kExitOk;
}

}  // namespace lcmloc::vp
