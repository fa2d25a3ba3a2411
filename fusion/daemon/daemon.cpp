#include "daemon.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>

#include <spdlog/spdlog.h>

#include "lcmloc/bus/convert.hpp"
#include "lcmloc/core/time_guard.hpp"
#include "lcmloc/app/text.hpp"
#include "lcmloc/app/csv.hpp"
#include "lcmloc/fusion_status_t.hpp"

namespace lcmloc::fusion {

namespace {

/// The input an engine event refusing one is about ("" for others).
std::string channelOf(const core::EngineEvent& e) {
  if (const auto* l = std::get_if<core::events::Late>(&e.fields)) return l->input.channel;
  if (const auto* o = std::get_if<core::events::Outlier>(&e.fields)) return o->input.channel;
  if (const auto* c = std::get_if<core::events::CommandAhead>(&e.fields)) return c->input.channel;
  return "";
}

/// FNV-1a over a POSE's utime, filter and state: what tells this daemon's POSE from another's.
uint64_t fingerprint(int64_t utime, const std::string& filter, const double* state, std::size_t n) {
  uint64_t h = 14695981039346656037ull;
  auto add = [&h](const void* p, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) h = (h ^ static_cast<const unsigned char*>(p)[i]) * 1099511628211ull;
  };
  add(&utime, sizeof utime);
  add(filter.data(), filter.size());
  add(state, n * sizeof(double));
  return h;
}
uint64_t fingerprint(const lcmloc::pose_t& m) { return fingerprint(m.utime, m.filter, m.state.data(), m.state.size()); }

std::string upper(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::toupper(c); });
  return s;
}

}  // namespace

FusionDaemon::FusionDaemon(const app::SystemConfig& cfg, bus::MessageBus& bus)
    : FusionDaemon(cfg, bus, Options{}) {}

FusionDaemon::FusionDaemon(const app::SystemConfig& cfg, bus::MessageBus& bus, Options opts)
    : cfg_(cfg), bus_(bus), intake_(cfg), hold_(opts.hold) {
  echo_ = opts.echo;
  timing_ = opts.timing;
  status_period_us_ = static_cast<int64_t>(std::llround(cfg.fusion.status_period * 1e6));
  if (echo_) echoes_.resize(kEchoSeqs);
  core::EngineConfig ec = app::engineConfig(cfg);
  max_jump_us_ = ec.max_time_jump_us;
  core::EngineOutputs out;
  out.on_state = [this](const std::string& f, bool active, const core::FilterState& s) { publishState(f, active, s); };
  if (opts.control) {
    control_out_.channel = cfg.channels.pose_control;
    control_out_.seq = &out_seq_[control_out_.channel];
    out.on_control = [this](const core::FilterState& s) { publishControl(s); };
  }
  out.on_decision = [this](const std::string& f, bool, const core::GateDecision& d) {
    bus_.publish(cfg_.channels.gate, bus::toLcm(d, f, out_seq_[cfg_.channels.gate]++));
    // Every decision is on the GATE channel; a rejection is a debug line (a replay of a real
    // recording rejects thousands), a lock-out an event.
    if (!d.accepted && d.reason == "gate")
      spdlog::debug("{}: {} seq {} rejected by the gate (tau = {:.2f} > {:.3f})", f, app::printable(d.sensor),
                   d.measurement_seq, d.mahalanobis, d.gate);
  };
  out.on_event = [this](const core::EngineEvent& e) {
    event_seen_ = true;
    const std::string detail = core::eventText(e);
    switch (e.kind) {
      case core::EventKind::TooOld:
        ++rejected_;
        if (log_throttle_.allow("too_old")) spdlog::warn("rejected input: {}", app::printable(detail));
        if (rejects_.note(channelOf(e), "too_old")) publishStatus("rejected_input", "too old: " + detail, e.utime);
        return;
      case core::EventKind::TooNew:  // the time-jump guard dropped it (fusion.max_time_jump)
        ++rejected_;
        if (log_throttle_.allow("too_new")) spdlog::warn("rejected input: {}", app::printable(detail));
        if (rejects_.note(channelOf(e), "too_new")) publishStatus("rejected_input", "too new: " + detail, last_utime_);
        return;
      case core::EventKind::OdometryGap:
      case core::EventKind::HorizonFull:
      case core::EventKind::SensorStopped:
      case core::EventKind::Ambiguous:  // the estimate may be off: a warning
        spdlog::warn("{}: {}", core::eventName(e.kind), app::printable(detail));
        break;
      default:
        spdlog::info("{}: {}", core::eventName(e.kind), app::printable(detail));
    }
    publishStatus(core::eventName(e.kind), detail, e.utime);
  };
  core::MarkerMap map;  // from the map file only ("" = no map); the simulator writes its own with lcmloc-sim --write-map
  if (!cfg.fusion.map_file.empty()) {
    try {
      map = app::csv::loadMap(cfg.fusion.map_file);
    } catch (const std::runtime_error& e) {  // a configuration error: the key that names the file
      throw app::ConfigError(cfg.file, "fusion.map_file", e.what());
    }
  }
  const std::size_t markers = map.size();
  engine_ = std::make_unique<core::FusionEngine>(ec, std::move(map), out);  // (the engine's is the one copy)

  const auto& ch = cfg.channels;
  std::vector<std::string> inputs;
  forEachSensorInput([&](const auto& kind) {
    using Lcm = typename std::decay_t<decltype(kind)>::lcm_type;
    for (const std::string& c : kind.channels(ch)) {
      subscribe<Lcm>(c, &DaemonIntake::take<Lcm>);
      inputs.push_back(c);
    }
  });
  subscribe(ch.control, &DaemonIntake::control);
  inputs.push_back(ch.control);

  spdlog::info("filter {} (shadow: {}), {} markers, horizon {:.3f} s; in: {}; out: {}{}, {}, {}{}",
               cfg.fusion.filter.type, cfg.fusion.shadow.empty() ? "none" : fmt::format("{}", fmt::join(cfg.fusion.shadow, ", ")),
               markers, static_cast<double>(engine_->horizonUs()) * 1e-6, fmt::format("{}", fmt::join(inputs, ", ")), ch.pose,
               opts.control ? ", " + ch.pose_control + " (control pose)" : "", ch.gate, ch.status,
               opts.timing ? ", " + ch.timing : "");
  if (!hold_) publishStatus("started", "filter " + engine_->activeFilter(), 0);
}

