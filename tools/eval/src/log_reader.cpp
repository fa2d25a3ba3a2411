#include "lcmloc/eval/log_reader.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <set>
#include <sstream>
#include <stdexcept>

#include <lcm/lcm-cpp.hpp>

#include "lcmloc/common/convert.hpp"
#include "lcmloc/fault_event_t.hpp"
#include "lcmloc/gate_decision_t.hpp"
#include "lcmloc/ground_truth_t.hpp"
#include "lcmloc/magruler_t.hpp"
#include "lcmloc/odometry_t.hpp"
#include "lcmloc/pose_t.hpp"

namespace lcmloc::eval {
namespace {

constexpr int64_t kEventHeaderBytes = 28;  // sync, event number, utime, channel len, data len

int64_t fileSize(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return -1;
  return static_cast<int64_t>(st.st_size);
}

/// Decodes one payload; records an issue and returns false when it does not decode.
template <typename T>
bool decode(const lcm::LogEvent& ev, T& msg, LogData& out, int64_t offset) {
  if (msg.decode(ev.data, 0, ev.datalen) >= 0) return true;
  out.issues.push_back({out.events_read - 1, offset,
                        "undecodable " + ev.channel + " message (" + std::to_string(ev.datalen) +
                            " bytes, not a " + T::getTypeName() + ")"});
  return false;
}

class Decoder {
 public:
  Decoder(const common::ChannelConfig& ch, LogData& out)
      : ch_(ch), ruler_(ch.magruler.begin(), ch.magruler.end()), out_(out) {}

  void handle(const lcm::LogEvent& ev, int64_t offset) {
    const std::string& c = ev.channel;
    if (c == ch_.ground_truth) truth(ev, offset);
    else if (c == ch_.odometry) odometry(ev, offset);
    else if (ruler_.count(c)) ruler(ev, offset);
    else if (c == ch_.fault_events) fault(ev, offset);
    else if (c == ch_.pose) pose(ev, offset);
    else if (c == ch_.gate) gate(ev, offset);
  }

 private:
  void invalid(int64_t offset, const std::string& what) {
    out_.issues.push_back({out_.events_read - 1, offset, what});
  }
  void truth(const lcm::LogEvent& ev, int64_t offset) {
    lcmloc::ground_truth_t m{};
    if (!decode(ev, m, out_, offset)) return;
    out_.truth.push_back({m.utime, m.x, m.y, m.heading, m.distance});
  }
  void odometry(const lcm::LogEvent& ev, int64_t offset) {
    lcmloc::odometry_t m{};
    if (!decode(ev, m, out_, offset)) return;
    ++out_.odometry_messages;
    std::string why;
    auto in = common::toCore(m, &why);
    if (!in) return invalid(offset, "invalid " + ev.channel + " seq " + std::to_string(m.seq) + ": " + why);
    out_.inputs.push_back({ev.channel, m.seq, m.utime, *in});
  }
  void ruler(const lcm::LogEvent& ev, int64_t offset) {
    lcmloc::magruler_t m{};
    if (!decode(ev, m, out_, offset)) return;
    ++out_.ruler_messages;
    std::string why;
    auto det = common::toCore(m, ev.channel, &why);
    if (!det) {
      if (!why.empty())
        invalid(offset, "invalid " + ev.channel + " seq " + std::to_string(m.seq) + ": " + why);
      return;
    }
    ++out_.ruler_detections;
    out_.inputs.push_back({ev.channel, m.seq, m.utime, *det});
  }
  void fault(const lcm::LogEvent& ev, int64_t offset) {
    lcmloc::fault_event_t m{};
    if (!decode(ev, m, out_, offset)) return;
    out_.faults.push_back({m.utime, m.kind, m.channel, m.measurement_seq, m.x, m.y, m.lateral_offset});
  }
  void pose(const lcm::LogEvent& ev, int64_t offset) {
    lcmloc::pose_t m{};
    if (!decode(ev, m, out_, offset)) return;
    if (m.dim < 3 || static_cast<int>(m.state.size()) < 3)
      return invalid(offset, "pose with fewer than 3 states");
    out_.live_poses.push_back({m.utime, m.filter, m.state[0], m.state[1], m.state[2], m.status});
  }
  void gate(const lcm::LogEvent& ev, int64_t offset) {
    lcmloc::gate_decision_t m{};
    if (!decode(ev, m, out_, offset)) return;
    core::GateDecision d;
    d.utime = m.utime;
    d.sensor = m.sensor;
    d.measurement_seq = m.measurement_seq;
    d.innovation = Eigen::Map<const Eigen::VectorXd>(m.innovation.data(),
                                                     static_cast<Eigen::Index>(m.innovation.size()));
    d.mahalanobis = m.mahalanobis;
    d.gate = m.gate;
    d.accepted = m.accepted;
    d.marker_id = m.marker_id;
    d.reason = m.reason;
    out_.live_decisions.push_back({m.filter, d});
  }

