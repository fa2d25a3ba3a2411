// A child of lcmloc-launcher (see child.hpp).
#include "child.hpp"

#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include <spdlog/fmt/fmt.h>

namespace lcmloc::launcher {

std::string resolveExecutable(const std::string& exe) {
  namespace fs = std::filesystem;
  if (exe.find('/') != std::string::npos) return exe;
  std::error_code ec;
  const auto self = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const auto sibling = self.parent_path() / exe;
    if (fs::exists(sibling)) return sibling.string();
  }
  return exe;  // execvp searches PATH
}

/// Starts the child in a process group of its own. Between fork and exec the child must not run
/// the launcher's signal handler (a SIGTERM would only set a flag in a copy about to be
/// replaced, and be lost): SIGINT/SIGTERM are blocked across fork and set back to their default
/// action in the child before they are unblocked, so such a signal ends the child (a stop).
/// The child gets none of the launcher's file descriptors (LCM sockets and pipes) and the
/// default action for the signals the launcher ignores.
pid_t spawn(const Child& c, const std::string& scenario, const std::string& url, const std::string& run_dir) {
  std::vector<std::string> args{resolveExecutable(c.spec.executable), "--config", scenario, "--lcm-url", url};
  for (auto& a : expandArgs(c.spec.args, run_dir)) args.push_back(std::move(a));
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  sigset_t stop_signals, before;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  ::sigprocmask(SIG_BLOCK, &stop_signals, &before);
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::setpgid(0, 0);                      // Ctrl-C reaches the launcher only: it stops us in order
    for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGPIPE, SIGXFSZ}) ::signal(sig, SIG_DFL);
    ::sigprocmask(SIG_SETMASK, &before, nullptr);
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);   // and we stop if the launcher dies
    if (::getppid() != parent) ::_exit(127);
    ::close_range(3, ~0U, 0);
    ::execvp(argv[0], argv.data());
    std::fprintf(stderr, "lcmloc-launcher: cannot execute %s: %s\n", argv[0], std::strerror(errno));
    ::_exit(127);
  }
  const int fork_errno = errno;
  if (pid > 0) ::setpgid(pid, pid);  // (also here: the group exists before we signal it)
  ::sigprocmask(SIG_SETMASK, &before, nullptr);
  if (pid < 0) throw std::runtime_error("fork failed for " + c.spec.name + ": " + std::strerror(fork_errno));
  return pid;
}

std::vector<std::string> expandArgs(const std::vector<std::string>& args, const std::string& run_dir) {
  std::vector<std::string> out = args;
  const std::string key = "{run_dir}";
  for (auto& a : out)
    for (std::size_t pos = 0; (pos = a.find(key, pos)) != std::string::npos; pos += run_dir.size())
      a.replace(pos, key.size(), run_dir);
  return out;
}

/// Sends sig to the child's process group (the child and what it started), or to the child
/// alone while it has no group yet.
void signalChild(const Child& c, int sig) {
  if (::kill(-c.pid, sig) != 0) ::kill(c.pid, sig);
}

/// SIGCONT, then SIGTERM: a child stopped by SIGSTOP (or a debugger) goes on, handles the
/// SIGTERM and ends in order (the logger closes its file) instead of waiting for the SIGKILL.
/// Never the other way round: a SIGCONT discards every stop signal still pending, and a child
/// that reacted to the SIGTERM before the SIGCONT came could by then be stopping itself on
/// purpose (LeakSanitizer's check at exit attaches with ptrace, whose SIGSTOP the late SIGCONT
/// discarded: the check then waited for a stop that never came, until the SIGKILL).
void terminateChild(const Child& c) {
  signalChild(c, SIGCONT);
  signalChild(c, SIGTERM);
}

/// Ended by the SIGTERM of a stop (before it had set up its own handling of it): stopped.
bool stoppedBySigterm(const Child& c) {
  return c.terminated && !c.killed && WIFSIGNALED(c.status) && WTERMSIG(c.status) == SIGTERM;
}

std::string describeStatus(const Child& c) {
  if (c.running) return "still running";
  const std::string hung = c.hung ? fmt::format("hung, no heartbeat for {:.1f} s; ", c.silent_for) : "";
  if (WIFEXITED(c.status)) return hung + "exit " + std::to_string(WEXITSTATUS(c.status));
  if (stoppedBySigterm(c)) return hung + "stopped by SIGTERM";
  if (WIFSIGNALED(c.status))
    return hung + std::string("killed by ") + strsignal(WTERMSIG(c.status)) + (c.killed ? " (stop timeout)" : "");
  return hung + "unknown";
}

bool failed(const Child& c) {
  if (c.hung) return true;
  if (stoppedBySigterm(c)) return false;
  return c.killed || !WIFEXITED(c.status) || WEXITSTATUS(c.status) != 0;
}

}  // namespace lcmloc::launcher
