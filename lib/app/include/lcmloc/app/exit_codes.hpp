#pragma once
// The exit codes every lcmloc program shares, and the usage error that exits 2.
#include <stdexcept>

namespace lcmloc::app {

/// Exit codes shared by every executable (runProcess states them in every --help):
///  0 ok; 1 a runtime error; 2 a usage or configuration error: a bad command line, a bad config
///  file, a missing input file, an output that exists without --overwrite; 3 damaged input: a
///  tool that reads an LCM log did its work, but the log was truncated or had corrupt events: it
///  read up to and past the damage and reported each damaged place (the result lacks what was
///  there). A program's own codes (lcmloc-ctl's) come after these.
enum ExitCode : int {
  kExitOk = 0,
  kExitRuntimeError = 1,
  kExitUsageError = 2,
  kExitConfigError = kExitUsageError,
  kExitInputDamaged = 3
};
/// The footer runProcess adds to every program's --help.
extern const char* const kExitCodesHelp;

/// A usage error found after parsing: runProcess exits 2 with its message.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace lcmloc::app
