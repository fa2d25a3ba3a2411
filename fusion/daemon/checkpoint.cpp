#include "checkpoint.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <vector>

#include "lcmloc/bus/convert.hpp"
#include "lcmloc/app/files.hpp"
#include "lcmloc/core/filter.hpp"
#include "lcmloc/pose_t.hpp"

namespace lcmloc::fusion {

void writeCheckpoint(const std::string& path, const core::FilterState& state, const std::string& filter) {
  const lcmloc::pose_t m = bus::toLcm(state, filter, 0);
  std::vector<uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  if (m.encode(buf.data(), 0, static_cast<int>(buf.size())) < 0)
    throw std::runtime_error("checkpoint: cannot encode the state");
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(buf.data()), static_cast<std::streamsize>(buf.size()));
    out.flush();
    if (!out) throw std::runtime_error("checkpoint: cannot write '" + tmp + "'");
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0)
    throw std::runtime_error("checkpoint: cannot rename '" + tmp + "' to '" + path + "'");
}

std::string checkpointUnwritable(const std::string& path) {
  const std::string tmp = path + ".tmp";
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) return "cannot create '" + tmp + "': " + std::strerror(errno);
  std::fclose(f);
  std::remove(tmp.c_str());
  return "";
}

std::optional<Checkpoint> readCheckpoint(const std::string& path) {
  // (a directory, /dev/zero or /dev/full: not a checkpoint, and not to be read to the end)
  if (const std::string problem = app::fileProblem(path, 1u << 20); problem == app::kNoSuchFile)
    return std::nullopt;
  else if (!problem.empty())
    throw std::runtime_error("checkpoint '" + path + "': " + problem + " (a checkpoint is a file of at most 1 MB)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("checkpoint '" + path + "' cannot be read: " + std::strerror(errno));
  const std::vector<char> buf((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  lcmloc::pose_t m;
  bool ok = false;
  try {
    ok = m.decode(buf.data(), 0, static_cast<int>(buf.size())) == static_cast<int>(buf.size());
  } catch (const std::exception&) {
    ok = false;
  }
  if (!ok || m.dim < 3 || static_cast<int>(m.state.size()) != m.dim)
    throw std::runtime_error("checkpoint '" + path + "' is not a valid checkpoint (an encoded pose_t)");
  Checkpoint c;
  c.state = bus::toCore(m);
  c.filter = m.filter;
  if (const std::string why = core::unusableState(c.state); !why.empty())
    throw std::runtime_error("checkpoint '" + path + "' holds a state no filter can start from: " + why);
  return c;
}

}  // namespace lcmloc::fusion
