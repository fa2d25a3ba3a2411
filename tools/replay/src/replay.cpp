#include "lcmloc/replay/replay.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <exception>
#include <memory>
#include <thread>

#include <time.h>

#include <lcm/lcm-cpp.hpp>
#include <spdlog/spdlog.h>

#include "daemon/daemon.hpp"
#include "lcmloc/replay/log_bus.hpp"
#include "handoff.hpp"

namespace lcmloc::replay {

bool isDaemonOutput(const app::ChannelConfig& ch, const std::string& c) {
  if (c == ch.pose || c == ch.pose_control || c == ch.gate || c == ch.status) return true;
  // shadow filters: POSE_<TYPE>
  const std::size_t n = ch.pose.size();
  if (c.size() > n + 1 && c[n] == '_' && c.compare(0, n, ch.pose) == 0) return true;
  return false;
}

namespace {

/// A stretch of the input log as the reading side made it, for the applying side: one record
/// per event, in file order, and one at the end (Record::end). What a record stands for, in this
/// order: the damage met before it (`issues` of the block's issues), its copy (--with-inputs),
/// what the daemon's intake made of it (`items` of the block's items, in order).
struct alignas(replay::kLinePair) Block {
  /// position and unreadable are the scanner's, after reading the event (at the end), apart in
  /// the record: side by side, the two would be read from the scanner in one wide load right
  /// after the scanner stored them one by one, a load the CPU cannot forward from its store
  /// buffer (a stall per event; see Reader::addRecord).
  struct Record {
    int64_t position = 0;
    uint32_t items = 0;
    uint16_t issues = 0;
    bool old_output = false, dispatched = false;
    int64_t unreadable = 0;
    bool copy = false;
    bool end = false;  ///< the end of the log: no event
  };
  struct Copy {
    std::size_t at;  ///< channel, then payload, in bytes
    uint32_t channel_len, data_len;
    int64_t timestamp;
  };
  /// A block is handed over once it holds this many records or bytes of copies: a thousand
  /// messages or so, one hand-over (a lock, a wake-up) for all of them.
  static constexpr std::size_t kRecords = 1024, kBytes = std::size_t{1} << 18;

  std::vector<Record> records;
  std::vector<logio::LogIssue> issues;
  std::vector<Copy> copies;
  std::vector<uint8_t> bytes;
  /// The intake's items, items_used of them this time (the rest kept for their storage: the
  /// intake fills a used item in place, strings and all, without allocating).
  std::vector<fusion::IntakeItem> items;
  std::size_t items_used = 0;
  /// Room for a full block from the start (kRecords events and the end, an item each): no vector
  /// grows by moving what it holds to new storage while the first blocks are filled, which would
  /// touch twice the memory, each new page a page fault (microseconds each on a virtual machine).
  Block() {
    records.reserve(kRecords + 1);
    items.reserve(kRecords);
  }
  /// Of the records: old_output ones, dispatched ones (summed as they are made, for the applying
  /// side's counts of a whole block at once).
  int64_t old_outputs = 0, dispatched = 0;
  bool last = false;         ///< nothing after it
  bool interrupted = false;  ///< (with last) ReplayOptions::stop asked
  std::exception_ptr error;  ///< (with last) what stopped the reading side
  void clear() {
    records.clear();
    issues.clear();
    copies.clear();
    bytes.clear();
    items_used = 0;
    old_outputs = dispatched = 0;
    last = interrupted = false;
    error = nullptr;
  }
  bool full() const { return records.size() >= kRecords || bytes.size() >= kBytes; }
  /// The item for the intake to fill next (of the last record).
  fusion::IntakeItem& nextItem() {
    ++records.back().items;
    if (items_used == items.size()) items.emplace_back();
    return items[items_used++];
  }
};

/// The reading side: reads the log and hands each input event to the daemon's subscriptions on
/// the bus; the daemon's intake makes items of them, which it diverts into the block being filled.
class Reader {
 public:
  Reader(const std::string& path, const app::SystemConfig& cfg, const ReplayOptions& opts)
      : scanner_(path, &issues_), cfg_(cfg), opts_(opts) {}
  void attach(LogBus& bus, fusion::FusionDaemon& daemon) {
    bus_ = &bus;
    daemon.divert([this]() -> fusion::IntakeItem& { return block_->nextItem(); });
  }
  int64_t fileSize() const { return scanner_.fileSize(); }

