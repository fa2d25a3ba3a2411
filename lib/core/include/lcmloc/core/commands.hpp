#pragma once
// Control commands (fusion_control_t): switch the active filter, reset the filters, set the pose.
// Each is answered ("ack" or "refused"), the answer naming the command's channel and seq so that
// a sender tells its own answer from that of another command at the same time.
#include "lcmloc/core/engine_events.hpp"
#include "lcmloc/core/engine_input.hpp"
#include "lcmloc/core/filter_bank.hpp"
#include "lcmloc/core/fix_stage.hpp"

namespace lcmloc::core {

class Commands {
 public:
  Commands(FilterBank& bank, LandmarkFixStage& fixes, const EngineOutputs& out)
      : bank_(bank), fixes_(fixes), out_(out) {}

  /// Applies command c that came as input in, and answers it.
  void apply(const EngineInput& in, const ControlCommand& c);
  /// (Nothing is kept from one command to the next.)
  void reset() {}

 private:
  void apply(const InputRef& in, const SwitchFilter& c);
  void apply(const InputRef& in, const ResetFilter& c);
  void apply(const InputRef& in, const SetPose& c);
  void answer(bool ack, const InputRef& in, events::Answer::Command what, std::string filter = {},
              std::string why = {}, std::string previous = {}) const;

  FilterBank& bank_;
  LandmarkFixStage& fixes_;
  const EngineOutputs& out_;
};

}  // namespace lcmloc::core