void FusionDaemon::release(const std::optional<core::FilterState>& init, const std::string& source,
                           bool saw_queued) {
  if (!hold_) return;
  hold_ = false;
  std::string detail = "filter " + engine_->activeFilter();
  int64_t utime = 0;
  if (init) {
    engine_->initialize(*init);
    init_utime_ = init->utime;
    utime = init->utime;
    last_utime_ = init->utime;
    last_status_ = engine_->activeState().status;
    detail += fmt::format(", initialized from {} at utime {} (x {:.3f}, y {:.3f}, theta {:.4f})", source,
                          init->utime, init->x(0), init->x(1), init->x(2));
  } else {
    detail += ", initialized from the configuration (" + source + ")";
  }
  if (held_dropped_ > 0)
    detail += fmt::format("; {} inputs queued while waiting were dropped, the oldest first (more than {} came in)",
                          held_dropped_, kMaxHeld);
  spdlog::info("started: {}", app::printable(detail));
  publishStatus("started", detail, utime);
  auto held = std::move(held_);
  held_.clear();
  releasing_seen_ = saw_queued && init.has_value();
  for (auto& in : held) push(std::move(in));
  releasing_seen_ = false;
}

bool FusionDaemon::checkEcho(const lcmloc::pose_t& m) {
  if (hold_ || !echo_) return false;  // (waiting for the previous daemon's POSE: that one is expected)
  bool foreign = false;
  if (m.seq < 0 || m.seq >= pose_seqs_) {
    foreign = true;  // a seq this daemon has not published (yet)
  } else if (pose_seqs_ - m.seq <= kEchoSeqs) {
    Echo& e = echoes_[static_cast<std::size_t>(m.seq % kEchoSeqs)];
    foreign = e.heard || e.fingerprint != fingerprint(m);
    if (!foreign) e.heard = true;
  }
  if (!foreign) return false;
  ++foreign_outputs_;
  if (log_throttle_.allow("foreign_output")) {
    const std::string detail = fmt::format(
        "another process publishes on {} (seq {}, utime {}, filter {}; this daemon's next seq is {}): a second fusion "
        "daemon on this bus? Its poses interleave with these; stop one ({} so far)",
        cfg_.channels.pose, m.seq, m.utime, m.filter, pose_seqs_, foreign_outputs_);
    spdlog::warn("{}", app::printable(detail));
    publishStatus("foreign_output", detail, last_utime_);
  }
  return true;
}

