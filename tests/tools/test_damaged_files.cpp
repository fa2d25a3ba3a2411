// Every tool that reads an .lcmlog (lcmloc-log info / to-csv / cut, lcmloc-evaluate,
// lcmloc-replay) on each kind of damaged file: a log cut in the middle of an event, a corrupted
// byte in the middle, an empty file, a file that is not a log, and a file that grows while it is
// read (a logger still writing). Each time what is readable is read, the damage is reported with
// its byte offset, and the exit code is 3 (damaged input).
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/ground_truth_t.hpp"
#include "lcmloc/logio/log_reader.hpp"
#include "lcmloc/odometry_t.hpp"
#include "lcmloc/pose_t.hpp"
#include "run_command.hpp"
#include "test_log_writer.hpp"

namespace fs = std::filesystem;
using namespace lcmloc;

namespace {

constexpr int64_t kT0 = 1700000000000000;
constexpr int kSteps = 200;  // 2 s at 100 Hz

/// A straight run north at 1 m/s: GROUND_TRUTH and ODOMETRY at 100 Hz, POSE at 10 Hz.
testlog::LogLayout writeRun(const std::string& path) {
  testlog::LogWriter w(path);
  for (int k = 0; k < kSteps; ++k) {
    const int64_t t = kT0 + k * 10000;
    ground_truth_t gt{};
    gt.utime = t; gt.seq = k; gt.y = 0.01 * k; gt.heading = M_PI / 2; gt.speed = 1.0; gt.distance = 0.01 * k;
    w.add("GROUND_TRUTH", gt, t);
    if (k > 0) {
      odometry_t od{};
      od.utime = t; od.seq = k - 1; od.delta_s = 0.01; od.ticks = 10; od.has_steering = true;
      w.add("ODOMETRY", od, t);
    }
    if (k % 10 == 5) {
      pose_t p{};
      p.utime = t; p.seq = k / 10; p.filter = "ukf_gated"; p.dim = 3;
      p.state = {0.02, 0.01 * k, M_PI / 2};
      p.state_names = {"x", "y", "theta"};
      p.covariance = {{1e-4, 0, 0}, {0, 1e-4, 0}, {0, 0, 1e-4}};
      w.add("POSE", p, t);
    }
  }
  return w.layout;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// What a damaged file should give: the intact events, and where the damage is said to be.
struct Expected {
  int64_t events = 0, poses = 0;
  int64_t offset = 0;
  std::string says;  ///< a phrase of the damage report
};

/// The tools, run on one file; each checks what it read and that it said where the damage is.
class DamagedFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / ("lcmloc_damaged_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    log_ = (dir_ / "run.lcmlog").string();
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }

  /// Runs every tool on log_ and checks each against e.
  void everyToolSays(const Expected& e) {
    const std::string at = "at byte " + std::to_string(e.offset);
    auto check = [&](const std::string& what, int rc, const std::string& out) {
      EXPECT_EQ(rc, app::kExitInputDamaged) << what << "\n" << out;
      EXPECT_NE(out.find(at), std::string::npos) << what << ": no '" << at << "'\n" << out;
      EXPECT_NE(out.find(e.says), std::string::npos) << what << ": no '" << e.says << "'\n" << out;
    };
    auto [rc, out] = runCommand(LCMLOC_LOG_BIN, "info " + log_, dir_);
    check("info", rc, out);
    EXPECT_NE(out.find("events:     " + std::to_string(e.events) + " on"), std::string::npos) << out;

    std::tie(rc, out) = runCommand(LCMLOC_LOG_BIN, "to-csv " + log_ + " -c POSE -o " + (dir_ / "pose.csv").string(), dir_);
    check("to-csv", rc, out);
    if (e.poses > 0) {
      const std::string csv = slurp(dir_ / "pose.csv");
      EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), e.poses + 1) << "header and one row per intact POSE";
    }

    const std::string cut = (dir_ / "cut.lcmlog").string();
    std::tie(rc, out) = runCommand(LCMLOC_LOG_BIN, "cut " + log_ + " -o " + cut + " --overwrite", dir_);
    check("cut", rc, out);
    if (fs::exists(cut)) {
      const auto s = logio::scanLog(cut, [](const logio::RawEvent&) {});
      EXPECT_EQ(s.events_read, e.events);
      EXPECT_EQ(s.damaged, e.events == 0) << "the cut log holds the intact events, undamaged (none: empty)";
    }

    std::tie(rc, out) = runCommand(LCMLOC_EVALUATE_BIN,
                                   log_ + " --no-plots --overwrite -o " + (dir_ / "eval").string(), dir_);
    check("evaluate", rc, out);
    if (e.poses > 0) {
      const auto j = nlohmann::json::parse(slurp(dir_ / "eval" / "report.json"));
      EXPECT_EQ(j.dump().find("\"events_read\":" + std::to_string(e.events)) != std::string::npos, true) << j.dump(1);
    }

    std::tie(rc, out) = runCommand(LCMLOC_REPLAY_BIN,
                                   log_ + " --overwrite -o " + (dir_ / "replayed.lcmlog").string(), dir_);
    check("replay", rc, out);
    EXPECT_NE(out.find("read " + std::to_string(e.events) + " events"), std::string::npos) << out;
  }

  fs::path dir_;
  std::string log_;
};

int64_t posesBefore(const testlog::LogLayout& w, std::size_t end) {
  return std::count(w.channels.begin(), w.channels.begin() + static_cast<std::ptrdiff_t>(end), "POSE");
}

}  // namespace

