#pragma once
// lcmloc-log's subcommands, for its command line (tools/log/main.cpp) and the tests. Each reads
// a truncated or damaged log up to and past the damage, reports every damaged place (a warning
// with its byte offset and event number) and returns the process's exit code:
// app::kExitOk, or app::kExitInputDamaged when the log is damaged (the work is done with
// the intact events). Bad arguments throw app::ConfigError; a failed write,
// std::runtime_error.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace lcmloc::logtool {

/// info: channels, types (by fingerprint), counts, rates, time span, seq gaps, undecodable
/// events, on stdout.
int info(const std::string& path);

/// to-csv: the channels matching one of channel_regexes (none: every channel) decoded to CSV,
/// a header row named after the fields. output "" or "-": stdout (one channel only); a
/// directory: one CHANNEL.csv each.
int toCsv(const std::string& path, const std::vector<std::string>& channel_regexes, const std::string& output);

/// What cut keeps: events on a channel matching one of `channels` (none: all) within the window.
struct CutOptions {
  std::vector<std::string> channels;
  std::optional<double> from, to;                 ///< [s] after the first event
  std::optional<int64_t> from_utime, to_utime;    ///< log times [us]
};

/// cut: the events o keeps into a new log at output.
int cut(const std::string& path, const std::string& output, const CutOptions& o);

}  // namespace lcmloc::logtool
