// lcmloc-logger as a real process over udpm on loopback: rotation by size and by time, SIGHUP,
// clean shutdown with accounting, the disk-full path (RLIMIT_FSIZE), crash safety (kill -9).
#include <gtest/gtest.h>

#include <sys/mount.h>

#include <filesystem>
#include <fstream>
#include <cstring>
#include <functional>
#include <set>

#include "process_fixture.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/logio/log_reader.hpp"
#include "lcmloc/heartbeat_t.hpp"
#include "lcmloc/logger_status_t.hpp"
#include "lcmloc/odometry_t.hpp"

using namespace std::chrono_literals;
namespace fs = std::filesystem;
using lcmloc::bus::Bus;

namespace {

struct ReadBack {
  lcmloc::logio::ScanSummary scan;
  std::vector<int64_t> seqs;       // ODOMETRY seq, in file order
  std::vector<int64_t> eventnums;
};

ReadBack readBack(const std::string& file) {
  ReadBack r;
  r.scan = lcmloc::logio::scanLog(file, [&](const lcmloc::logio::RawEvent& ev) {
    r.eventnums.push_back(ev.eventnum);
    lcmloc::odometry_t o;
    if (*ev.channel == "ODOMETRY" && o.decode(ev.data, 0, ev.size) >= 0) r.seqs.push_back(o.seq);
  });
  return r;
}

class LoggerTest : public ProcessFixture {
 protected:
  void SetUp() override {
    ProcessFixture::SetUp();
    config_ = path("config.yaml");
    std::ofstream(config_) << "logger: {status_period: 0.05, flush_period: 0.05}\n";
    bus_ = std::make_unique<Bus>(url_);
    bus_->subscribe<lcmloc::logger_status_t>(
        "LOGGER_STATUS", [this](const std::string&, const lcmloc::logger_status_t& m, int64_t) { status_ = m; });
  }

  /// Starts the logger (through prlimit with its options when given).
  std::unique_ptr<Child> start(std::vector<std::string> args, std::vector<std::string> prlimit = {}) {
    std::vector<std::string> all{"--lcm-url", url_, "--config", config_, "--channel", "ODOMETRY"};
    all.insert(all.end(), args.begin(), args.end());
    std::string exe = LCMLOC_LOGGER;
    if (!prlimit.empty()) {
      all.insert(all.begin(), LCMLOC_LOGGER);
      all.insert(all.begin(), "--");
      all.insert(all.begin(), prlimit.begin(), prlimit.end());
      exe = LCMLOC_PRLIMIT;
    }
    auto c = std::make_unique<Child>(exe, all, path("logger.out"));
    // Ready once it publishes its status (it subscribed before).
    EXPECT_TRUE(waitStatus([](const auto&) { return true; }, 10s)) << c->output();
    return c;
  }

  bool waitStatus(const std::function<bool(const lcmloc::logger_status_t&)>& pred, std::chrono::milliseconds t) {
    const auto deadline = std::chrono::steady_clock::now() + t;
    while (std::chrono::steady_clock::now() < deadline) {
      if (status_ && pred(*status_)) return true;
      bus_->handle(20);
    }
    return status_ && pred(*status_);
  }

  void publish(int64_t seq) {
    lcmloc::odometry_t o{};
    o.utime = 1000 * seq;
    o.seq = seq;
    o.delta_s = 0.1;
    ASSERT_TRUE(bus_->publish("ODOMETRY", o));
  }

  /// Log files in the directory, by name.
  std::vector<std::string> logs() const {
    std::vector<std::string> v;
    for (const auto& e : fs::directory_iterator(dir_))
      if (e.path().extension() == ".lcmlog") v.push_back(e.path().string());
    std::sort(v.begin(), v.end());
    return v;
  }

  std::string config_;
  std::unique_ptr<Bus> bus_;
  std::optional<lcmloc::logger_status_t> status_;
};

constexpr int64_t kEventBytes = 28 + 8 + 57;  // header + "ODOMETRY" + odometry_t

}  // namespace

