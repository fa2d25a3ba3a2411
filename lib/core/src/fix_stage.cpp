#include "lcmloc/core/fix_stage.hpp"

#include <cmath>
#include <stdexcept>
#include <vector>

#include "filter_internal.hpp"
#include "lcmloc/core/angles.hpp"
#include "lcmloc/core/chi2.hpp"
#include "lcmloc/core/landmark_fix.hpp"

namespace lcmloc::core {

LandmarkFixStage::LandmarkFixStage(const EngineConfig& cfg, FilterBank& bank, const EngineOutputs& out,
                                   EngineCounters& counters)
    : landmarks_(cfg.landmarks), options_(cfg.fix), gate_cfg_(cfg.fix_gate), bank_(bank), out_(out),
      counters_(counters) {
  const LandmarkFixGate& g = gate_cfg_;
  if (!(g.probability >= 0.0 && g.probability < 1.0) || g.lockout_rejections < 0)
    throw std::invalid_argument("fix gate: probability must be in [0, 1) and lockout_rejections >= 0");
  if (g.probability > 0.0) gate_ = chi2Quantile(g.probability, 3);
}

int LandmarkFixStage::refusedInARow(const std::string& filter_key) const {
  const auto it = refused_.find(filter_key);
  return it == refused_.end() ? 0 : it->second;
}

void LandmarkFixStage::process(const EngineInput& in, const BearingsInput& b) {
  Filter& active = bank_.active();
  GateDecision d = detail::decision(in.utime, b.sensor.empty() ? in.channel : b.sensor, in.seq,
                                    std::numeric_limits<double>::infinity());
  auto refuse = [&](const std::string& reason, EventKind kind, const std::string& why) {
    d.reason = reason;
    out_.decision(active.name(), true, d);
    ++counters_.rejected;
    out_.event(kind, in.utime, events::FixNotMade{refOf(in), why});
  };
  if (b.ids.size() != b.bearings.size())
    return refuse("bad_input", EventKind::BadInput, "ids and bearings differ in count");
  for (double a : b.bearings)
    if (!std::isfinite(a)) return refuse("bad_input", EventKind::BadInput, "non-finite bearing");
  for (int id : b.ids)
    if (!landmarks_.count(id))
      return refuse("bad_input", EventKind::BadInput, "landmark " + std::to_string(id) + " not in the map");
  if (b.ids.size() < 3) {
    // Fewer than three landmarks in view is a normal reading (the vehicle is away from them):
    // a decision that says so, no event.
    d.reason = "too_few_landmarks";
    out_.decision(active.name(), true, d);
    return;
  }
  if (b.ids.size() != 3) return refuse("bad_input", EventKind::BadInput, "need exactly three bearings");
  const FilterState prior = active.state();
  if (!prior.x.head<3>().allFinite()) return refuse("bad_input", EventKind::BadInput, "filter pose not finite");
  // Bearings CCW from the body x (forward) axis -> clockwise from the body axis (landmark_fix);
  // theta CCW from east -> heading clockwise from north.
  std::vector<landmark::Bearing> bs;
  for (std::size_t i = 0; i < b.ids.size(); ++i) bs.push_back({b.ids[i], -b.bearings[i]});
  landmark::FixOptions o = options_;
  if (std::isfinite(b.bearing_std) && b.bearing_std > 0) o.sigma_bearing = b.bearing_std;
  const double psi_prior = wrapAngle(M_PI / 2 - prior.x[2]);
  const landmark::FixResult r = landmark::leastSquaresFix(landmarks_, bs, prior.x.head<2>(), psi_prior, o);
  if (!r.ok) return refuse("geometry", EventKind::FixRefused, r.error);
  PoseFix fix;
  fix.utime = in.utime;
  fix.pose = Vec3(r.position.x(), r.position.y(), wrapAngle(M_PI / 2 - r.heading));
  Mat3 J = Mat3::Identity();
  J(2, 2) = -1.0;
  fix.cov = J * r.covariance * J.transpose();
  fix.source = in.channel;
  d.gate = gate_;
  bool active_took_it = false;
  bank_.forEach([&](Filter& f, bool is_active) {
    GateDecision fd = d;
    const FilterState s = is_active ? prior : f.state();
    Vec3 v = fix.pose - s.x.head<3>();
    v[2] = wrapAngle(v[2]);
    const Mat3 S = s.P.topLeftCorner<3, 3>() + fix.cov;
    fd.innovation = v;
    fd.mahalanobis = v.dot(S.ldlt().solve(v));
    int& refused = refused_[FilterBank::key(f, is_active)];
    // A NaN distance (a broken state) is not outside: the fix repairs the filter (applyFix).
    const bool outside = fd.mahalanobis > gate_;
    const int lockout_after = gate_cfg_.lockout_rejections;
    const bool lockout = outside && lockout_after > 0 && refused >= lockout_after;
    if (outside && !lockout) {
      ++refused;
      fd.reason = "gate";
      if (is_active) ++counters_.rejected;
      out_.decision(f.name(), is_active, fd);
      out_.event(EventKind::FixRefused, in.utime, events::FixGated{refOf(in), f.name(), fd.mahalanobis, gate_, refused});
      return;
    }
    fd.reason = lockout ? "fix_lockout" : "fix";
    fd.accepted = bank_.applyFix(f, is_active, fix);
    if (!fd.accepted) fd.reason = "bad_input";
    if (fd.accepted) refused = 0;
    if (is_active) active_took_it = fd.accepted;
    if (is_active) ++(fd.accepted ? counters_.accepted : counters_.rejected);
    out_.decision(f.name(), is_active, fd);
    bank_.emitState(f, is_active);
    if (lockout && fd.accepted)
      out_.event(EventKind::FixLockout, in.utime, events::FixLockout{refOf(in), f.name(), lockout_after});
  });
  if (!active_took_it) return;  // (the shadows' decisions are on GATE)
  Vec3 moved = fix.pose - prior.x.head<3>();
  moved[2] = wrapAngle(moved[2]);
  out_.event(EventKind::Fix, in.utime, events::Fix{refOf(in), fix.pose, moved, r.condition});
}

}  // namespace lcmloc::core