  /// Fills b (cleared) with the next events until it is full; false when the log (or the replay:
  /// ReplayOptions::stop) ended there.
  bool fill(Block& b) {
    block_ = &b;
    while (!b.full()) {
      if ((scanner_.eventsRead() & 255) == 0 && opts_.stop && opts_.stop()) {  // (every 256 events)
        b.interrupted = true;
        return end(b);
      }
      const lcm::LogEvent* ev = scanner_.next();
      if (!ev) return end(b);
      addRecord(b);
      takeIssues(b);
      // Same channel as the event before: that one was not an output either, so it went to the
      // bus, which then need not look the channel up again.
      const bool again = !last_channel_.empty() && ev->channel == last_channel_;
      if (!again) {
        last_channel_ = ev->channel;
        last_is_output_ = isDaemonOutput(cfg_.channels, ev->channel);
      }
      if (last_is_output_) {
        b.records.back().old_output = true;  // the recorded run's estimates: never fed back, never copied
        ++b.old_outputs;
        continue;
      }
      if (opts_.with_inputs && ev->channel != cfg_.channels.heartbeat && ev->channel != "LCM_SELF_TEST") copy(b, *ev);
      const auto size = static_cast<std::size_t>(ev->datalen);
      const bool dispatched = (again ? bus_->dispatchAgain(ev->channel, ev->data, size, ev->timestamp)
                                     : bus_->dispatch(ev->channel, ev->data, size, ev->timestamp)) > 0;
      b.records.back().dispatched = dispatched;
      b.dispatched += dispatched;
    }
    return true;
  }

 private:
  /// The record of the event just read (or of the end), made in place: one made first and then
  /// copied in would be read back whole right after its fields were stored (as Record says).
  void addRecord(Block& b) const {
    Block::Record& r = b.records.emplace_back();
    r.position = scanner_.position();
    r.unreadable = scanner_.bytesUnreadable();
  }
  bool end(Block& b) {
    addRecord(b);
    b.records.back().end = true;
    takeIssues(b);  // (damage at the end of the file)
    b.last = true;
    return false;
  }
  /// The damage the scanner met before the event just read (or before the end), to its record.
  void takeIssues(Block& b) {
    if (issues_.empty()) return;  // (records start with none)
    for (auto& is : issues_) b.issues.push_back(std::move(is));
    b.records.back().issues = static_cast<uint16_t>(issues_.size());  // (one per damaged stretch: a few)
    issues_.clear();
  }
  void copy(Block& b, const lcm::LogEvent& ev) {
    const std::size_t at = b.bytes.size();
    const auto* ch = reinterpret_cast<const uint8_t*>(ev.channel.data());
    const auto* d = static_cast<const uint8_t*>(ev.data);
    b.bytes.insert(b.bytes.end(), ch, ch + ev.channel.size());
    b.bytes.insert(b.bytes.end(), d, d + ev.datalen);
    b.copies.push_back({at, static_cast<uint32_t>(ev.channel.size()), static_cast<uint32_t>(ev.datalen), ev.timestamp});
    b.records.back().copy = true;
  }

