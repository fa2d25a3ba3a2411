// Reading estimates, truth and gate decisions of any log through LogScanner.
#include <algorithm>
#include <cmath>
#include <memory>

#include <lcm/lcm-cpp.hpp>

#include "lcmloc/eval/trajectory.hpp"
#include "lcmloc/fault_event_t.hpp"
#include "lcmloc/gate_decision_t.hpp"
#include "lcmloc/gps_fix_t.hpp"
#include "lcmloc/landmark_obs_t.hpp"
#include "lcmloc/ground_truth_t.hpp"
#include "lcmloc/pose_t.hpp"

namespace lcmloc::eval {
namespace {

bool finite(double v) { return std::isfinite(v); }

class TrajectoryDecoder {
 public:
  TrajectoryDecoder(const TrajectoryLogOptions& opt, TrajectoryLog& out) : opt_(opt), out_(out) {
    out_.tracks.push_back({opt.pose_channel, {}, {}, {}});
    out_.landmark_channel = opt.landmark_channel;
  }

  void handle(const lcm::LogEvent& ev, int64_t index, int64_t offset) {
    index_ = index;
    offset_ = offset;
    const std::string& c = ev.channel;
    if (c == opt_.truth_channel) truth(ev);
    else if (c == opt_.pose_channel) pose(ev, 0);
    else if (opt_.all_pose_channels && c.size() > 5 && c.compare(0, 5, "POSE_") == 0) pose(ev, trackIndex(c));
    else if (c == opt_.gate_channel) gate(ev);
    else if (c == opt_.fault_channel) fault(ev);
    else if (!opt_.landmark_channel.empty() && c == opt_.landmark_channel) landmark(ev);
  }

  /// Sorts every track and the truth by utime; extra tracks by channel name.
  void finish() {
    for (auto& t : out_.tracks)
      std::stable_sort(t.poses.begin(), t.poses.end(),
                       [](const Estimate& a, const Estimate& b) { return a.utime < b.utime; });
    std::stable_sort(out_.tracks.begin() + 1, out_.tracks.end(),
                     [](const EstimateTrack& a, const EstimateTrack& b) { return a.channel < b.channel; });
    auto& tr = out_.truth;
    std::stable_sort(tr.begin(), tr.end(), [](const TruthPose& a, const TruthPose& b) { return a.utime < b.utime; });
    // One sample per utime: the last one recorded.
    std::vector<TruthPose> unique;
    for (const auto& s : tr) {
      if (!unique.empty() && unique.back().utime == s.utime) unique.back() = s;
      else unique.push_back(s);
    }
    if (unique.size() != tr.size())
      issue("truth channel " + opt_.truth_channel + ": " + std::to_string(tr.size() - unique.size()) +
            " samples with a duplicate utime (the last of each kept; a log of a restarted simulator holds its runs "
            "one after the other: `lcmloc-log cut` by log time gives each its own log)",
            -1, -1);
    tr = std::move(unique);
  }

 private:
  void issue(const std::string& what, int64_t index, int64_t offset) { out_.issues.push_back({index, offset, what}); }
  void issue(const std::string& what) { issue(what, index_, offset_); }
  /// False, counted and reported, for |utime| >= kUtimeLimit.
  bool usable(const lcm::LogEvent& ev, int64_t utime) {
    if (usableUtime(utime)) return true;
    ++out_.bad_utime;
    issue(badUtimeIssue(ev.channel, utime));
    return false;
  }

  template <typename T>
  bool decode(const lcm::LogEvent& ev, T& msg, bool report = true) {
    if (msg.decode(ev.data, 0, ev.datalen) >= 0) return true;
    if (report) {
      ++out_.undecodable[ev.channel];
      issue("undecodable " + ev.channel + " message (" + std::to_string(ev.datalen) + " bytes, not a " +
            T::getTypeName() + ")");
    }
    return false;
  }

  std::size_t trackIndex(const std::string& channel) {
    for (std::size_t i = 1; i < out_.tracks.size(); ++i)
      if (out_.tracks[i].channel == channel) return i;
    out_.tracks.push_back({channel, {}, {}, {}});
    return out_.tracks.size() - 1;
  }

  void pose(const lcm::LogEvent& ev, std::size_t k) {
    lcmloc::pose_t m{};
    if (!decode(ev, m) || !usable(ev, m.utime)) return;
    if (m.dim < 3 || m.state.size() < 3) return issue(ev.channel + " seq " + std::to_string(m.seq) + ": fewer than 3 states");
    if (!finite(m.state[0]) || !finite(m.state[1]) || !finite(m.state[2]))
      return issue(ev.channel + " seq " + std::to_string(m.seq) + ": non-finite state");
    EstimateTrack& t = out_.tracks[k];
    if (std::find(t.filters.begin(), t.filters.end(), m.filter) == t.filters.end()) t.filters.push_back(m.filter);
    Estimate e;
    e.utime = m.utime;
    e.x = m.state[0];
    e.y = m.state[1];
    e.theta = m.state[2];
    e.status = m.status;
    e.has_cov = m.covariance.size() >= 3;
    for (int r = 0; r < 3 && e.has_cov; ++r) {
      if (m.covariance[static_cast<std::size_t>(r)].size() < 3) { e.has_cov = false; break; }
      for (int c = 0; c < 3; ++c) {
        const double v = m.covariance[static_cast<std::size_t>(r)][static_cast<std::size_t>(c)];
        if (!finite(v)) e.has_cov = false;
        e.cov(r, c) = v;
      }
    }
    t.poses.push_back(e);
    // The self-calibration states ("cal_*", FilterConfig::Calibration) of the newest estimate.
    t.calibration.clear();
    for (std::size_t i = 3; i < m.state.size() && i < m.state_names.size(); ++i) {
      if (m.state_names[i].rfind("cal_", 0) != 0) continue;
      const double var = i < m.covariance.size() && i < m.covariance[i].size() ? m.covariance[i][i] : NAN;
      t.calibration.push_back({m.state_names[i].substr(4), m.state[i], std::sqrt(std::max(var, 0.0))});
    }
  }

