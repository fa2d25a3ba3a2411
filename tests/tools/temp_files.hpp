#pragma once
// Scratch files of the tool tests: a fresh directory per test and a file written whole.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

/// An empty directory temp/<prefix><name>_<pid> (removed first if it was there).
inline std::filesystem::path freshTempDir(const std::string& prefix, const std::string& name) {
  const std::filesystem::path d =
      std::filesystem::temp_directory_path() / (prefix + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

inline void writeText(const std::filesystem::path& p, const std::string& text) { std::ofstream(p) << text; }
