// Replay goldens: committed sensor logs (tests/data/golden/NAME.lcmlog) replayed with their
// committed configs (NAME.yaml) must give, byte for byte, the output recorded in
// tests/data/golden/expected.txt (a 64-bit FNV-1a digest of the output log plus a readable
// summary: events per channel, GATE decisions by reason, the last pose of every pose channel).
// A change of the fusion's numbers or decisions shows here. When the change is meant, rewrite
// expected.txt with `LCMLOC_UPDATE_GOLDENS=1 build/test-bin/test_golden` and say why in the commit.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <algorithm>
#include <map>

#include <fmt/format.h>
#include <lcm/lcm-cpp.hpp>

#include "lcmloc/logio/log_reader.hpp"
#include "lcmloc/gate_decision_t.hpp"
#include "lcmloc/pose_t.hpp"
#include "lcmloc/replay/replay.hpp"

using namespace lcmloc;
namespace fs = std::filesystem;

namespace {

const fs::path kDir = LCMLOC_GOLDEN_DIR;

/// 64-bit FNV-1a of a file's bytes.
uint64_t digest(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  uint64_t h = 1469598103934665603ull;
  char buf[1 << 16];
  while (in.read(buf, sizeof buf) || in.gcount() > 0) {
    for (std::streamsize i = 0; i < in.gcount(); ++i) {
      h ^= static_cast<unsigned char>(buf[i]);
      h *= 1099511628211ull;
    }
  }
  return h;
}

/// The digest and summary block of one case's output log.
std::string summarize(const std::string& name, const std::string& out) {
  std::map<std::string, int64_t> counts, reasons;
  std::map<std::string, lcmloc::pose_t> last;
  logio::LogScanner scanner(out, nullptr);
  while (const lcm::LogEvent* ev = scanner.next()) {
    ++counts[ev->channel];
    if (ev->channel == "GATE") {
      lcmloc::gate_decision_t d;
      if (d.decode(ev->data, 0, ev->datalen) >= 0)
        ++reasons[d.filter + " " + d.reason + (d.accepted ? " accepted" : " refused")];
    } else if (ev->channel.rfind("POSE", 0) == 0) {
      lcmloc::pose_t p;
      if (p.decode(ev->data, 0, ev->datalen) >= 0) last[ev->channel] = p;
    }
  }
  std::string s = fmt::format("[{}] fnv1a64 {:016x}\n", name, digest(out));
  for (const auto& [ch, n] : counts) s += fmt::format("  events {} {}\n", ch, n);
  for (const auto& [r, n] : reasons) s += fmt::format("  gate {} {}\n", r, n);
  for (const auto& [ch, p] : last) {
    s += fmt::format("  last {} {} utime {} status {}", ch, p.filter, p.utime, p.status);
    for (int i = 0; i < std::min<int>(3, p.dim); ++i) s += fmt::format(" {:.17g}", p.state[i]);
    s += "\n";
  }
  return s;
}

/// Blocks of expected.txt by case name.
std::map<std::string, std::string> readExpected(const fs::path& file) {
  std::map<std::string, std::string> blocks;
  std::ifstream in(file);
  std::string line, name;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (line[0] == '[') name = line.substr(1, line.find(']') - 1);
    blocks[name] += line + "\n";
  }
  return blocks;
}

std::vector<std::string> caseNames() {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(kDir))
    if (e.path().extension() == ".lcmlog") names.push_back(e.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace

TEST(Golden, CommittedLogsReplayToTheRecordedOutputByteForByte) {
  const bool update = std::getenv("LCMLOC_UPDATE_GOLDENS") != nullptr;
  const auto names = caseNames();
  ASSERT_GE(names.size(), 4u) << kDir;
  const auto expected = readExpected(kDir / "expected.txt");
  const fs::path tmp = fs::temp_directory_path() / ("lcmloc_golden_" + std::to_string(::getpid()));
  fs::create_directories(tmp);
  struct RemoveOnExit {
    fs::path p;
    ~RemoveOnExit() { fs::remove_all(p); }
  } cleanup{tmp};
  std::string all =
      "# Replay goldens (tests/replay/test_golden.cpp): for each NAME.lcmlog replayed with NAME.yaml,\n"
      "# the FNV-1a digest of the output log and a summary of it. Rewritten by\n"
      "# LCMLOC_UPDATE_GOLDENS=1 build/test-bin/test_golden\n";
  for (const std::string& name : names) {
    SCOPED_TRACE(name);
    const std::string yaml = (kDir / (name + ".yaml")).string();
    ASSERT_TRUE(fs::exists(yaml)) << "every golden log has its config: " << yaml;
    replay::ReplayOptions o;
    o.input = (kDir / (name + ".lcmlog")).string();
    o.output = (tmp / (name + ".lcmlog")).string();
    o.progress_period_s = 0;
    const replay::ReplayResult r = replay::replayLog(app::loadSystemConfig(yaml), o);
    ASSERT_FALSE(r.damaged);  // (nor is expected.txt rewritten from a damaged log)
    ASSERT_GT(r.written, 0);
    const std::string got = summarize(name, o.output);
    all += got;
    if (update) continue;
    const auto it = expected.find(name);
    ASSERT_NE(it, expected.end()) << "no golden for " << name << " in expected.txt; got:\n" << got;
    EXPECT_EQ(got, it->second) << "the replay of " << name
                               << " changed; if that is meant: LCMLOC_UPDATE_GOLDENS=1 build/test-bin/test_golden";
  }
  if (update) {
    std::ofstream(kDir / "expected.txt") << all;
    std::printf("wrote %s\n", (kDir / "expected.txt").c_str());
  } else {
    EXPECT_EQ(expected.size(), names.size()) << "expected.txt names a case without its log";
  }
}
