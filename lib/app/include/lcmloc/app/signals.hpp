#pragma once
// SIGINT/SIGTERM -> a stop flag that the programs' loops poll.
#include <atomic>

namespace lcmloc::app {

/// Installs SIGINT/SIGTERM handlers (no SA_RESTART, so a blocking handleTimeout returns early).
void installSignalHandlers();
bool stopRequested();
/// The flag behind stopRequested(), for readers that poll an atomic.
const std::atomic<bool>& stopFlag();
void requestStop();
/// Signal number that requested the stop (0 if none).
int stopSignal();

}  // namespace lcmloc::app