void FusionDaemon::warn(const std::string& event, const std::string& detail) {
  spdlog::warn("{}", app::printable(detail));
  publishStatus(event, detail, last_utime_);
}

void FusionDaemon::reportSeq(const IntakeItem& item) {
  const bus::SeqGap& gap = item.gap;
  const std::string& ch = item.input.channel;
  gaps_ += gap.missing - gap.uncounted;  // (the tracker's count: a small jump is taken back when it was an outlier)
  if (gap.ignored) {  // a lone corrupt seq: neither a loss nor a restart (and maybe a gap too)
    const std::string what = gap.describeIgnored(ch);
    if (log_throttle_.allow("ignored:" + ch)) spdlog::warn("{}", app::printable(what));
    publishStatus("seq_ignored", what, last_utime_);
  }
  if (gap) {
    const std::string what = gap.describe(ch);
    if (log_throttle_.allow("gap:" + ch)) spdlog::warn("{}", app::printable(what));
    publishStatus("drop", what, last_utime_);
  } else if (gap.restarted) {
    const std::string what = gap.describeRestart(ch);
    if (log_throttle_.allow("restart:" + ch)) spdlog::warn("{}", app::printable(what));
    publishStatus("source_restart", what, last_utime_);
  }
}

void FusionDaemon::reject(const std::string& ch, int64_t seq, int64_t utime, const std::string& why,
                          const std::string& reason) {
  ++rejected_;
  const std::string detail = ch + " seq " + std::to_string(seq) + ": " + why;
  if (log_throttle_.allow("reject:" + ch)) spdlog::warn("rejected input: {}", app::printable(detail));
  if (rejects_.note(ch, reason.empty() ? RejectBook::reasonOf(why) : reason))
    publishStatus("rejected_input", detail, utime > 0 ? utime : last_utime_);
}

void FusionDaemon::decodeError(const std::string& ch, const std::string& why) {
  ++rejected_;
  if (log_throttle_.allow("decode:" + ch)) spdlog::warn("rejected input: {}: {}", app::printable(ch), why);
  if (rejects_.note(ch, "undecodable")) publishStatus("rejected_input", ch + ": " + why, last_utime_);
}

void FusionDaemon::apply(IntakeItem& item) {
  ++messages_in_;
  if (item.seq_event) reportSeq(item);
  if (item.stream.kind == bus::StreamVerdict::Kind::Replaced) {
    const std::string what = item.stream.describe(item.input.channel);
    spdlog::warn("{}", app::printable(what));
    publishStatus("source_replaced", what, last_utime_);
  }
  core::EngineInput& in = item.input;
  switch (item.kind) {
    case IntakeItem::Kind::Input:
      return push(std::move(in));
    case IntakeItem::Kind::Rejected:
      return reject(in.channel, in.seq, in.utime, item.why);
    case IntakeItem::Kind::Refused:
      spdlog::warn("{}", item.note);
      return publishStatus("refused", item.why, in.utime);
    case IntakeItem::Kind::DecodeError:
      return decodeError(in.channel, item.why);
    case IntakeItem::Kind::Nothing:
      return;
    case IntakeItem::Kind::Held:
      return held(item);
  }
}

void FusionDaemon::held(const IntakeItem& item) {
  ++rejected_;
  rejects_.note(item.input.channel, "second_publisher");  // (its status event: the detection)
  if (!item.stream.detected) return;
  const std::string what = item.stream.describe(item.input.channel);
  spdlog::warn("{}", app::printable(what));
  publishStatus("second_publisher", what, last_utime_);
}

void FusionDaemon::checkResumeGap(const core::EngineInput& in) {
  resumed_ = true;
  // A hand-over from a running daemon goes on with the next message (10 ms at 100 Hz); a daemon
  // started again from its checkpoint after a crash has not seen what came in meanwhile.
  if (!core::apartBy(in.utime, *init_utime_, kResumeGapUs)) return;
  const std::string detail = fmt::format(
      "{} seq {}: the first input comes {:.3f} s of message time after the state this daemon started from (utime {}): "
      "the motion in between was not seen (the filters bridge it: odometry_gap)",
      in.channel, in.seq, (static_cast<double>(in.utime) - static_cast<double>(*init_utime_)) * 1e-6, *init_utime_);
  spdlog::warn("{}", app::printable(detail));
  publishStatus("resume_gap", detail, in.utime);
}