TEST_F(LoggerTest, RotatesBySizeWithoutSplittingOrLosingEvents) {
  auto logger = start({"--output", path("run.lcmlog"), "--max-file-mb", "0.004"});  // 4000 bytes
  for (int i = 0; i < 200; ++i) publish(i);
  ASSERT_TRUE(waitStatus([](const auto& s) { return s.written == 200; }, 10s)) << logger->output();
  logger->signal(SIGTERM);
  ASSERT_EQ(logger->wait(10s), std::optional<int>(0)) << logger->output();

  const auto files = logs();
  const int64_t per_file = 4000 / kEventBytes;  // 43
  ASSERT_EQ(static_cast<int64_t>(files.size()), (200 + per_file - 1) / per_file) << logger->output();
  EXPECT_EQ(files[0], path("run-001.lcmlog"));  // sorted: run-001 .. run-004, run.lcmlog
  std::vector<int64_t> all;
  for (const std::string name : {"run.lcmlog", "run-001.lcmlog", "run-002.lcmlog", "run-003.lcmlog", "run-004.lcmlog"}) {
    ASSERT_TRUE(fs::exists(path(name))) << name;
    EXPECT_LE(fs::file_size(path(name)), 4000u) << name;
    const auto r = readBack(path(name));
    EXPECT_FALSE(r.scan.damaged) << name;
    EXPECT_EQ(r.eventnums.front(), 0) << "each file numbers its events from 0";
    all.insert(all.end(), r.seqs.begin(), r.seqs.end());
  }
  ASSERT_EQ(all.size(), 200u);
  for (int i = 0; i < 200; ++i) EXPECT_EQ(all[static_cast<std::size_t>(i)], i);
}

TEST_F(LoggerTest, RotatesByTime) {
  auto logger = start({"--output", path("t-{index}.lcmlog"), "--max-file-seconds", "0.2"});
  const auto t0 = std::chrono::steady_clock::now();
  int n = 0;
  while (std::chrono::steady_clock::now() - t0 < 1s) {  // paces the publisher, ~10 messages/s
    publish(n++);
    bus_->handle(100);
  }
  ASSERT_TRUE(waitStatus([&](const auto& s) { return s.written == n; }, 10s)) << logger->output();
  logger->signal(SIGINT);
  ASSERT_EQ(logger->wait(10s), std::optional<int>(0)) << logger->output();
  const auto files = logs();
  EXPECT_GE(files.size(), 4u) << logger->output();
  EXPECT_LE(files.size(), 7u) << logger->output();
  int64_t total = 0;
  for (const auto& f : files) {
    const auto r = readBack(f);
    EXPECT_GT(r.seqs.size(), 0u) << f << ": no empty files";
    total += static_cast<int64_t>(r.seqs.size());
  }
  EXPECT_EQ(total, n);
  EXPECT_EQ(files.front(), path("t-000.lcmlog"));
}

TEST_F(LoggerTest, SighupStartsANewFile) {
  auto logger = start({"--output", path("h-{index}.lcmlog")});
  for (int i = 0; i < 5; ++i) publish(i);
  ASSERT_TRUE(waitStatus([](const auto& s) { return s.written == 5; }, 10s)) << logger->output();
  logger->signal(SIGHUP);
  ASSERT_TRUE(waitStatus([](const auto& s) { return s.files == 2; }, 10s)) << logger->output();
  EXPECT_EQ(status_->file, path("h-001.lcmlog"));
  for (int i = 5; i < 12; ++i) publish(i);
  ASSERT_TRUE(waitStatus([](const auto& s) { return s.written == 12; }, 10s)) << logger->output();
  logger->signal(SIGTERM);
  ASSERT_EQ(logger->wait(10s), std::optional<int>(0)) << logger->output();
  EXPECT_EQ(readBack(path("h-000.lcmlog")).seqs, (std::vector<int64_t>{0, 1, 2, 3, 4}));
  EXPECT_EQ(readBack(path("h-001.lcmlog")).seqs, (std::vector<int64_t>{5, 6, 7, 8, 9, 10, 11}));
  EXPECT_NE(logger->output().find("SIGHUP: starting a new file"), std::string::npos);
}

