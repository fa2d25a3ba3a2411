#include "lcmloc/ctl/status.hpp"

#include <chrono>
#include <iostream>

#include <fmt/format.h>

#include "lcmloc/app/exit_codes.hpp"
#include "lcmloc/app/signals.hpp"
#include "lcmloc/app/text.hpp"
#include "lcmloc/bus/transport.hpp"
#include "lcmloc/ctl/control.hpp"

namespace lcmloc::ctl {

void printTiming(std::ostream& out, const lcmloc::fusion_timing_t& t) {
  out << fmt::format("timing over the last {:.1f} s (wall clock; delay = arrival - message time):\n", t.window);
  out << fmt::format("  {:<20} {:>12} {:>12} {:>9} {:>9} {:>7} {:>11}\n", "channel", "delay p50 ms", "delay max ms",
                     "age s", "rate Hz", "late", "late max ms");
  for (std::size_t i = 0; i < t.channel.size(); ++i)
    out << fmt::format("  {:<20} {:>12.3f} {:>12.3f} {:>9.3f} {:>9.1f} {:>7} {:>11.3f}\n", app::printable(t.channel[i]),
                       t.delay_p50[i] * 1e3, t.delay_max[i] * 1e3, t.age[i], t.rate[i],
                       i < t.late.size() ? t.late[i] : 0, i < t.late_max.size() ? t.late_max[i] * 1e3 : 0.0);
  out << fmt::format("  horizon {:.3f} s (late: refused as later than it, since the daemon started); released early "
                     "at its memory bound: {}\n", t.horizon, t.released_early);
  out << fmt::format("  filter step (one message through the daemon): {} steps, p50 {:.3f} ms, p99 {:.3f} ms, "
                     "max {:.3f} ms\n",
                     t.steps, t.step_p50 * 1e3, t.step_p99 * 1e3, t.step_max * 1e3);
}

int fusionStatus(const app::SystemConfig& cfg, const std::string& lcm_url, double timeout) {
  bus::Bus bus(lcm_url);
  std::optional<lcmloc::fusion_status_t> st;
  std::optional<lcmloc::fusion_timing_t> timing;
  bus.subscribe<lcmloc::fusion_status_t>(cfg.channels.status,
                                         [&](const std::string&, const lcmloc::fusion_status_t& m, int64_t) { st = m; });
  bus.subscribe<lcmloc::fusion_timing_t>(
      cfg.channels.timing, [&](const std::string&, const lcmloc::fusion_timing_t& m, int64_t) { timing = m; });
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout);
  // FUSION_TIMING comes once per wall second, FUSION_STATUS once per fusion.status_period of
  // message time (and at events): both are waited for.
  while (!(timing && st) && std::chrono::steady_clock::now() < deadline && !app::stopRequested()) bus.handle(50);
  if (st)
    std::cout << fmt::format("filter {}, status {}, last event {} at utime {}; in {}, used {}, rejected {}, gaps {}\n",
                             app::printable(st->filter), st->status, app::printable(st->event), st->utime,
                             st->messages_in, st->messages_used, st->messages_rejected, st->sequence_gaps);
  else
    std::cout << fmt::format("no {} within {:.1f} s\n", cfg.channels.status, timeout);
  if (!timing) {
    std::cout << fmt::format("no {} within {:.1f} s: is lcmloc-fusion running?\n", cfg.channels.timing, timeout);
    return kExitNoAnswer;
  }
  printTiming(std::cout, *timing);
  return app::kExitOk;
}

}  // namespace lcmloc::ctl
