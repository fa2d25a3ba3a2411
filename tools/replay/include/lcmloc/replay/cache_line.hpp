#pragma once
// Keeping the replay's two threads' data apart in memory (its reading and applying threads).
#include <cstddef>

namespace lcmloc::replay {

/// Two cache lines (the unit an x86 core's adjacent-line prefetcher fetches): data of two threads
/// kept this far apart (alignas(kLinePair)) shares no line, so that neither thread's writes take
/// a line from under the other's reads.
inline constexpr std::size_t kLinePair = 128;

}  // namespace lcmloc::replay