  std::vector<logio::LogIssue> issues_;  ///< the scanner's, until taken into a block
  logio::LogScanner scanner_;
  const app::SystemConfig& cfg_;
  const ReplayOptions& opts_;
  LogBus* bus_ = nullptr;
  Block* block_ = nullptr;  ///< being filled
  // Whether the channel is one of the daemon's outputs, kept for the channel of the event before
  // (most events are on the same channel as the one before).
  std::string last_channel_;
  bool last_is_output_ = false;
};

/// The applying side: the daemon's work after its intake, the copies, the damage reports and
/// the counts, record by record, as the events were read.
class Applier {
 public:
  Applier(LogBus& bus, fusion::FusionDaemon& daemon, const ReplayOptions& opts, ReplayResult& r)
      : bus_(bus), daemon_(daemon), opts_(opts), r_(r) {
    next_progress_ = t0_ + period();
  }
  /// Applies b; false when the replay ends with it (the end of the log, or the output failed).
  bool apply(Block& b) {
    if (b.issues.empty() && b.copies.empty()) return applyItems(b);
    std::size_t item = 0, issue = 0, copy = 0;
    for (const Block::Record& rec : b.records) {
      if (!bus_.writeError().empty()) return false;  // the output cannot hold more
      r_.bytes_unreadable = rec.unreadable;
      if (!rec.end) {
        ++r_.events_read;
        position_ = rec.position;
        if (rec.old_output) ++r_.old_outputs;
        if (rec.dispatched) ++r_.dispatched;
        if (opts_.progress_period_s > 0 && (r_.events_read & 1023) == 0) progress();
      }
      for (const std::size_t n = issue + rec.issues; issue < n; ++issue) {
        const logio::LogIssue& is = b.issues[issue];
        spdlog::warn("input log damaged: event {} at byte {}: {}", is.event_index, is.byte_offset, is.what);
        r_.issues.push_back(is);
      }
      if (rec.copy) {
        const Block::Copy& c = b.copies[copy++];
        const auto* p = b.bytes.data() + c.at;
        channel_.assign(reinterpret_cast<const char*>(p), c.channel_len);
        bus_.copy(channel_, p + c.channel_len, c.data_len, c.timestamp);
        ++r_.copied;
      }
      for (const std::size_t n = item + rec.items; item < n; ++item) daemon_.apply(b.items[item]);
    }
    return finish(b);
  }

 private:
  /// apply() of a block without damage or copies (nearly every one): the items record by record
  /// as there, the counts of the records (the same) taken for the whole block at once.
  bool applyItems(Block& b) {
    std::size_t item = 0;
    const std::size_t records = b.records.size();
    for (std::size_t i = 0; i < records; ++i) {
      if (!bus_.writeError().empty()) {  // (rare) the output cannot hold more: the records before i
        countRecords(b, i);
        return false;
      }
      for (const std::size_t n = item + b.records[i].items; item < n; ++item) daemon_.apply(b.items[item]);
    }
    const int64_t events = static_cast<int64_t>(records) - (records > 0 && b.records.back().end ? 1 : 0);
    const int64_t before = r_.events_read;
    r_.events_read += events;
    r_.old_outputs += b.old_outputs;
    r_.dispatched += b.dispatched;
    if (records > 0) r_.bytes_unreadable = b.records.back().unreadable;
    for (std::size_t i = records; i-- > 0;)
      if (!b.records[i].end) {
        position_ = b.records[i].position;
        break;
      }
    // (a progress line where the per-record count would have given one: at a multiple of 1024)
    if (opts_.progress_period_s > 0 && (r_.events_read >> 10) != (before >> 10)) progress();
    return finish(b);
  }
  /// The counts of b's first n records (no damage, no copies in b).
  void countRecords(const Block& b, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) {
      const Block::Record& rec = b.records[i];
      r_.bytes_unreadable = rec.unreadable;
      if (rec.end) continue;
      ++r_.events_read;
      position_ = rec.position;
      if (rec.old_output) ++r_.old_outputs;
      if (rec.dispatched) ++r_.dispatched;
    }
  }
  bool finish(const Block& b) {
    if (b.error) std::rethrow_exception(b.error);
    if (b.interrupted) r_.interrupted = true;
    return !b.last;
  }

  std::chrono::steady_clock::duration period() const {
    return std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(opts_.progress_period_s));
  }
  void progress() {
    using Clock = std::chrono::steady_clock;
    if (Clock::now() < next_progress_) return;
    next_progress_ = Clock::now() + period();
    const double pct = r_.file_size > 0 ? 100.0 * static_cast<double>(position_) / r_.file_size : 100.0;
    const double secs = std::chrono::duration<double>(Clock::now() - t0_).count();
    spdlog::info("{:5.1f} %: {} events read, {} used, {} written ({:.0f} events/s)", pct, r_.events_read,
                 daemon_.processed(), bus_.written(), r_.events_read / std::max(secs, 1e-9));
  }

  LogBus& bus_;
  fusion::FusionDaemon& daemon_;
  const ReplayOptions& opts_;
  ReplayResult& r_;
  const std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point next_progress_;
  int64_t position_ = 0;
  std::string channel_;  ///< of the copy being written
};

