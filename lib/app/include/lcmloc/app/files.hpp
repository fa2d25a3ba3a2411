#pragma once
// Where a program finds its files and how it checks them: the directory of the shipped
// configuration files, an input that must be a readable file, an output that must not be
// replaced without --overwrite, an output directory that must be writable.
#include <cstdint>
#include <string>

namespace lcmloc::app {

/// The directory of the shipped configuration files: $LCMLOC_CONFIG_DIR when set, else
/// <prefix>/share/lcmloc/config, <prefix> being the directory above the running program's
/// (an installed P/bin/lcmloc-fusion reads P/share/lcmloc/config; in the build tree
/// build/share/lcmloc/config links to the source's config/). No source path is compiled in.
std::string configDir();
/// The default scenario file: configDir()/paper.yaml.
std::string defaultConfigPath();

/// What stops path from being read as a file of at most max_bytes ("" when nothing): it does not
/// exist ("no such file"), "is a directory", "is not a regular file" (a device or a FIFO:
/// /dev/zero would be read until memory runs out) or is "larger than N MB".
std::string fileProblem(const std::string& path, std::uintmax_t max_bytes = UINTMAX_MAX);
inline constexpr const char* kNoSuchFile = "no such file";
/// Throws UsageError (exit 2) naming what ("input log", "--odometry") when path is not a file
/// that can be read (fileProblem): a missing input is a usage error.
void requireInputFile(const std::string& path, const std::string& what);

/// Throws UsageError (exit 2) when path exists (a regular file, or a directory that is not
/// empty) and overwrite is false, naming flag: no program replaces an output without
/// --overwrite. A device or a FIFO (/dev/null) is written to, not replaced: accepted.
void refuseExistingOutput(const std::string& path, bool overwrite, const std::string& flag = "--output");

/// Creates the output directory dir (and its parents) and checks that a file can be written in
/// it: a long experiment finds a bad --output before it computes, not after. Throws
/// std::runtime_error naming dir and the reason. With overwrite false, a directory that exists
/// and is not empty is refused first (refuseExistingOutput).
void prepareOutputDir(const std::string& dir, bool overwrite);

}  // namespace lcmloc::app
