#include "lcmloc/app/signals.hpp"

#include <csignal>

namespace lcmloc::app {

namespace {
std::atomic<bool> g_stop{false};
std::atomic<int> g_signal{0};

extern "C" void onSignal(int sig) {
  g_signal.store(sig);
  g_stop.store(true);
}
}  // namespace

void installSignalHandlers() {
  struct sigaction sa {};
  sa.sa_handler = onSignal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: blocking calls return EINTR so loops see the flag
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  std::signal(SIGPIPE, SIG_IGN);
  // A file-size limit (ulimit -f) makes write(2) fail with EFBIG, which every writer reports,
  // instead of killing the process in the middle of an event.
  std::signal(SIGXFSZ, SIG_IGN);
}

bool stopRequested() { return g_stop.load(); }
const std::atomic<bool>& stopFlag() { return g_stop; }
void requestStop() { g_stop.store(true); }
int stopSignal() { return g_signal.load(); }

}  // namespace lcmloc::app
