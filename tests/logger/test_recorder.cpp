// The logger's behaviour (logger::Recorder) over the MemoryBus, without sockets: rotation by
// size, by time and on request, drops (counted per channel and reported, never silent), upstream
// sequence gaps told apart from drops, and the log ending with the logger's own last status.
#include <gtest/gtest.h>

#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <thread>

#include <lcm/lcm-cpp.hpp>

#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/bus/memory_bus.hpp"
#include "lcmloc/heartbeat_t.hpp"
#include "lcmloc/logger_status_t.hpp"
#include "lcmloc/odometry_t.hpp"
#include "recorder.hpp"

using namespace lcmloc;
namespace fs = std::filesystem;

namespace {

lcmloc::odometry_t odometry(int64_t seq) {
  lcmloc::odometry_t m{};
  m.utime = 1000000 + seq * 10000;
  m.seq = seq;
  m.delta_s = 0.1;
  return m;
}

struct Event {
  std::string channel;
  std::vector<uint8_t> data;
};

std::vector<Event> readLog(const std::string& path) {
  lcm::LogFile log(path, "r");
  EXPECT_TRUE(log.good()) << path;
  std::vector<Event> out;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    const auto* p = static_cast<const uint8_t*>(ev->data);
    out.push_back({ev->channel, std::vector<uint8_t>(p, p + ev->datalen)});
  }
  return out;
}

/// The ODOMETRY seqs of each file, in order.
std::vector<std::vector<int64_t>> seqsPerFile(const std::vector<std::string>& files) {
  std::vector<std::vector<int64_t>> out;
  for (const auto& f : files) {
    out.emplace_back();
    for (const auto& ev : readLog(f)) {
      lcmloc::odometry_t o;
      if (ev.channel == "ODOMETRY" && o.decode(ev.data.data(), 0, static_cast<int>(ev.data.size())) >= 0)
        out.back().push_back(o.seq);
    }
  }
  return out;
}

using Seqs = std::vector<std::vector<int64_t>>;

class RecorderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("lcmloc_recorder_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    opts_.regex = logger::channelRegex({"ODOMETRY", "BIG"});
    opts_.status_channel = "LOGGER_STATUS";
    opts_.heartbeat_channel = "HEARTBEAT";
    opts_.writer.pattern = (dir_ / "run.lcmlog").string();
    opts_.writer.flush_period = 0.05;
  }
  void TearDown() override { fs::remove_all(dir_); }

  /// The process loop's turns until everything queued on the bus was handled.
  void run(logger::Recorder& rec) {
    while (bus_.queued() > 0) ASSERT_TRUE(rec.step(0));
  }
  void odo(int64_t from, int64_t to) {
    for (int64_t k = from; k <= to; ++k) bus_.inject("ODOMETRY", odometry(k));
  }
  lcmloc::logger_status_t lastStatus() const {
    const auto s = bus_.decoded<lcmloc::logger_status_t>("LOGGER_STATUS");
    EXPECT_FALSE(s.empty());
    return s.empty() ? lcmloc::logger_status_t{} : s.back();
  }
  /// (received, dropped, gaps) of channel in status s; -1s when it is not listed.
  static std::tuple<int64_t, int64_t, int64_t> row(const lcmloc::logger_status_t& s, const std::string& channel) {
    for (int i = 0; i < s.num_channels; ++i)
      if (s.channels[i] == channel) return {s.channel_received[i], s.channel_dropped[i], s.channel_gaps[i]};
    return {-1, -1, -1};
  }

  fs::path dir_;
  logger::RecorderOptions opts_;
  bus::MemoryBus bus_;
};

}  // namespace

TEST_F(RecorderTest, ANewFileStartsBeforeOneWouldExceedMaxFileBytes) {
  const auto event_bytes = static_cast<int64_t>(28 + std::string("ODOMETRY").size() + bus::MemoryBus::encode(odometry(0)).size());
  opts_.writer.max_file_bytes = 3 * event_bytes;  // three events fit, the fourth starts a new file
  logger::Recorder rec(opts_, bus_);
  odo(0, 9);
  run(rec);
  EXPECT_EQ(rec.finish(), app::kExitOk);
  const auto files = rec.files();
  ASSERT_EQ(files.size(), 4u);
  EXPECT_EQ(seqsPerFile(files), (Seqs{{0, 1, 2}, {3, 4, 5}, {6, 7, 8}, {9}}));
  for (const auto& f : files) EXPECT_LE(static_cast<int64_t>(fs::file_size(f)), opts_.writer.max_file_bytes) << f;
  const auto w = rec.writerStats();
  EXPECT_EQ(w.files, 4);
  EXPECT_EQ(w.written, 10);
  EXPECT_EQ(w.dropped, 0);
  EXPECT_EQ(w.file, files.back());
}

