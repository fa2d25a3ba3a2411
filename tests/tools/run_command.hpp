#pragma once
// Runs a program of the project from a test: a shell command line, output captured to a file.
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>

/// Runs `exe args` (args are shell words) with stdout and stderr to dir/out.txt; returns
/// (exit code, -1 for a signal; the output).
inline std::pair<int, std::string> runCommand(const std::string& exe, const std::string& args,
                                              const std::filesystem::path& dir) {
  const std::string cmd = exe + " " + args + " > '" + (dir / "out.txt").string() + "' 2>&1";
  const int st = std::system(cmd.c_str());
  std::ifstream in(dir / "out.txt");
  std::stringstream ss;
  ss << in.rdbuf();
  return {WIFEXITED(st) ? WEXITSTATUS(st) : -1, ss.str()};
}