/// Blocks in flight between the reading thread and the applying one: the reading side is at
/// most this far ahead. A side that waits for blocks is woken once kBatch are ready for it.
constexpr int kBlocks = 8, kBatch = 4;

/// CPU time of the calling thread [s].
double threadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

/// Adds the calling thread's CPU time from construction to destruction to `sum`.
class CpuTimer {
 public:
  explicit CpuTimer(double& sum) : sum_(sum), t0_(threadCpuSeconds()) {}
  ~CpuTimer() { sum_ += threadCpuSeconds() - t0_; }
  CpuTimer(const CpuTimer&) = delete;
  CpuTimer& operator=(const CpuTimer&) = delete;

 private:
  double& sum_;
  double t0_;
};

/// Reads on a thread of its own while the caller applies: the two sides overlap on two cores.
void replayThreaded(Reader& reader, Applier& applier, ReplayResult& r) {
  Handoff<Block> handoff(kBlocks, kBatch);
  double reading_cpu_s = 0;  // (the thread's own until it ended: r is the applying side's)
  std::thread thread([&] {
    while (Block* b = handoff.acquire()) {
      b->clear();
      bool more = false;
      try {
        const CpuTimer t(reading_cpu_s);
        more = reader.fill(*b);
      } catch (...) {  // (memory running out): the applying side rethrows it after what came before
        b->error = std::current_exception();
        b->last = true;
      }
      handoff.publish(b, !more);
      if (!more) return;
    }
  });
  // The reading thread ends on its own after its last block, or when stopped.
  struct Join {
    Handoff<Block>& h;
    std::thread& t;
    double& reading_cpu_s;
    ReplayResult& r;
    ~Join() {
      h.stop();
      t.join();
      r.reading_cpu_s += reading_cpu_s;
      r.handoff_sleeps = h.sleeps();
    }
  } join{handoff, thread, reading_cpu_s, r};
  while (Block* b = handoff.take()) {
    bool more = false;
    try {
      const CpuTimer t(r.applying_cpu_s);
      more = applier.apply(*b);
    } catch (...) {
      handoff.release(b);
      throw;
    }
    handoff.release(b);
    if (!more) return;
  }
}

/// Both sides in the caller's thread, a block at a time.
void replayInline(Reader& reader, Applier& applier, ReplayResult& r) {
  Block b;
  while (true) {
    b.clear();
    {
      const CpuTimer t(r.reading_cpu_s);
      reader.fill(b);
    }
    const CpuTimer t(r.applying_cpu_s);
    if (!applier.apply(b)) return;
  }
}

}  // namespace

ReplayResult replayLog(const app::SystemConfig& cfg, const ReplayOptions& opts) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  // Each on cache lines of its own (replay::kLinePair): the reader is the reading thread's, the
  // result and the applier the applying thread's, and the bus and the daemon keep their two
  // threads' parts apart inside.
  alignas(replay::kLinePair) ReplayResult r;
  if (!opts.output.empty()) app::refuseOutputOverInputs("--output", opts.output, {opts.input}, "input log");
  alignas(replay::kLinePair) Reader reader(opts.input, cfg, opts);
  r.file_size = reader.fileSize();
  alignas(replay::kLinePair) LogBus bus(opts.output);
  alignas(replay::kLinePair) fusion::FusionDaemon daemon(cfg, bus, fusion::FusionDaemon::Options{false, false, opts.control});
  reader.attach(bus, daemon);
  alignas(replay::kLinePair) Applier applier(bus, daemon, opts, r);
  if (opts.read_ahead)
    replayThreaded(reader, applier, r);
  else
    replayInline(reader, applier, r);
  daemon.shutdown();
  bus.close();
  r.damaged = r.bytes_unreadable > 0 || r.file_size == 0;  // (an empty file: LogScanner::damaged)
  r.messages_in = daemon.messagesIn();
  r.used = daemon.processed();
  r.rejected = daemon.rejected();
  r.gaps = daemon.gaps();
  r.written = bus.written();
  r.write_error = bus.writeError();
  r.written_per_channel = bus.writtenPerChannel();
  r.final_filter = daemon.activeFilter();
  r.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return r;
}

}  // namespace lcmloc::replay
