#pragma once
// Network namespaces for process tests that need several "hosts" or a network set up to fail
// (as root; `ip netns`). A namespace is deleted with its interfaces when the object goes.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

/// The `ip` program, or "" when there is none.
inline std::string ipProgram() {
  for (const char* p : {"/usr/sbin/ip", "/sbin/ip", "/usr/bin/ip", "/bin/ip"})
    if (std::filesystem::exists(p)) return p;
  return "";
}

/// "" when network namespaces can be made here, else why not (the reason a test skips with).
inline std::string netnsUnavailable() {
  if (::geteuid() != 0) return "needs root (ip netns); CI runs it as root";
  if (ipProgram().empty()) return "no `ip` program (iproute2)";
  const std::string probe = "lcmloc_probe_" + std::to_string(::getpid());
  if (std::system((ipProgram() + " netns add " + probe + " 2>/dev/null").c_str()) != 0)
    return "`ip netns add` failed (no network namespaces here)";
  std::system((ipProgram() + " netns del " + probe).c_str());
  return "";
}

class NetNs {
 public:
  /// A namespace of this test process (name unique per pid and tag) with lo up.
  explicit NetNs(const std::string& tag) : name_("lcmloc_" + std::to_string(::getpid()) + "_" + tag) {
    run("netns del " + name_ + " 2>/dev/null");
    ok_ = run("netns add " + name_) && run("-n " + name_ + " link set lo up");
  }
  ~NetNs() { run("netns del " + name_ + " 2>/dev/null"); }
  NetNs(const NetNs&) = delete;
  NetNs& operator=(const NetNs&) = delete;

  bool ok() const { return ok_; }
  const std::string& name() const { return name_; }
  /// `ip -n NAME args` (true when it exits 0).
  bool ip(const std::string& args) const { return run("-n " + name_ + " " + args); }
  /// argv that runs exe with args in the namespace, with LCMLOC_HOST=host when host is given.
  std::vector<std::string> exec(const std::string& exe, const std::vector<std::string>& args,
                                const std::string& host = "") const {
    std::vector<std::string> v{"netns", "exec", name_, "/usr/bin/env"};
    if (!host.empty()) v.push_back("LCMLOC_HOST=" + host);
    v.push_back(exe);
    v.insert(v.end(), args.begin(), args.end());
    return v;
  }
  static bool run(const std::string& args) { return std::system((ipProgram() + " " + args).c_str()) == 0; }

 private:
  std::string name_;
  bool ok_ = false;
};