TEST_F(LoggerTest, SighupWithOverwriteAndAPatternWithoutIndexKeepsEveryFile) {
  // With --overwrite and no {index}, every new file of the run took the pattern's name again and
  // truncated the run's own first file (6 of 10 events gone); and every rotation warned about
  // "an earlier recording".
  const std::string log = path("o.lcmlog");
  std::ofstream(log) << "an earlier recording";
  auto logger = start({"--output", log, "--overwrite"});
  for (int i = 0; i < 5; ++i) publish(i);
  ASSERT_TRUE(waitStatus([](const auto& s) { return s.written == 5; }, 10s)) << logger->output();
  logger->signal(SIGHUP);
  ASSERT_TRUE(waitStatus([](const auto& s) { return s.files == 2; }, 10s)) << logger->output();
  for (int i = 5; i < 12; ++i) publish(i);
  ASSERT_TRUE(waitStatus([](const auto& s) { return s.written == 12; }, 10s)) << logger->output();
  logger->signal(SIGTERM);
  ASSERT_EQ(logger->wait(10s), std::optional<int>(0)) << logger->output();
  EXPECT_EQ(readBack(log).seqs, (std::vector<int64_t>{0, 1, 2, 3, 4}));  // the earlier one replaced
  EXPECT_EQ(readBack(path("o-001.lcmlog")).seqs, (std::vector<int64_t>{5, 6, 7, 8, 9, 10, 11}));
  EXPECT_EQ(logger->output().find("earlier recording"), std::string::npos) << logger->output();
}

TEST_F(LoggerTest, ChannelRegexesMatchWholeChannelNames) {
  // Two regexes were joined as (A)|(B), which LCM anchors as ^(A)|(B)$: channels that merely
  // began with A or ended with B were recorded too.
  auto logger = start({"--output", path("c.lcmlog"), "--channel", "GATE"});
  lcmloc::odometry_t o{};
  for (const char* ch : {"ODOMETRY", "ODOMETRY_EXTRA", "GATE", "NOT_A_GATE"}) ASSERT_TRUE(bus_->publish(ch, o));
  ASSERT_TRUE(waitStatus([](const auto& s) { return s.received >= 2; }, 10s)) << logger->output();
  logger->signal(SIGTERM);
  ASSERT_EQ(logger->wait(10s), std::optional<int>(0)) << logger->output();
  std::vector<std::string> channels;
  lcmloc::logio::scanLog(path("c.lcmlog"), [&](const lcmloc::logio::RawEvent& ev) {
    if (*ev.channel != "LOGGER_STATUS" && *ev.channel != "HEARTBEAT") channels.push_back(*ev.channel);
  });
  EXPECT_EQ(channels, (std::vector<std::string>{"ODOMETRY", "GATE"}));
}

TEST_F(LoggerTest, TheLogEndsWithTheLoggersOwnFinalStatusWhenItRecordsThatChannel) {
  // The final LOGGER_STATUS ("stopping", with the final counters) was published and then only
  // one pass over what had arrived was made: it was missing from the log in 1 of 3 runs.
  for (int run = 0; run < 3; ++run) {
    const std::string log = path("s" + std::to_string(run) + ".lcmlog");
    while (bus_->handle(100) > 0) {}  // the last run's statuses
    status_.reset();
    auto logger = start({"--output", log, "--channel", "LOGGER_STATUS"});
    publish(1);
    ASSERT_TRUE(waitStatus([](const auto& s) { return s.written >= 1; }, 10s)) << logger->output();
    logger->signal(SIGTERM);
    ASSERT_EQ(logger->wait(10s), std::optional<int>(0)) << logger->output();
    std::string last_state;
    lcmloc::logio::scanLog(log, [&](const lcmloc::logio::RawEvent& ev) {
      lcmloc::logger_status_t m;
      if (*ev.channel == "LOGGER_STATUS" && m.decode(ev.data, 0, ev.size) >= 0) last_state = m.state;
    });
    EXPECT_EQ(last_state, "stopping") << "run " << run;
  }
}

