#include "lcmloc/core/commands.hpp"

#include "filter_internal.hpp"

namespace lcmloc::core {

using Command = events::Answer::Command;

void Commands::apply(const EngineInput& in, const ControlCommand& c) {
  const InputRef at = refOf(in);
  std::visit([&](const auto& cmd) { apply(at, cmd); }, c);
}

void Commands::answer(bool ack, const InputRef& in, Command what, std::string filter, std::string why,
                      std::string previous) const {
  out_.event(ack ? EventKind::Ack : EventKind::Refused, in.utime,
             events::Answer{in, what, std::move(filter), std::move(previous), std::move(why)});
}

void Commands::apply(const InputRef& in, const SwitchFilter& c) {
  FilterBank::Switched s = bank_.switchTo(c.config, in.utime);
  if (!s.error.empty()) return answer(false, in, Command::Switch, c.config.type, s.error);
  fixes_.forget(FilterBank::key(bank_.active(), true));
  answer(true, in, Command::Switch, bank_.active().name(), s.note, s.previous);
}

void Commands::apply(const InputRef& in, const ResetFilter&) {
  bank_.startAllFresh(in.utime);
  fixes_.reset();
  answer(true, in, Command::Reset, bank_.active().name());
}

void Commands::apply(const InputRef& in, const SetPose& c) {
  // A pose fix for every filter: each moves what depends on the pose with it (odo_ins turns
  // its velocity with the heading). Checked as the variances it gives: a standard deviation
  // of 1e200 squares to infinity, one of 1e-200 to 0.
  PoseFix fix;
  fix.utime = in.utime;
  fix.pose = c.pose;
  fix.cov = c.stddev.array().square().matrix().asDiagonal();
  fix.source = "set_pose";
  if (!(c.stddev.array() > 0).all()) return answer(false, in, Command::SetPose, {}, "stddev must be > 0");
  if (const std::string why = detail::fixProblem(fix); !why.empty())
    return answer(false, in, Command::SetPose, {}, why + " (pose and stddev must be finite, stddev > 0)");
  std::string not_taken;
  bank_.forEach([&](Filter& f, bool is_active) {
    if (!bank_.applyFix(f, is_active, fix)) not_taken += (not_taken.empty() ? "" : ", ") + f.name();
  });
  fixes_.reset();
  if (!not_taken.empty()) return answer(false, in, Command::SetPose, {}, "not taken by " + not_taken);
  answer(true, in, Command::SetPose);
}

}  // namespace lcmloc::core
