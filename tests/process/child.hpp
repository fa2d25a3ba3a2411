#pragma once
// A child process for process tests: fork/exec with stdout+stderr to a file, bounded waits.
// The child leads a process group of its own; on destruction the whole group is killed, so
// what it started and left behind goes too (gpsfake's gpsd, a launcher's processes).
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fcntl.h>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

class Child {
 public:
  Child(const std::string& exe, const std::vector<std::string>& args, const std::string& output_file)
      : output_(output_file) {
    std::vector<std::string> all{exe};
    all.insert(all.end(), args.begin(), args.end());
    pid_ = ::fork();
    if (pid_ == 0) {
      ::setpgid(0, 0);
      const int fd = ::open(output_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      ::dup2(fd, 1);
      ::dup2(fd, 2);
      std::vector<char*> argv;
      for (auto& a : all) argv.push_back(a.data());
      argv.push_back(nullptr);
      ::execv(argv[0], argv.data());
      ::_exit(127);
    }
    if (pid_ > 0) ::setpgid(pid_, pid_);  // also here: whichever runs first
  }
  ~Child() {
    if (pid_ <= 0) return;
    ::kill(-pid_, SIGKILL);  // the group: while any member lives, no other process gets this id
    if (running()) ::waitpid(pid_, nullptr, 0);
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  pid_t pid() const { return pid_; }
  bool running() const { return pid_ > 0 && !status_; }
  void signal(int sig) { if (running()) ::kill(pid_, sig); }

  /// Exit code (or 128 + signal) if the child ends within timeout, else nullopt.
  std::optional<int> wait(std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (!status_) {
      int st = 0;
      if (::waitpid(pid_, &st, WNOHANG) == pid_) {
        status_ = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
        break;
      }
      if (std::chrono::steady_clock::now() >= deadline) return std::nullopt;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return status_;
  }

  std::string output() const {
    std::ifstream in(output_);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }

 private:
  pid_t pid_ = -1;
  std::optional<int> status_;
  std::string output_;
};

/// A udpm:// URL on loopback with a port of its own, shared by every process test so that tests
/// of different files running at the same time do not hear each other: one allocator, 8 ports
/// per test process, 1500 process slots (20000..31999): below the kernel's ephemeral ports
/// (net.ipv4.ip_local_port_range, 32768 up), where another program's socket made LCM's bind fail
/// now and then ("Address already in use").
inline std::string uniqueLcmUrl() {
  static int next = 0;
  const int port = 20000 + (::getpid() % 1500) * 8 + (next++ % 8);
  return "udpm://239.255.76.67:" + std::to_string(port) + "?ttl=0&recv_buf_size=4194304";
}
