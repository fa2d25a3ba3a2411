#include "lcmloc/app/files.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "lcmloc/app/exit_codes.hpp"

namespace lcmloc::app {

std::string configDir() {
  if (const char* env = std::getenv("LCMLOC_CONFIG_DIR"); env && *env) return env;
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return "config";
  // <prefix>/bin/<program> -> <prefix>/share/lcmloc/config (build/share/lcmloc/config in the build tree)
  return (exe.parent_path().parent_path() / "share" / "lcmloc" / "config").string();
}

std::string defaultConfigPath() { return configDir() + "/paper.yaml"; }

std::string fileProblem(const std::string& path, std::uintmax_t max_bytes) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const auto st = fs::status(path, ec);
  if (ec || !fs::exists(st)) return kNoSuchFile;
  if (fs::is_directory(st)) return "is a directory";
  if (!fs::is_regular_file(st)) return "is not a regular file";
  if (fs::file_size(path, ec) > max_bytes) return "larger than " + std::to_string(max_bytes >> 20) + " MB";
  return "";
}

void requireInputFile(const std::string& path, const std::string& what) {
  if (const std::string problem = fileProblem(path); !problem.empty())
    throw UsageError(what + " '" + path + "': " + (problem == kNoSuchFile ? "no such file" : "it " + problem));
}

void refuseExistingOutput(const std::string& path, bool overwrite, const std::string& flag) {
  namespace fs = std::filesystem;
  if (overwrite || path.empty()) return;
  std::error_code ec;
  const auto st = fs::status(path, ec);  // (a link: what it points to)
  if (ec || !fs::exists(st)) return;
  if (fs::is_directory(st)) {
    if (fs::directory_iterator(path, ec) == fs::directory_iterator() && !ec) return;  // empty: nothing to replace
    throw UsageError(flag + " '" + path + "' is a directory that is not empty: give --overwrite to replace the "
                     "files in it, or another " + flag);
  }
  if (!fs::is_regular_file(st)) return;  // a device or a FIFO (/dev/null, /dev/stdout): written to, not replaced
  throw UsageError(flag + " '" + path + "' exists: give --overwrite to replace it, or another " + flag);
}

void prepareOutputDir(const std::string& dir, bool overwrite) {
  namespace fs = std::filesystem;
  refuseExistingOutput(dir, overwrite);
  const fs::path d = dir.empty() ? fs::path(".") : fs::path(dir);
  std::error_code ec;
  fs::create_directories(d, ec);
  if (ec) throw std::runtime_error("output directory '" + dir + "': " + ec.message());
  const fs::path probe = d / (".lcmloc_probe_" + std::to_string(::getpid()));
  std::FILE* f = std::fopen(probe.c_str(), "wb");
  if (!f) throw std::runtime_error("output directory '" + dir + "' is not writable: " + std::strerror(errno));
  std::fclose(f);
  fs::remove(probe, ec);
}

}  // namespace lcmloc::app
