#include "timing.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace lcmloc::fusion {

double quantile(std::vector<double>& values, double q) {
  if (values.empty()) return 0.0;
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(values.size())));
  const std::size_t k = std::min(values.size() - 1, rank > 0 ? rank - 1 : 0);
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

void DaemonTiming::expire(std::deque<Sample>& d, int64_t now_us) const {
  while (!d.empty() && (d.front().at < now_us - window_us_ || d.size() > kMaxSamples)) d.pop_front();
}

void DaemonTiming::arrived(const std::string& channel, int64_t msg_utime, int64_t recv_utime) {
  Channel& c = channels_[channel];
  if (c.delays.empty() && c.last == 0) c.first = recv_utime;
  c.last = recv_utime;
  c.delays.push_back({recv_utime, (static_cast<double>(recv_utime) - static_cast<double>(msg_utime)) * 1e-6});
  expire(c.delays, recv_utime);
}

void DaemonTiming::step(double seconds, int64_t now_us) {
  steps_.push_back({now_us, seconds});
  expire(steps_, now_us);
}

lcmloc::fusion_timing_t DaemonTiming::report(int64_t now_us, const std::map<std::string, core::LateInputs>& late) {
  lcmloc::fusion_timing_t m{};
  m.utime = now_us;
  m.window = static_cast<double>(window_us_) * 1e-6;
  std::vector<double> v;
  for (auto& [name, c] : channels_) {
    expire(c.delays, now_us);
    v.clear();
    for (const Sample& s : c.delays) v.push_back(s.value);
    m.channel.push_back(name);
    m.count.push_back(static_cast<int64_t>(v.size()));
    const double span = std::min(m.window, static_cast<double>(now_us - c.first) * 1e-6);
    m.rate.push_back(span > 0 ? static_cast<double>(v.size()) / span : 0.0);
    m.age.push_back(static_cast<double>(now_us - c.last) * 1e-6);
    m.delay_max.push_back(v.empty() ? 0.0 : *std::max_element(v.begin(), v.end()));
    m.delay_p50.push_back(quantile(v, 0.5));
    const auto l = late.find(name);
    m.late.push_back(l == late.end() ? 0 : l->second.count);
    m.late_max.push_back(l == late.end() ? 0.0 : static_cast<double>(l->second.max_lateness_us) * 1e-6);
  }
  m.num_channels = static_cast<int32_t>(m.channel.size());
  expire(steps_, now_us);
  v.clear();
  for (const Sample& s : steps_) v.push_back(s.value);
  m.steps = static_cast<int64_t>(v.size());
  m.step_max = v.empty() ? 0.0 : *std::max_element(v.begin(), v.end());
  m.step_p99 = quantile(v, 0.99);
  m.step_p50 = quantile(v, 0.5);
  return m;
}

}  // namespace lcmloc::fusion