void FusionDaemon::push(core::EngineInput&& in) {
  if (hold_) {
    if (held_.size() >= kMaxHeld) {
      held_.pop_front();
      ++held_dropped_;
    }
    held_.push_back(std::move(in));
    return;
  }
  if (init_utime_) {
    if (in.utime <= *init_utime_ &&
        (releasing_seen_ || !(max_jump_us_ > 0 && core::apartBy(*init_utime_, in.utime, max_jump_us_)))) {
      ++covered_;  // already in the state handed over (far older: another time base, taken)
      return;
    }
    if (!resumed_) checkResumeGap(in);
  }
  event_seen_ = false;
  if (!engine_->push(std::move(in)) && !event_seen_)  // refused inputs are left as they were;
    reject(in.channel, in.seq, in.utime, "older than the reorder window", "too_old");  // normally reported by the engine
}

DaemonIntake::DaemonIntake(const app::SystemConfig& cfg) : cfg_(cfg), limits_(cfg.fusion.limits), frame_(cfg.datum) {}

void DaemonIntake::start(IntakeItem& out, IntakeItem::Kind kind, const std::string& ch, int64_t seq, int64_t utime) {
  out.kind = kind;
  out.seq_event = false;
  out.stream = bus::StreamVerdict{};
  out.input.channel = ch;
  out.input.seq = seq;
  out.input.utime = utime;
}

void DaemonIntake::tracked(IntakeItem& out, const std::string& ch, int64_t seq, int64_t utime) {
  start(out, IntakeItem::Kind::Nothing, ch, seq, utime);
  out.stream = streams_.observe(ch, seq, utime);
  if (out.stream.held()) {  // another publisher's: neither for the fusion nor for the gap count
    out.kind = IntakeItem::Kind::Held;
    return;
  }
  if (gaps_.follows(ch, seq)) return;
  const bus::SeqGap gap = gaps_.observe(ch, seq);
  if (gap.missing > 0 || gap.uncounted > 0 || gap.ignored || gap.restarted) {
    out.seq_event = true;
    out.gap = gap;
  }
}

void DaemonIntake::decodeError(const std::string& ch, const std::string& why, IntakeItem& out) {
  start(out, IntakeItem::Kind::DecodeError, ch, 0, 0);
  out.why = why;
}

void DaemonIntake::control(const std::string& ch, const lcmloc::fusion_control_t& m, IntakeItem& out) {
  start(out, IntakeItem::Kind::Rejected, ch, m.seq, m.utime);
  if (m.utime < 0) {
    out.why = "utime is negative";
    return;
  }
  core::ControlCommand cmd;
  switch (m.command) {
    case lcmloc::fusion_control_t::CMD_SWITCH_FILTER: {
      core::FilterConfig fc = cfg_.fusion.filter;
      try {
        YAML::Node params = m.parameters.empty() ? YAML::Node() : YAML::Load(m.parameters);
        if (!m.filter.empty()) params["type"] = m.filter;
        fc = app::parseFilterConfig(params, fc, ch, "parameters");
      } catch (const std::exception& e) {
        out.kind = IntakeItem::Kind::Refused;
        out.note = "refused switch to '" + app::printable(m.filter) + "': " + app::printable(e.what());
        out.why = ch + " seq " + std::to_string(m.seq) + ": switch to '" + m.filter + "': " + e.what();
        return;
      }
      cmd = core::SwitchFilter{fc};
      break;
    }
    case lcmloc::fusion_control_t::CMD_RESET:
      cmd = core::ResetFilter{};
      break;
    case lcmloc::fusion_control_t::CMD_SET_POSE:
      cmd = core::SetPose{core::Pose(m.pose[0], m.pose[1], m.pose[2]),
                          core::Vec3(m.pose_std[0], m.pose_std[1], m.pose_std[2])};
      break;
    default:
      out.why = "unknown command " + std::to_string(m.command);
      return;
  }
  out.kind = IntakeItem::Kind::Input;
  out.input.payload = std::move(cmd);
}

std::string FusionDaemon::poseChannel(const std::string& filter, bool active) const {
  return active ? cfg_.channels.pose : cfg_.channels.pose + "_" + upper(filter);
}

