#include "lcmloc/eval/evaluate.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <stdexcept>
#include <utility>

#include "lcmloc/core/angles.hpp"

namespace lcmloc::eval {
namespace {

constexpr uint64_t kTruthToleranceUs = 100000;  // accept estimates this close to the truth span

using FaultKey = std::pair<std::string, int64_t>;  // (channel, measurement_seq)

std::set<FaultKey> faultKeys(const std::vector<FaultRecord>& faults) {
  std::set<FaultKey> keys;
  for (const auto& f : faults) keys.emplace(f.channel, f.measurement_seq);
  return keys;
}

TrackPoint score(const std::vector<TruthSample>& truth, int64_t utime, double x, double y,
                 double theta) {
  TrackPoint p;
  p.utime = utime;
  p.x = x;
  p.y = y;
  p.theta = theta;
  if (auto t = truthAt(truth, utime)) {
    p.scored = true;
    p.truth_x = t->x;
    p.truth_y = t->y;
    p.err_x = x - t->x;
    p.err_y = y - t->y;
    p.err = std::hypot(p.err_x, p.err_y);
  }
  return p;
}

/// Fills the error metrics from the track and the decision counts from the decisions.
void computeMetrics(FilterRun& run, const std::vector<FaultRecord>& faults) {
  Metrics& m = run.metrics;
  double sum_sq = 0;
  for (const auto& p : run.track) {
    if (!p.scored) continue;
    ++m.samples;
    sum_sq += p.err * p.err;
    m.max_error_m = std::max(m.max_error_m, p.err);
    m.final_error_m = p.err;
  }
  m.rmse_m = m.samples ? std::sqrt(sum_sq / static_cast<double>(m.samples)) : 0.0;
  m.faults_total = static_cast<int>(faults.size());
  for (const auto& d : run.decisions) {
    const bool ignored = d.decision.reason == "dead_reckoning";
    if (ignored) ++m.ignored;
    else if (d.decision.accepted) ++m.accepted;
    else ++m.rejected;
    if (ignored) continue;
    if (d.is_fault) (d.decision.accepted ? m.faults_accepted : m.faults_rejected)++;
    else if (!d.decision.accepted) ++m.valid_rejected;
  }
}

FilterRun replay(const LogData& data, const EvalSetup& setup, const std::string& type,
                 const std::set<FaultKey>& fault_keys) {
  FilterRun run;
  run.name = type;
  core::EngineConfig cfg = setup.engine;
  cfg.filter = setup.filter;
  cfg.filter.type = type;
  cfg.shadow.clear();
  cfg.output_every = 1;
  cfg.reorder_window_us = setup.reorder_window_us;
  core::EngineOutputs out;
  out.on_state = [&](const std::string&, bool active, const core::FilterState& s) {
    if (active && s.x.size() >= 3) run.track.push_back(score(data.truth, s.utime, s.x[0], s.x[1], s.x[2]));
  };
  out.on_decision = [&](const std::string&, bool active, const core::GateDecision& d) {
    if (active) run.decisions.push_back({d, fault_keys.count({d.sensor, d.measurement_seq}) > 0});
  };
  out.on_event = [&](const core::EngineEvent& e) {
    if (e.kind == core::EventKind::Lockout) ++run.metrics.lockouts;
  };
  core::FusionEngine engine(cfg, setup.map, out);
  for (const auto& in : data.inputs) engine.push(in);
  engine.flush();
  return run;
}

/// The live daemon's poses and decisions (the decisions of the filter the poses name).
LiveRun scoreLive(const LogData& data, const std::set<FaultKey>& fault_keys) {
  LiveRun live;
  live.filter = data.live_poses.back().filter;
  live.run.name = "live:" + live.filter;
  for (const auto& p : data.live_poses) live.run.track.push_back(score(data.truth, p.utime, p.x, p.y, p.theta));
  std::set<std::string> names;
  for (const auto& p : data.live_poses) names.insert(p.filter);
  for (const auto& d : data.live_decisions)
    if (names.count(d.filter))
      live.run.decisions.push_back({d.decision, fault_keys.count({d.decision.sensor, d.decision.measurement_seq}) > 0});
  return live;
}

void compareWithReplay(LiveRun& live, const std::vector<FilterRun>& runs) {
  auto it = std::find_if(runs.begin(), runs.end(), [&](const FilterRun& r) { return r.name == live.filter; });
  if (it == runs.end()) return;
  std::map<int64_t, const TrackPoint*> by_time;
  for (const auto& p : it->track) by_time[p.utime] = &p;  // last estimate at each utime
  std::map<int64_t, const TrackPoint*> live_by_time;
  for (const auto& p : live.run.track) live_by_time[p.utime] = &p;
  double worst = 0;
  for (const auto& [t, p] : live_by_time) {
    auto r = by_time.find(t);
    if (r == by_time.end()) continue;
    ++live.matched_poses;
    worst = std::max(worst, std::hypot(p->x - r->second->x, p->y - r->second->y));
  }
  if (live.matched_poses) live.max_diff_to_replay_m = worst;
}

}  // namespace

std::optional<TruthSample> truthAt(const std::vector<TruthSample>& truth, int64_t utime) {
  if (truth.empty()) return std::nullopt;
  // Distances as utimeSpan: no overflow whatever the utimes.
  if ((utime < truth.front().utime && utimeSpan(utime, truth.front().utime) > kTruthToleranceUs) ||
      (utime > truth.back().utime && utimeSpan(truth.back().utime, utime) > kTruthToleranceUs))
    return std::nullopt;
  auto hi = std::lower_bound(truth.begin(), truth.end(), utime,
                             [](const TruthSample& s, int64_t t) { return s.utime < t; });
  if (hi == truth.end()) return truth.back();
  if (hi->utime == utime || hi == truth.begin()) return *hi;
  const TruthSample& a = *(hi - 1);
  const TruthSample& b = *hi;
  const double w = static_cast<double>(utimeSpan(a.utime, utime)) / static_cast<double>(utimeSpan(a.utime, b.utime));
  TruthSample s;
  s.utime = utime;
  s.x = a.x + w * (b.x - a.x);
  s.y = a.y + w * (b.y - a.y);
  s.heading = core::wrapAngle(a.heading + w * core::wrapAngle(b.heading - a.heading));
  s.distance = a.distance + w * (b.distance - a.distance);
  return s;
}

Evaluation evaluate(const LogData& data, const EvalSetup& setup) {
  const auto known = core::filterTypes();
  for (const auto& f : setup.filters) {
    if (std::find(known.begin(), known.end(), f) == known.end())
      throw std::invalid_argument("unknown filter '" + f + "'");
    // The log reader decodes odometry and ruler detections only: a filter that needs another
    // sensor would be scored on odometry alone, a number that means nothing.
    core::FilterConfig c = setup.filter;
    c.type = f;
    const auto filter = core::makeFilter(c, setup.map);
    for (const auto& [m, what] : {std::pair{core::Measurement::Imu, "IMU samples"},
                                  std::pair{core::Measurement::Gps, "GPS fixes"},
                                  std::pair{core::Measurement::Landmark, "landmark observations"},
                                  std::pair{core::Measurement::Beacon, "beacon ranges"}})
      if (filter->uses(m))
        throw std::invalid_argument(
            "filter '" + f + "' needs " + what +
            ", and this evaluation replays odometry and ruler detections only (filters: dead_reckoning, "
            "ukf, ukf_gated, ukf_calib); replay the log with lcmloc-replay and score the output with "
            "lcmloc-evaluate");
  }

  Evaluation ev;
  ev.gate_threshold = setup.filter.gate.threshold(2);
  if (!data.truth.empty()) ev.t0_utime = data.truth.front().utime;
  else if (!data.inputs.empty()) ev.t0_utime = data.inputs.front().utime;

  const auto keys = faultKeys(data.faults);
  for (const auto& f : setup.filters) {
    ev.filters.push_back(replay(data, setup, f, keys));
    computeMetrics(ev.filters.back(), data.faults);
  }
  if (!data.live_poses.empty()) {
    ev.live = scoreLive(data, keys);
    computeMetrics(ev.live->run, data.faults);
    compareWithReplay(*ev.live, ev.filters);
  }
  for (const auto& f : data.faults) {
    Evaluation::FaultMark mark{f};
    if (auto t = truthAt(data.truth, f.utime)) {  // where the reported marker would lie
      const double l1 = setup.filter.ruler_offset, c = std::cos(t->heading), s = std::sin(t->heading);
      mark.marker_x = t->x + l1 * c - f.lateral_offset * s;
      mark.marker_y = t->y + l1 * s + f.lateral_offset * c;
      mark.located = true;
    }
    ev.faults.push_back(mark);
  }
  return ev;
}

}  // namespace lcmloc::eval
