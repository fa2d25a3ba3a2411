// The gate figures of lcmloc-evaluate (see trajectory_report.hpp).
#include <cmath>
#include <fstream>
#include <iomanip>
#include <map>
#include <set>

#include "lcmloc/eval/gnuplot.hpp"
#include "lcmloc/eval/trajectory_report.hpp"

namespace lcmloc::eval {

void writeGatePlots(std::ostream& gp, const TrajectoryLog& log, int64_t t0, const std::string& dir,
                    std::vector<std::string>& figures) {
  std::set<std::pair<std::string, int64_t>> faults;
  for (const auto& f : log.faults) faults.emplace(f.channel, f.measurement_seq);
  std::map<std::string, std::vector<const GateRecord*>> by_filter;  // plottable on a log scale
  for (const auto& g : log.gates)
    if (g.nis > 0 && std::isfinite(g.nis)) by_filter[g.filter].push_back(&g);
  std::vector<std::string> names;
  for (const auto& [name, records] : by_filter) names.push_back(name);
  const auto stems = uniqueStems(names);
  for (std::size_t i = 0; i < names.size(); ++i) {
    const std::string data = "gate_" + stems[i] + ".dat", png = "gate_" + stems[i] + ".png";
    {
      std::ofstream f(dir + "/" + data);
      f << "# t[s] nis accepted fault gate (? = no gate)\n" << std::setprecision(10);
      for (const auto* g : by_filter[names[i]]) {
        f << secondsSince(g->utime, t0) << ' ' << g->nis << ' ' << (g->accepted ? 1 : 0) << ' '
          << (faults.count({g->sensor, g->measurement_seq}) ? 1 : 0) << ' ';
        if (g->gate > 0 && std::isfinite(g->gate)) f << g->gate << '\n';
        else f << "?\n";
      }
    }
    // Filter names come from the log: into the script only through gnuplotQuote.
    const std::string q = gnuplotQuote(data);
    gp << "set output " << gnuplotQuote(png) << "\n"
       << "set title " << gnuplotQuote("Gate decisions of " + names[i] + ": NIS against the gate") << "\n"
       << "set xlabel 'time [s]'\nset ylabel 'NIS v^T S^-1 v (log scale)'\nset logscale y\nset format y '%g'\n"
       << "set key inside right top box opaque\n"
       << "plot " << q << " u 1:5 w p pt 1 ps 1.5 lc rgb '#7f7f7f' t 'gate', \\\n  "
       << q << " u 1:($3==1?$2:1/0) w p pt 7 ps 1.2 lc rgb '#009e73' t 'accepted', \\\n  "
       << q << " u 1:($3==0?$2:1/0) w p pt 5 ps 1.2 lc rgb '#d55e00' t 'rejected', \\\n  "
       << q << " u 1:($4==1?$2:1/0) w p pt 6 ps 3 lw 2 lc rgb '#000000' t 'announced fault'\n"
       << "unset logscale y\nset format y '% h'\nset key outside right top nobox\n";
    figures.push_back(png);
  }
}

}  // namespace lcmloc::eval