  void truth(const lcm::LogEvent& ev) {
    lcmloc::ground_truth_t g{};
    if (decode(ev, g, false)) {
      if (!usable(ev, g.utime)) return;
      if (!finite(g.x) || !finite(g.y) || std::isinf(g.heading))
        return issue("truth seq " + std::to_string(g.seq) + ": non-finite pose");
      noteTruthType("ground_truth_t");
      // a NaN heading: a truth of position only (lcmloc-import's ground truth without heading)
      const bool has_heading = !std::isnan(g.heading);
      out_.truth.push_back({g.utime, g.x, g.y, has_heading ? g.heading : 0.0, has_heading});
      return;
    }
    lcmloc::gps_fix_t f{};
    if (!decode(ev, f, false)) {
      ++out_.undecodable[ev.channel];
      issue("undecodable " + ev.channel + " message (" + std::to_string(ev.datalen) +
            " bytes, neither a ground_truth_t nor a gps_fix_t)");
      return;
    }
    if (!opt_.datum) {
      if (!datum_reported_)
        issue("truth channel " + ev.channel + " holds gps_fix_t: a datum is needed to convert latitude and "
              "longitude to the local frame (--datum or --config); these samples are not used");
      datum_reported_ = true;
      return;
    }
    if (f.fix_type < 2 || !finite(f.latitude) || !finite(f.longitude))
      return issue("truth fix seq " + std::to_string(f.seq) + ": no position fix");
    if (!usable(ev, f.utime)) return;
    if (!frame_) frame_ = std::make_unique<bus::LocalFrame>(*opt_.datum);
    double x = 0, y = 0, z = 0;
    frame_->toLocal(f.latitude, f.longitude, finite(f.altitude) ? f.altitude : 0.0, x, y, z);
    noteTruthType("gps_fix_t");
    out_.truth.push_back({f.utime, x, y, 0.0, false});
  }

  void noteTruthType(const char* type) {
    if (out_.truth_type.empty()) out_.truth_type = type;
    else if (out_.truth_type != type && !mixed_reported_) {
      issue("truth channel " + opt_.truth_channel + " mixes ground_truth_t and gps_fix_t; heading is used "
            "where present");
      mixed_reported_ = true;
    }
  }

  void gate(const lcm::LogEvent& ev) {
    lcmloc::gate_decision_t m{};
    if (!decode(ev, m) || !usable(ev, m.utime)) return;
    out_.gates.push_back({m.utime, m.filter, m.sensor, m.reason, m.dim, m.mahalanobis, m.accepted != 0,
                          m.measurement_seq, m.gate});
  }

  void fault(const lcm::LogEvent& ev) {
    lcmloc::fault_event_t m{};
    if (!decode(ev, m) || !usable(ev, m.utime)) return;
    out_.faults.push_back({m.utime, m.kind, m.channel, m.measurement_seq});
  }

  void landmark(const lcm::LogEvent& ev) {
    lcmloc::landmark_obs_t m{};
    if (!decode(ev, m) || !usable(ev, m.utime)) return;
    ++out_.landmark_observations;
    if (m.landmark_id < 0) out_.unknown_identity.emplace_back(ev.channel, m.seq);
  }

  const TrajectoryLogOptions& opt_;
  TrajectoryLog& out_;
  std::unique_ptr<bus::LocalFrame> frame_;
  int64_t index_ = 0, offset_ = 0;
  bool datum_reported_ = false, mixed_reported_ = false;
};

}  // namespace

TrajectoryLog readTrajectoryLog(const std::string& path, const TrajectoryLogOptions& opt,
                                const std::atomic<bool>* stop, const std::function<void(int64_t, int64_t)>& progress) {
  TrajectoryLog out;
  out.path = path;
  logio::LogScanner scanner(path, &out.issues);
  out.file_size = scanner.fileSize();
  TrajectoryDecoder decoder(opt, out);
  while (!(stop && stop->load())) {
    const lcm::LogEvent* ev = scanner.next();
    if (!ev) break;
    ++out.channel_counts[ev->channel];
    decoder.handle(*ev, scanner.eventsRead() - 1, scanner.eventOffset());
    if (progress && (scanner.eventsRead() & 0xFFFF) == 0) progress(scanner.position(), scanner.fileSize());
  }
  if (stop && stop->load()) out.interrupted = true;
  decoder.finish();
  out.events_read = scanner.eventsRead();
  out.bytes_unreadable = scanner.bytesUnreadable();
  out.damaged = scanner.damaged();
  std::stable_sort(out.issues.begin(), out.issues.end(),
                   [](const LogIssue& a, const LogIssue& b) { return a.byte_offset < b.byte_offset; });
  return out;
}

}  // namespace lcmloc::eval