TEST_F(RecorderTest, ARequestStartsANewFileAfterWhatCameBefore) {
  logger::Recorder rec(opts_, bus_);  // (no size or time rotation)
  odo(0, 2);
  run(rec);
  rec.requestRotate();  // SIGHUP
  odo(3, 4);
  run(rec);
  EXPECT_EQ(rec.finish(), app::kExitOk);
  EXPECT_EQ(seqsPerFile(rec.files()), (Seqs{{0, 1, 2}, {3, 4}}));
}

TEST_F(RecorderTest, ANewFileStartsAfterMaxFileSeconds) {
  opts_.writer.max_file_seconds = 0.03;
  logger::Recorder rec(opts_, bus_);
  odo(0, 0);  // the first event of a file: never the one that starts a new file
  run(rec);
  // (time passing, not a wait for something: the next event comes after the file's time is up)
  std::this_thread::sleep_for(std::chrono::milliseconds(60));
  odo(1, 1);
  run(rec);
  EXPECT_EQ(rec.finish(), app::kExitOk);
  EXPECT_EQ(seqsPerFile(rec.files()), (Seqs{{0}, {1}}));
}

TEST_F(RecorderTest, AMessageTheQueueCannotTakeIsDroppedCountedAndReported) {
  opts_.writer.queue_bytes = 4096;  // a message larger than this never fits
  logger::Recorder rec(opts_, bus_);
  odo(0, 0);
  lcmloc::heartbeat_t big{};
  big.seq = 0;
  big.process = std::string(8000, 'x');
  bus_.inject("BIG", big);
  odo(1, 1);
  run(rec);
  EXPECT_EQ(rec.finish(), app::kExitOk);

  // The status published at the stop (before the writer finished what was queued: written
  // is the writer's count, below).
  const auto s = lastStatus();
  EXPECT_EQ(s.state, "stopping");
  EXPECT_EQ(s.received, 3);
  EXPECT_EQ(s.dropped, 1);
  EXPECT_EQ(rec.writerStats().written, 2);
  EXPECT_EQ(rec.writerStats().dropped, 1);
  EXPECT_EQ(row(s, "BIG"), std::make_tuple(int64_t{1}, int64_t{1}, int64_t{0}));
  EXPECT_EQ(row(s, "ODOMETRY"), std::make_tuple(int64_t{2}, int64_t{0}, int64_t{0}));
  EXPECT_EQ(s.gaps, 0) << "a drop by the logger is not a gap upstream";
  bool counted = false;
  for (const auto& [name, value] : rec.counters())
    if (name == "dropped") counted = value == 1;
  EXPECT_TRUE(counted) << "the heartbeat's dropped counter";
  EXPECT_EQ(seqsPerFile(rec.files()), (Seqs{{0, 1}}));
  EXPECT_EQ(readLog(rec.files().front()).size(), 2u);
}

TEST_F(RecorderTest, MessagesLostUpstreamAreGapsNotDrops) {
  logger::Recorder rec(opts_, bus_);
  odo(0, 1);
  odo(5, 6);  // 2, 3, 4 never came
  run(rec);
  EXPECT_EQ(rec.finish(), app::kExitOk);
  const auto s = lastStatus();
  EXPECT_EQ(s.gaps, 3);
  EXPECT_EQ(s.dropped, 0);
  EXPECT_EQ(row(s, "ODOMETRY"), std::make_tuple(int64_t{4}, int64_t{0}, int64_t{3}));
  EXPECT_EQ(rec.gaps(), 3);
  EXPECT_EQ(seqsPerFile(rec.files()), (Seqs{{0, 1, 5, 6}}));
}

TEST_F(RecorderTest, TheLogEndsWithTheLoggersOwnLastStatus) {
  opts_.regex = ".*";  // its own status and heartbeat come back and are recorded too
  logger::Recorder rec(opts_, bus_);
  odo(0, 4);
  run(rec);
  EXPECT_EQ(rec.finish(), app::kExitOk);
  const auto events = readLog(rec.files().front());
  ASSERT_GE(events.size(), 8u);  // 5 ODOMETRY, a heartbeat and a status at the start, the last status
  ASSERT_EQ(events.back().channel, "LOGGER_STATUS");
  lcmloc::logger_status_t last;
  ASSERT_GE(last.decode(events.back().data.data(), 0, static_cast<int>(events.back().data.size())), 0);
  EXPECT_EQ(last.state, "stopping");
  EXPECT_EQ(last.seq, lastStatus().seq) << "the one published at the stop";
  lcmloc::heartbeat_t hb;
  const auto& before = events[events.size() - 2];
  ASSERT_EQ(before.channel, "HEARTBEAT");
  ASSERT_GE(hb.decode(before.data.data(), 0, static_cast<int>(before.data.size())), 0);
  EXPECT_EQ(hb.state, "stopping");
  EXPECT_EQ(hb.process, "lcmloc-logger");
}