  const common::ChannelConfig& ch_;
  std::set<std::string> ruler_;
  LogData& out_;
};

/// Tracks a damaged stretch of the file from the first failed read to the next intact event.
struct Damage {
  bool open = false;
  int64_t event_index = 0, start = 0;
};

/// Offset of the next sync word at or after from, or -1 when there is none.
int64_t findSync(FILE* f, int64_t from) {
  static const unsigned char kSync[4] = {0xED, 0xA1, 0xDA, 0x01};
  if (fseeko(f, from, SEEK_SET) != 0) return -1;
  std::vector<unsigned char> buf(1 << 16);
  int64_t base = from;
  size_t keep = 0;  // bytes carried over from the previous chunk
  while (true) {
    const size_t n = fread(buf.data() + keep, 1, buf.size() - keep, f);
    if (n == 0) return -1;
    const size_t len = keep + n;
    for (size_t i = 0; i + 4 <= len; ++i)
      if (std::equal(kSync, kSync + 4, buf.begin() + static_cast<std::ptrdiff_t>(i)))
        return base + static_cast<int64_t>(i);
    keep = std::min<size_t>(3, len);
    std::copy(buf.begin() + static_cast<std::ptrdiff_t>(len - keep),
              buf.begin() + static_cast<std::ptrdiff_t>(len), buf.begin());
    base += static_cast<int64_t>(len - keep);
  }
}

void closeDamage(Damage& dmg, int64_t resume_at, ScanSummary& out) {
  if (!dmg.open) return;
  const int64_t skipped = resume_at - dmg.start;
  out.bytes_unreadable += skipped;
  std::ostringstream s;
  if (resume_at >= out.file_size)
    s << "log ends in a damaged or truncated event: the last " << skipped << " bytes from byte "
      << dmg.start << " could not be read (" << out.events_read << " events read before)";
  else
    s << "damaged event at byte " << dmg.start << ": skipped " << skipped
      << " bytes, resumed at byte " << resume_at;
  out.issues.push_back({dmg.event_index, dmg.start, s.str()});
  dmg.open = false;
}

}  // namespace

ScanSummary scanLog(const std::string& path, const std::function<void(const RawEvent&)>& on_event,
                    const std::atomic<bool>* stop) {
  // Parsed here rather than with lcm::LogFile: LCM 1.3.1's reader also rejects an intact event
  // when the sync word after it is damaged, and cannot say where an event starts.
  ScanSummary out;
  out.file_size = fileSize(path);
  if (out.file_size < 0) throw std::runtime_error("cannot open log '" + path + "': no such file");
  std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) throw std::runtime_error("cannot open log '" + path + "' for reading");
  FILE* f = file.get();
  std::vector<char> iobuf(1 << 20);
  std::setvbuf(f, iobuf.data(), _IOFBF, iobuf.size());
  Damage dmg;
  std::string channel;
  std::vector<uint8_t> data;
  int64_t pos = 0;
  auto be = [](const unsigned char* p, int n) {
    uint64_t v = 0;
    for (int i = 0; i < n; ++i) v = (v << 8) | p[i];
    return v;
  };

  while (pos < out.file_size && !(stop && stop->load())) {
    unsigned char h[kEventHeaderBytes];
    bool ok = fseeko(f, pos, SEEK_SET) == 0 && std::fread(h, 1, sizeof h, f) == sizeof h &&
              be(h, 4) == 0xEDA1DA01u;
    int64_t channel_len = 0, data_len = 0;
    if (ok) {
      channel_len = static_cast<int64_t>(be(h + 20, 4));
      data_len = static_cast<int64_t>(be(h + 24, 4));
      ok = channel_len > 0 && channel_len < 1000 && data_len < (int64_t{1} << 31) &&
           pos + kEventHeaderBytes + channel_len + data_len <= out.file_size;
    }
    if (ok) {
      channel.resize(static_cast<std::size_t>(channel_len));
      data.resize(static_cast<std::size_t>(data_len));
      ok = std::fread(channel.data(), 1, channel.size(), f) == channel.size() &&
           (data.empty() || std::fread(data.data(), 1, data.size(), f) == data.size());
    }
    if (!ok) {
      if (!dmg.open) dmg = {true, out.events_read, pos};
      const int64_t next = findSync(f, pos + 1);  // resynchronise on the next sync word
      if (next < 0) {
        closeDamage(dmg, out.file_size, out);
        break;
      }
      pos = next;
      continue;
    }
    closeDamage(dmg, pos, out);
    RawEvent raw;
    raw.index = out.events_read++;
    raw.offset = pos;
    raw.eventnum = static_cast<int64_t>(be(h + 4, 8));
    raw.utime = static_cast<int64_t>(be(h + 12, 8));
    raw.channel = &channel;
    raw.data = data.data();
    raw.size = static_cast<int32_t>(data_len);
    on_event(raw);
    pos += kEventHeaderBytes + channel_len + data_len;
  }
  if (stop && stop->load()) out.interrupted = true;
  out.damaged = out.bytes_unreadable > 0;
  return out;
}

LogData readLog(const std::string& path, const common::ChannelConfig& channels,
                const std::atomic<bool>* stop) {
  LogData out;
  out.path = path;
  Decoder decoder(channels, out);
  const ScanSummary scan = scanLog(path, [&](const RawEvent& raw) {
    out.events_read = raw.index + 1;
    ++out.channel_counts[*raw.channel];
    lcm::LogEvent ev;
    ev.eventnum = raw.eventnum;
    ev.timestamp = raw.utime;
    ev.channel = *raw.channel;
    ev.datalen = raw.size;
    ev.data = const_cast<uint8_t*>(raw.data);
    decoder.handle(ev, raw.offset);
  }, stop);
  out.file_size = scan.file_size;
  out.events_read = scan.events_read;
  out.bytes_unreadable = scan.bytes_unreadable;
  out.damaged = scan.damaged;
  out.interrupted = scan.interrupted;
  // Damage and bad messages in file order.
  out.issues.insert(out.issues.end(), scan.issues.begin(), scan.issues.end());
  std::stable_sort(out.issues.begin(), out.issues.end(),
                   [](const LogIssue& a, const LogIssue& b) { return a.byte_offset < b.byte_offset; });
  std::stable_sort(out.truth.begin(), out.truth.end(),
                   [](const TruthSample& a, const TruthSample& b) { return a.utime < b.utime; });
  return out;
}

}  // namespace lcmloc::eval
