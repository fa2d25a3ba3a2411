#pragma once
// What the fuzz targets share: a scratch directory per process (on /dev/shm when there is one:
// the readers under test take paths, so each input is written to a file first), quiet logging,
// and the abort that marks a finding.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <streambuf>
#include <string>

#include <spdlog/spdlog.h>

namespace lcmloc::fuzz {

/// A directory of this process's own, removed at exit.
inline const std::filesystem::path& scratchDir() {
  // Never destroyed: the removal at exit runs after the destructors of function-local statics.
  static const std::filesystem::path* const dir = [] {
    namespace fs = std::filesystem;
    const fs::path base = fs::is_directory("/dev/shm") ? fs::path("/dev/shm") : fs::temp_directory_path();
    auto* d = new fs::path(base / ("lcmloc_fuzz_" + std::to_string(::getpid())));
    fs::create_directories(*d);
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(scratchDir(), ec);
    });
    return d;
  }();
  return *dir;
}

/// Writes size bytes to scratchDir()/name (replacing it); returns its path.
inline std::string writeFile(const std::string& name, const uint8_t* data, std::size_t size) {
  const auto path = scratchDir() / name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path.string();
}

/// Empties scratchDir()/name (a directory, made anew).
inline std::string freshDir(const std::string& name) {
  const auto path = scratchDir() / name;
  std::error_code ec;
  std::filesystem::remove_all(path, ec);
  std::filesystem::create_directories(path);
  return path.string();
}

/// Logging off and std::cout discarded (the tools print their reports there).
inline void quiet() {
  static struct Null : std::streambuf {
    int overflow(int c) override { return c == EOF ? 0 : c; }
  } null;
  spdlog::set_level(spdlog::level::off);
  std::cout.rdbuf(&null);
}

/// An input refused with an exception (an expected outcome); said on stderr when the
/// environment has LCMLOC_FUZZ_VERBOSE (to see what a seed reaches).
inline void refused(const std::exception& e) {
  static const bool verbose = std::getenv("LCMLOC_FUZZ_VERBOSE") != nullptr;
  if (verbose) std::fprintf(stderr, "refused: %s\n", e.what());
}

/// A broken invariant: reported and aborted (libFuzzer keeps the input as a crash).
[[noreturn]] inline void finding(const std::string& what) {
  std::fprintf(stderr, "lcmloc fuzz finding: %s\n", what.c_str());
  std::abort();
}

}  // namespace lcmloc::fuzz
