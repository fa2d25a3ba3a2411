#pragma once
// Programs that run other lcmloc programs and watch them from outside (lcmloc-latency-bench,
// lcmloc-hostile-run): start one with its output to a file, and read a figure of its
// /proc/PID/status. (lcmloc-launcher supervises its children with its own fork/exec: it needs
// a process group and blocked signals across the fork.)
#include <sys/types.h>

#include <cstdint>
#include <string>
#include <vector>

namespace lcmloc::app {

/// Starts args[0] (a path) with args, stdout and stderr to the file output (made or emptied);
/// returns its pid. Throws std::runtime_error naming the program when it cannot be started.
pid_t spawnWithOutput(const std::vector<std::string>& args, const std::string& output);

/// A "Key:  N kB" line of /proc/PID/status (VmRSS, VmHWM, ...) [kB]; 0 when absent or gone.
int64_t procStatusKb(pid_t pid, const std::string& key);

}  // namespace lcmloc::app