void FusionDaemon::publishState(const std::string& filter, bool active, const core::FilterState& s) {
  PoseOut* po = nullptr;
  for (auto& p : pose_out_)
    if (p.active == active && p.filter == filter) {
      po = &p;
      break;
    }
  if (!po) {
    PoseOut n;
    n.filter = filter;
    n.active = active;
    n.channel = poseChannel(filter, active);
    n.seq = &out_seq_[n.channel];
    pose_out_.push_back(std::move(n));
    po = &pose_out_.back();
  }
  const int64_t seq = (*po->seq)++;
  const std::size_t size = bus::encodePose(s, filter, seq, po->bytes);
  bus_.publishRaw(po->channel, po->bytes.data(), size);
  if (!active) return;
  if (echo_) {
    echoes_[static_cast<std::size_t>(seq % kEchoSeqs)] =
        Echo{fingerprint(s.utime, filter, s.x.data(), static_cast<std::size_t>(s.x.size())), false};
    pose_seqs_ = seq + 1;
  }
  last_utime_ = s.utime;
  last_status_ = s.status;
  const int64_t period = status_period_us_;
  // A time base in the past (fusion.max_time_jump): the schedule starts over.
  if (next_status_utime_ != INT64_MIN && core::apartBy(next_status_utime_, s.utime, 2 * period))
    next_status_utime_ = INT64_MIN;
  if (s.utime >= next_status_utime_) {
    // (the detail: the self-calibration estimates of a filter that has them, then the inputs
    // refused since the last periodic status; empty when neither)
    if (next_status_utime_ != INT64_MIN) {
      std::string detail = core::calibrationSummary(s);
      if (const std::string rejected = rejects_.period(); !rejected.empty())
        detail += (detail.empty() ? "" : "; ") + rejected;
      publishStatus("periodic", detail, s.utime);
    }
    if (__builtin_add_overflow(s.utime, period, &next_status_utime_)) next_status_utime_ = INT64_MAX;
  }
}

void FusionDaemon::publishControl(const core::FilterState& s) {
  PoseOut& po = control_out_;
  po.filter = engine_->activeFilter();
  const std::size_t size = bus::encodePose(s, po.filter, (*po.seq)++, po.bytes);
  bus_.publishRaw(po.channel, po.bytes.data(), size);
}

void FusionDaemon::publishStatus(const std::string& event, const std::string& detail, int64_t utime) {
  lcmloc::fusion_status_t m;
  m.utime = utime;
  m.seq = out_seq_[cfg_.channels.status]++;
  m.filter = engine_->activeFilter();
  m.status = static_cast<int32_t>(last_status_);
  m.event = event;
  m.detail = app::printable(detail);  // names from the bus inside: no control characters on the bus again
  m.messages_in = messages_in_;
  m.messages_used = engine_->counters().processed;
  m.messages_rejected = rejected_;
  m.sequence_gaps = gaps_;
  bus_.publish(cfg_.channels.status, m);
}

void FusionDaemon::shutdown() {
  engine_->flush();
  const auto c = engine_->counters();
  std::string detail = fmt::format(
      "in {}, processed {}, rejected {} (too old {}{}), gaps {}, gate accepted {}, rejected {}", messages_in_,
      c.processed, rejected_, c.too_old, c.too_new ? fmt::format(", too new {}", c.too_new) : "", gaps_,
      c.accepted, c.rejected);
  if (covered_ > 0) detail += fmt::format(", covered by the initial state {}", covered_);
  for (const auto& [ch, l] : engine_->lateInputs())  // (later than the horizon: their lateness, docs/horizon.md)
    detail += fmt::format(", {} later than the {:.3f} s horizon {} (by up to {:.3f} s)", app::printable(ch),
                          static_cast<double>(engine_->horizonUs()) * 1e-6, l.count, static_cast<double>(l.max_lateness_us) * 1e-6);
  if (c.released_early > 0) detail += fmt::format(", released early at fusion.max_queued {}", c.released_early);
  if (const std::string by = rejects_.totals(); !by.empty()) detail += "; rejected by channel and reason: " + by;
  publishStatus("stopped", detail, last_utime_);
  spdlog::info("stopping: {}", detail);
}

app::Heartbeat::Counters FusionDaemon::counters() const {
  const auto c = engine_->counters();
  return {{"in", messages_in_}, {"processed", c.processed}, {"rejected", rejected_},
          {"gaps", gaps_}, {"accepted", c.accepted}, {"gate_rejected", c.rejected}};
}

}  // namespace lcmloc::fusion