TEST_F(LoggerTest, CleanShutdownCountsUpstreamGapsApartFromDrops) {
  auto logger = start({"--output", path("run-%Y.lcmlog")});
  for (int64_t seq : {0, 1, 2, 5, 6}) publish(seq);
  ASSERT_TRUE(waitStatus([](const auto& s) { return s.written == 5; }, 10s)) << logger->output();
  EXPECT_EQ(status_->state, "running");
  EXPECT_EQ(status_->gaps, 2);
  EXPECT_EQ(status_->dropped, 0);
  ASSERT_EQ(status_->channels, std::vector<std::string>{"ODOMETRY"});
  EXPECT_EQ(status_->channel_received, std::vector<int64_t>{5});
  EXPECT_EQ(status_->channel_gaps, std::vector<int64_t>{2});
  EXPECT_EQ(status_->channel_dropped, std::vector<int64_t>{0});
  logger->signal(SIGINT);
  ASSERT_EQ(logger->wait(10s), std::optional<int>(0)) << logger->output();
  ASSERT_TRUE(waitStatus([](const auto& s) { return s.state == "stopping"; }, 5s));
  EXPECT_EQ(status_->flushed_events, 5);
  const auto files = logs();
  ASSERT_EQ(files.size(), 1u);
  char year[8];
  const std::time_t now = std::time(nullptr);
  std::strftime(year, sizeof year, "%Y", std::localtime(&now));
  EXPECT_EQ(files[0], path(std::string("run-") + year + ".lcmlog"));
  EXPECT_EQ(readBack(files[0]).seqs, (std::vector<int64_t>{0, 1, 2, 5, 6}));
  const std::string out = logger->output();
  EXPECT_NE(out.find("ODOMETRY                        5 messages, 2 sequence gaps, 0 dropped"), std::string::npos) << out;
  EXPECT_NE(out.find("2 sequence gaps upstream, 0 dropped by the logger, 0 lost to write errors"), std::string::npos) << out;
  // Said at start: the size it got, and the kernel's cap.
  EXPECT_NE(out.find("receive buffer: "), std::string::npos) << out;
  EXPECT_NE(out.find("net.core.rmem_max = "), std::string::npos) << out;
}

// Channel and heartbeat process names are whatever bytes their publisher chose: printed as they
// were, "X\e[2J\e[31mEVIL\a" cleared the screen in a gap warning and in the summary, and a process
// name "p\e]0;pwned\a" set the terminal's title.
TEST_F(LoggerTest, ControlCharactersOfChannelAndProcessNamesNeverReachTheTerminal) {
  auto logger = start({"--output", path("ctl.lcmlog"), "--channel", "X.*", "--channel", "HEARTBEAT"});
  const std::string evil = "X\x1b[2J\x1b[31mEVIL\x07";
  for (int64_t seq : {1, 5}) {
    lcmloc::odometry_t o{};
    o.seq = seq;
    ASSERT_TRUE(bus_->publish(evil, o));
  }
  for (int64_t seq : {0, 7}) {
    lcmloc::heartbeat_t hb{};
    hb.seq = seq;
    hb.process = "p\x1b[2J\x1b]0;pwned\x07";
    hb.state = "running";
    ASSERT_TRUE(bus_->publish("HEARTBEAT", hb));
  }
  ASSERT_TRUE(waitStatus([](const auto& s) { return s.gaps >= 9; }, 10s)) << logger->output();
  logger->signal(SIGTERM);
  ASSERT_EQ(logger->wait(10s), std::optional<int>(0)) << logger->output();
  const std::string out = logger->output();
  EXPECT_EQ(out.find('\x1b'), std::string::npos) << out;
  EXPECT_EQ(out.find('\x07'), std::string::npos) << out;
  EXPECT_NE(out.find("X?[2J?[31mEVIL?: 3 message(s) missing before seq 5"), std::string::npos) << out;
  EXPECT_NE(out.find("HEARTBEAT[p?[2J?]0;pwned?]: 6 message(s) missing before seq 7"), std::string::npos) << out;
  EXPECT_NE(out.find("X?[2J?[31mEVIL?                 2 messages, 3 sequence gaps"), std::string::npos) << out;
  int events = 0;  // recorded as they came
  lcmloc::logio::scanLog(path("ctl.lcmlog"), [&](const lcmloc::logio::RawEvent& ev) { events += *ev.channel == evil; });
  EXPECT_EQ(events, 2);
}