TEST_F(DamagedFiles, ALogCutInTheMiddleOfAnEvent) {
  const auto w = writeRun(log_);
  const std::size_t k = w.starts.size() / 2;
  fs::resize_file(log_, static_cast<uintmax_t>(w.starts[k] + 30));  // its header and 2 bytes of its channel
  everyToolSays({static_cast<int64_t>(k), posesBefore(w, k), w.starts[k], "truncated"});
}

TEST_F(DamagedFiles, ACorruptedByteInTheMiddle) {
  const auto w = writeRun(log_);
  const std::size_t k = w.starts.size() / 2;
  {
    std::fstream f(log_, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(w.starts[k] + 1);  // the second byte of the event's sync word
    f.put('\x00');
  }
  const int64_t poses = posesBefore(w, w.starts.size()) - (w.channels[k] == "POSE" ? 1 : 0);
  everyToolSays({static_cast<int64_t>(w.starts.size()) - 1, poses, w.starts[k],
                 "resumed at byte " + std::to_string(w.starts[k + 1])});
}

TEST_F(DamagedFiles, AnEmptyFile) {
  std::ofstream(log_).close();
  everyToolSays({0, 0, 0, "empty file (0 bytes)"});
}

TEST_F(DamagedFiles, AFileThatIsNotALog) {
  {
    std::ofstream f(log_);
    for (int i = 0; i < 50; ++i) f << "t,x,y,heading\n" << i << ",1.0,2.0,0.5\n";
  }
  everyToolSays({0, 0, 0, "no LCM event in the whole file"});
}

// A logger still writing: the file is read up to its size when it was opened. A partial event at
// that end is reported as a truncated tail (and that the file has grown); what was added after
// the opening is not read; the events before are.
TEST(GrowingLog, TheScannerReadsWhatWasCompleteWhenOpenedAndSaysTheFileGrew) {
  const fs::path dir = fs::temp_directory_path() / ("lcmloc_growing_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string full = (dir / "full.lcmlog").string(), growing = (dir / "growing.lcmlog").string();
  const auto w = writeRun(full);
  const std::string bytes = slurp(full);
  const std::size_t k = 100;
  const auto part = static_cast<std::size_t>(w.starts[k] + 20);  // event k half written
  std::ofstream(growing, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(part));

  std::vector<logio::LogIssue> issues;
  logio::LogScanner scanner(growing, &issues);
  {
    std::ofstream f(growing, std::ios::binary | std::ios::app);  // the writer goes on
    f.write(bytes.data() + part, static_cast<std::streamsize>(bytes.size() - part));
  }
  int64_t n = 0;
  while (scanner.next()) ++n;
  EXPECT_EQ(n, static_cast<int64_t>(k));
  EXPECT_TRUE(scanner.damaged());
  ASSERT_EQ(issues.size(), 1u);
  EXPECT_EQ(issues[0].byte_offset, w.starts[k]);
  EXPECT_NE(issues[0].what.find("truncated"), std::string::npos) << issues[0].what;
  EXPECT_NE(issues[0].what.find("has grown to " + std::to_string(bytes.size()) + " bytes"), std::string::npos)
      << issues[0].what;
  // Read again now that it is whole: every event, no damage.
  const auto s = logio::scanLog(growing, [](const logio::RawEvent&) {});
  EXPECT_EQ(s.events_read, static_cast<int64_t>(w.starts.size()));
  EXPECT_FALSE(s.damaged);
  fs::remove_all(dir);
}

// The tools on a file another thread is appending to in chunks that cut events: each run reads
// the events complete when it opened the file; a run that met a partial event says where it
// starts (an event boundary) with exit 3, one that did not exits 0.
TEST_F(DamagedFiles, AFileThatGrowsWhileTheToolsReadIt) {
  const std::string full = (dir_ / "full.lcmlog").string();
  const auto w = writeRun(full);
  const std::string bytes = slurp(full);
  std::ofstream(log_, std::ios::binary).write(bytes.data(), 1000);
  std::atomic<bool> done{false};
  std::thread writer([&] {
    std::ofstream f(log_, std::ios::binary | std::ios::app);
    for (std::size_t at = 1000; at < bytes.size(); at += 777) {
      f.write(bytes.data() + at, static_cast<std::streamsize>(std::min<std::size_t>(777, bytes.size() - at)));
      f.flush();
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    done = true;
  });
  const std::regex events_re("events: +([0-9]+) on"), at_re("DAMAGE in [^ ]+ at byte ([0-9]+) \\(event ([0-9]+)\\)");
  int runs = 0, with_tail = 0;
  while (!done || runs < 2) {
    auto [rc, out] = runCommand(LCMLOC_LOG_BIN, "info " + log_, dir_);
    ++runs;
    std::smatch m;
    ASSERT_TRUE(std::regex_search(out, m, events_re)) << out;
    const auto n = std::stoll(m[1]);
    ASSERT_LE(n, static_cast<long long>(w.starts.size())) << out;
    if (rc == app::kExitInputDamaged) {
      ++with_tail;
      ASSERT_TRUE(std::regex_search(out, m, at_re)) << out;
      EXPECT_EQ(std::stoll(m[1]), w.starts[static_cast<std::size_t>(n)]) << "the partial event starts after the last read";
      EXPECT_EQ(std::stoll(m[2]), n);
      EXPECT_NE(out.find("truncated"), std::string::npos) << out;
    } else {
      ASSERT_EQ(rc, app::kExitOk) << out;
    }
  }
  writer.join();
  auto [rc, out] = runCommand(LCMLOC_LOG_BIN, "info " + log_, dir_);
  EXPECT_EQ(rc, app::kExitOk) << out;  // whole now
  EXPECT_NE(out.find("events:     " + std::to_string(w.starts.size()) + " on"), std::string::npos) << out;
  RecordProperty("runs", runs);
  RecordProperty("runs_with_a_partial_tail", with_tail);
}
