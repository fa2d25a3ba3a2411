#pragma once
// Checkpoint of the fusion daemon: the active filter's state (x, P, state names, status, utime)
// as one LCM-encoded pose_t, written atomically (temporary file + rename). A daemon started with
// --checkpoint FILE begins from it, so a restart (another filter, a new build) needs no manual
// re-initialisation.
#include <optional>
#include <string>

#include "lcmloc/core/types.hpp"

namespace lcmloc::fusion {

/// Writes state to path (path.tmp, then rename). Throws std::runtime_error on I/O failure.
void writeCheckpoint(const std::string& path, const core::FilterState& state, const std::string& filter);

/// Why the checkpoint could not be written at path ("" if it can): creates and removes
/// path.tmp, so a missing directory, a read-only file system or missing permissions are found
/// at start-up rather than at the first periodic write.
std::string checkpointUnwritable(const std::string& path);

struct Checkpoint {
  core::FilterState state;
  std::string filter;
};

/// Reads a checkpoint; nullopt when the file does not exist. Throws std::runtime_error (naming
/// the file) when it exists but is not a valid checkpoint.
std::optional<Checkpoint> readCheckpoint(const std::string& path);

}  // namespace lcmloc::fusion