// One corrupt seq counted as up to 2^31 lost messages (bit 30 flipped: 1073741824 "gaps").
TEST_F(LoggerTest, ALoneCorruptSeqIsIgnoredNotCountedAsLostMessages) {
  auto logger = start({"--output", path("seq.lcmlog")});
  for (int64_t seq : {int64_t{0}, int64_t{1}, int64_t{2}, int64_t{3} | (int64_t{1} << 30), int64_t{4}, int64_t{5},
                      int64_t{8}})
    publish(seq);
  ASSERT_TRUE(waitStatus([](const auto& s) { return s.written == 7; }, 10s)) << logger->output();
  EXPECT_EQ(status_->gaps, 2);  // 6 and 7
  EXPECT_EQ(status_->channel_gaps, std::vector<int64_t>{2});
  logger->signal(SIGTERM);
  ASSERT_EQ(logger->wait(10s), std::optional<int>(0)) << logger->output();
  const std::string out = logger->output();
  EXPECT_NE(out.find("ODOMETRY: seq 1073741827 (after 2) ignored: the next message (seq 4) did not go on from it"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("ODOMETRY                        7 messages, 2 sequence gaps, 0 dropped, 1 seq(s) ignored"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("2 sequence gaps upstream"), std::string::npos) << out;
}

// 30,000 channel names grew the logger's memory, a LOGGER_STATUS past 1 MiB (which no lcmloc
// decoder takes) and a summary of 30,005 lines. Statistics are kept for kMaxChannels channels;
// every message is still recorded.
TEST_F(LoggerTest, ThousandsOfChannelsAreAllRecordedButCountedOneByOneOnlyUpToALimit) {
  auto logger = start({"--output", path("many.lcmlog"), "--channel", "C[0-9]+"});
  constexpr int kChannels = 1500;
  for (int i = 0; i < kChannels; ++i) {
    lcmloc::odometry_t o{};
    o.seq = 0;
    char name[16];
    std::snprintf(name, sizeof name, "C%05d", i);
    ASSERT_TRUE(bus_->publish(name, o));
    if (i % 100 == 99) bus_->handle(5);
  }
  ASSERT_TRUE(waitStatus([](const auto& s) { return s.received >= kChannels; }, 20s)) << logger->output();
  EXPECT_EQ(status_->channels.size(), 1001u);  // 1000 channels of their own and the rest together
  int64_t listed = 0;
  for (const auto r : status_->channel_received) listed += r;
  EXPECT_EQ(listed, status_->received);
  ASSERT_FALSE(status_->channels.empty());
  EXPECT_EQ(status_->channels.back(), "(other channels)");
  EXPECT_LT(status_->getEncodedSize(), 100 * 1024);
  logger->signal(SIGTERM);
  ASSERT_EQ(logger->wait(10s), std::optional<int>(0)) << logger->output();
  int events = 0;
  lcmloc::logio::scanLog(path("many.lcmlog"), [&](const lcmloc::logio::RawEvent& ev) { events += (*ev.channel)[0] == 'C'; });
  EXPECT_EQ(events, kChannels);
  const std::string out = logger->output();
  int lines = 0;
  for (std::size_t at = 0; (at = out.find(" messages, ", at)) != std::string::npos; ++at) ++lines;
  EXPECT_LE(lines, 1002) << "one line per channel counted on its own, one for the rest";
  EXPECT_NE(out.find("more than 1000 channels: 'C01000' and every later new channel are counted together"),
            std::string::npos)
      << out.substr(0, 4000);
  EXPECT_NE(out.find("(other channels)"), std::string::npos);
}

TEST_F(LoggerTest, DiskFullExitsNonZeroAndKeepsEveryWholeEventReadable) {
  // RLIMIT_FSIZE of 20000 bytes for the logger (SIGXFSZ is ignored by it): writes fail with EFBIG.
  auto logger = start({"--output", path("full.lcmlog")}, {"--fsize=20000"});
  for (int i = 0; i < 1000 && logger->running(); ++i) {
    publish(i);
    if (i % 100 == 99) bus_->handle(1);
  }
  const auto rc = logger->wait(10s);
  ASSERT_TRUE(rc.has_value()) << "the logger did not stop on a full disk\n" << logger->output();
  EXPECT_EQ(*rc, 1) << logger->output();
  const std::string out = logger->output();
  EXPECT_NE(out.find("file size limit reached (EFBIG)"), std::string::npos) << out;
  EXPECT_NE(out.find("stays readable"), std::string::npos) << out;
  const auto size = static_cast<int64_t>(fs::file_size(path("full.lcmlog")));
  EXPECT_LE(size, 20000);
  EXPECT_EQ(size % kEventBytes, 0) << "whole events only";
  const auto r = readBack(path("full.lcmlog"));
  EXPECT_FALSE(r.scan.damaged);
  ASSERT_EQ(static_cast<int64_t>(r.seqs.size()), size / kEventBytes);
  for (std::size_t i = 0; i < r.seqs.size(); ++i) EXPECT_EQ(r.seqs[i], static_cast<int64_t>(i));
  EXPECT_GE(r.seqs.size(), 200u);  // 20000 / 93 = 215 fit
}

TEST_F(LoggerTest, FullTmpfsIsENOSPCExitsNonZeroAndKeepsEveryWholeEventReadable) {
  const std::string mnt = path("small_disk");
  fs::create_directories(mnt);
  if (::mount("tmpfs", mnt.c_str(), "tmpfs", 0, "size=64k") != 0)
    GTEST_SKIP() << "cannot mount a tmpfs here (needs root): " << std::strerror(errno);
  struct Unmount {
    std::string dir;
    ~Unmount() { ::umount2(dir.c_str(), MNT_DETACH); }
  } unmount{mnt};
  auto logger = start({"--output", mnt + "/full.lcmlog"});
  for (int i = 0; i < 2000 && logger->running(); ++i) {
    publish(i);
    if (i % 100 == 99) bus_->handle(1);
  }
  const auto rc = logger->wait(10s);
  ASSERT_TRUE(rc.has_value()) << "the logger did not stop on a full disk\n" << logger->output();
  EXPECT_EQ(*rc, 1) << logger->output();
  EXPECT_NE(logger->output().find("disk full (ENOSPC)"), std::string::npos) << logger->output();
  const auto size = static_cast<int64_t>(fs::file_size(mnt + "/full.lcmlog"));
  EXPECT_EQ(size % kEventBytes, 0) << "whole events only";
  const auto r = readBack(mnt + "/full.lcmlog");
  EXPECT_FALSE(r.scan.damaged);
  ASSERT_EQ(static_cast<int64_t>(r.seqs.size()), size / kEventBytes);
  EXPECT_GE(r.seqs.size(), 400u);  // most of the 64 KB
  for (std::size_t i = 0; i < r.seqs.size(); ++i) EXPECT_EQ(r.seqs[i], static_cast<int64_t>(i));
}

TEST_F(LoggerTest, KillDashNineKeepsEverythingUpToTheLastFlushReadableByUsAndLcmLogplayer) {
  auto logger = start({"--output", path("crash.lcmlog")});
  for (int i = 0; i < 300; ++i) publish(i);
  ASSERT_TRUE(waitStatus([](const auto& s) { return s.flushed_events == 300; }, 10s)) << logger->output();
  for (int i = 300; i < 400; ++i) publish(i);  // more in flight while it dies
  logger->signal(SIGKILL);
  ASSERT_EQ(logger->wait(5s), std::optional<int>(128 + SIGKILL));

  const auto r = readBack(path("crash.lcmlog"));
  // A SIGKILL that lands inside write(2) can leave part of an event at the end (the kernel stops
  // copying at a page boundary once a fatal signal is pending): that tail, and nothing else, may be
  // unreadable.
  if (r.scan.damaged) {
    ASSERT_EQ(r.scan.issues.size(), 1u);
    EXPECT_NE(r.scan.issues[0].what.find("log ends in a damaged or truncated event"), std::string::npos)
        << r.scan.issues[0].describe();
  }
  ASSERT_GE(r.seqs.size(), 300u);
  for (std::size_t i = 0; i < r.seqs.size(); ++i) ASSERT_EQ(r.seqs[i], static_cast<int64_t>(i));

  // lcm-logplayer plays the file: every event arrives on another port.
  const std::string play_url = uniqueLcmUrl();
  Bus play(play_url);
  std::vector<int64_t> played;
  play.subscribe<lcmloc::odometry_t>("ODOMETRY", [&](const std::string&, const lcmloc::odometry_t& m, int64_t) {
    played.push_back(m.seq);
  });
  Child player(LCMLOC_LCM_LOGPLAYER, {"--lcm-url=" + play_url, "--speed=10", path("crash.lcmlog")}, path("player.out"));
  const auto deadline = std::chrono::steady_clock::now() + 15s;
  while (played.size() < r.seqs.size() && std::chrono::steady_clock::now() < deadline) play.handle(50);
  EXPECT_EQ(played, r.seqs) << player.output();
  EXPECT_EQ(player.wait(10s), std::optional<int>(0)) << player.output();
}

TEST_F(LoggerTest, LcmLoggersLogsAreReadByOurReader) {
  const std::string log = path("lcm.lcmlog");
  Child lcm_logger(LCMLOC_LCM_LOGGER, {"-q", "--lcm-url=" + url_, "-c", "ODOMETRY", log}, path("lcm-logger.out"));
  // lcm-logger says nothing when ready: publish until its file shows the first message.
  int64_t n = 0;
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while ((!fs::exists(log) || fs::file_size(log) == 0) && std::chrono::steady_clock::now() < deadline) {
    publish(n++);
    bus_->handle(50);  // lcm-logger flushes every 100 ms
  }
  ASSERT_GT(fs::file_size(log), 0u) << lcm_logger.output();
  for (int i = 0; i < 20; ++i) publish(n++);
  bus_->handle(300);
  lcm_logger.signal(SIGINT);
  ASSERT_TRUE(lcm_logger.wait(10s).has_value());
  const auto r = readBack(log);
  EXPECT_FALSE(r.scan.damaged);
  ASSERT_GE(r.seqs.size(), 20u);
  for (std::size_t i = 1; i < r.seqs.size(); ++i) EXPECT_EQ(r.seqs[i], r.seqs[i - 1] + 1);
  EXPECT_EQ(r.seqs.back(), n - 1);
}

TEST_F(LoggerTest, BadConfigIsAClearErrorWithExitTwo) {
  std::ofstream(config_) << "logger: {flush_period: -1}\n";
  Child logger(LCMLOC_LOGGER, {"--lcm-url", url_, "--config", config_}, path("logger.out"));
  ASSERT_EQ(logger.wait(10s), std::optional<int>(2)) << logger.output();
  EXPECT_NE(logger.output().find("logger.flush_period"), std::string::npos) << logger.output();
  // A channel regex LCM cannot compile: exit 2 naming it, before any file is made (it was exit 1
  // after the log file had been created).
  std::ofstream(config_) << "logger: {channels: [\"[\"]}\n";
  Child bad_key(LCMLOC_LOGGER, {"--lcm-url", url_, "--config", config_, "-o", path("never.lcmlog")}, path("key.out"));
  ASSERT_EQ(bad_key.wait(10s), std::optional<int>(2)) << bad_key.output();
  EXPECT_NE(bad_key.output().find("logger.channels: bad channel regex"), std::string::npos) << bad_key.output();
  std::ofstream(config_) << "logger: {}\n";
  Child bad_flag(LCMLOC_LOGGER, {"--lcm-url", url_, "--config", config_, "-o", path("never.lcmlog"), "--channel", "(A"},
                 path("flag.out"));
  ASSERT_EQ(bad_flag.wait(10s), std::optional<int>(2)) << bad_flag.output();
  EXPECT_NE(bad_flag.output().find("--channel: bad channel regex"), std::string::npos) << bad_flag.output();
  EXPECT_FALSE(std::filesystem::exists(path("never.lcmlog")));
  // A directory as the output: it wrote DIR-001 beside it, saying DIR was "an earlier recording".
  std::filesystem::create_directories(path("logs"));
  Child dir(LCMLOC_LOGGER, {"--lcm-url", url_, "--config", config_, "-o", path("logs")}, path("dir.out"));
  ASSERT_EQ(dir.wait(10s), std::optional<int>(2)) << dir.output();
  EXPECT_NE(dir.output().find("--output: '" + path("logs") + "' is a directory: give a file name in it"),
            std::string::npos) << dir.output();
  EXPECT_FALSE(std::filesystem::exists(path("logs-001")));
}

namespace {
/// Makes dir unwritable for anyone, root included: moved away (the logger's open file with it)
/// and a regular file put in its place, so a new file in it cannot be created (ENOTDIR).
/// restore() puts it back.
struct BrokenDir {
  std::string dir, moved;
  BrokenDir(std::string d) : dir(std::move(d)), moved(dir + ".moved") {
    fs::rename(dir, moved);
    std::ofstream(dir) << "not a directory";
  }
  void restore() {
    if (moved.empty()) return;
    fs::remove(dir);
    fs::rename(moved, dir);
    moved.clear();
  }
  ~BrokenDir() { restore(); }
};
}  // namespace

// SIGHUP into a directory that had become unwritable stopped the recording ("cannot open log
// file ... stopped recording"): every later message was lost. The logger now goes on recording
// into the file it has, says so (error, LOGGER_STATUS state rotate_failed) and tries again at
// the next SIGHUP.
TEST_F(LoggerTest, SighupIntoAnUnwritableDirectoryKeepsRecordingIntoTheOpenFile) {
  const std::string sub = path("sub");
  fs::create_directories(sub);
  auto logger = start({"--output", sub + "/h-{index}.lcmlog"});
  for (int i = 0; i < 5; ++i) publish(i);
  ASSERT_TRUE(waitStatus([](const auto& s) { return s.written == 5; }, 10s)) << logger->output();
  {
    BrokenDir broken(sub);
    logger->signal(SIGHUP);
    ASSERT_TRUE(waitStatus([](const auto& s) { return s.state == "rotate_failed"; }, 10s)) << logger->output();
    EXPECT_EQ(status_->files, 1);
    for (int i = 5; i < 12; ++i) publish(i);
    ASSERT_TRUE(waitStatus([](const auto& s) { return s.written == 12; }, 10s)) << logger->output();
    EXPECT_TRUE(logger->running());
    broken.restore();
    logger->signal(SIGHUP);  // tried again, now with success
    ASSERT_TRUE(waitStatus([](const auto& s) { return s.files == 2 && s.state == "running"; }, 10s))
        << logger->output();
  }
  for (int i = 12; i < 15; ++i) publish(i);
  ASSERT_TRUE(waitStatus([](const auto& s) { return s.written == 15; }, 10s)) << logger->output();
  logger->signal(SIGTERM);
  ASSERT_EQ(logger->wait(10s), std::optional<int>(0)) << logger->output();
  EXPECT_EQ(readBack(sub + "/h-000.lcmlog").seqs, (std::vector<int64_t>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}));
  EXPECT_EQ(readBack(sub + "/h-001.lcmlog").seqs, (std::vector<int64_t>{12, 13, 14}));
  const std::string out = logger->output();
  EXPECT_NE(out.find("cannot start a new log file: cannot open log file '" + sub + "/h-001.lcmlog'"), std::string::npos)
      << out;
  EXPECT_NE(out.find("still recording into " + sub + "/h-000.lcmlog"), std::string::npos) << out;
  EXPECT_NE(out.find("new log file " + sub + "/h-001.lcmlog (after 1 failed attempt(s) to start one)"),
            std::string::npos)
      << out;
  EXPECT_EQ(out.find("stopped recording"), std::string::npos) << out;
}

// Rotation by size had the same flaw: the file that could not be opened stopped the recording.
// Now the full file takes what comes (larger than asked) until a new one opens, tried again
// every kRotateRetry (1 s); nothing is lost. (Rotation by time goes the same way.)
TEST_F(LoggerTest, SizeRotationIntoAnUnwritableDirectoryKeepsRecordingAndTriesAgain) {
  const std::string sub = path("sub");
  fs::create_directories(sub);
  auto logger = start({"--output", sub + "/s-{index}.lcmlog", "--max-file-mb", "0.001"});  // 1000 bytes: 10 events
  int n = 0;
  for (; n < 10; ++n) publish(n);
  ASSERT_TRUE(waitStatus([&](const auto& s) { return s.written == n; }, 10s)) << logger->output();
  {
    BrokenDir broken(sub);
    for (; n < 30; ++n) publish(n);
    ASSERT_TRUE(waitStatus([&](const auto& s) { return s.written == n && s.state == "rotate_failed"; }, 10s))
        << logger->output();
    EXPECT_EQ(status_->files, 1);
    broken.restore();
    // (the next attempt comes with a message at least 1 s after the last failed one)
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    while (!(status_->files >= 2 && status_->state == "running") && std::chrono::steady_clock::now() < deadline) {
      publish(n++);
      bus_->handle(100);
    }
    ASSERT_GE(status_->files, 2) << logger->output();
  }
  for (int k = 0; k < 10; ++k) publish(n++);
  ASSERT_TRUE(waitStatus([&](const auto& s) { return s.written == n; }, 10s)) << logger->output();
  logger->signal(SIGTERM);
  ASSERT_EQ(logger->wait(10s), std::optional<int>(0)) << logger->output();
  std::vector<int64_t> all;
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(sub)) files.push_back(e.path().string());
  std::sort(files.begin(), files.end());
  ASSERT_GE(files.size(), 3u);
  EXPECT_GE(readBack(files[0]).seqs.size(), 30u) << "the full file took what came while no new one opened";
  for (const auto& f : files) {
    const auto r = readBack(f);
    EXPECT_FALSE(r.scan.damaged) << f;
    all.insert(all.end(), r.seqs.begin(), r.seqs.end());
  }
  ASSERT_EQ(static_cast<int>(all.size()), n) << logger->output();
  for (int i = 0; i < n; ++i) EXPECT_EQ(all[static_cast<std::size_t>(i)], i);
  EXPECT_NE(logger->output().find("attempt(s) to start a new file failed"), std::string::npos) << logger->output();
}
