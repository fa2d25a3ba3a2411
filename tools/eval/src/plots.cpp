// Figures like the paper's Fig. 5-9, drawn by gnuplot (pngcairo) from data files.
#include <sys/stat.h>
#include <sys/wait.h>
#include <fcntl.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <map>
#include <set>
#include <sstream>

#include "lcmloc/eval/gnuplot.hpp"
#include "lcmloc/eval/report.hpp"
#include "lcmloc/app/text.hpp"

namespace lcmloc::eval {

std::string withoutControlCharacters(std::string text) { return common::printable(text); }

std::string gnuplotQuote(const std::string& text) {
  std::string out = "'";
  for (char c : withoutControlCharacters(text)) {
    out += c;
    if (c == '\'') out += c;  // '' is a quote inside a single-quoted string
  }
  return out + "'";
}

bool findInPath(const std::string& exe) {
  const char* path = std::getenv("PATH");
  if (!path) return false;
  std::stringstream ss(path);
  std::string dir;
  while (std::getline(ss, dir, ':'))
    if (!dir.empty() && ::access((dir + "/" + exe).c_str(), X_OK) == 0) return true;
  return false;
}

int runGnuplot(const std::string& dir, const std::string& script) {
  const pid_t pid = ::fork();
  if (pid < 0) return -1;
  if (pid == 0) {
    if (::chdir(dir.c_str()) != 0) ::_exit(126);
    const int fd = ::open("gnuplot.log", O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) { ::dup2(fd, 1); ::dup2(fd, 2); ::close(fd); }
    ::execlp("gnuplot", "gnuplot", script.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return -1;
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

PlotResult& drawFigures(PlotResult& res, const std::string& dir, const std::string& script) {
  if (!findInPath("gnuplot")) {
    res.message = "gnuplot not found in PATH: no figures drawn (install gnuplot-nox); data files and " + script +
                  " are in " + dir;
    res.figures.clear();
    return res;
  }
  const int rc = runGnuplot(dir, script);
  if (rc != 0) {
    res.message = "gnuplot failed (exit " + std::to_string(rc) + "): see " + dir + "/gnuplot.log";
    res.figures.clear();
    return res;
  }
  for (auto& f : res.figures) f = dir + "/" + f;
  res.ok = true;
  res.message = "figures written to " + dir;
  return res;
}

namespace {

const std::map<std::string, std::string> kColours{{"dead_reckoning", "#e69f00"},
                                                  {"ukf", "#cc79a7"},
                                                  {"ukf_gated", "#009e73"},
                                                  {"ukf_calib", "#56b4e9"}};

std::string colour(const std::string& name) {
  auto it = kColours.find(name);
  return it == kColours.end() ? "#0072b2" : it->second;
}
/// The legend title of a run, quoted for the script.
std::string title(std::string name, const std::string& suffix = "") {
  for (auto& c : name) if (c == '_') c = ' ';
  return gnuplotQuote(name + suffix);
}

void writeTrack(const std::string& path, const FilterRun& run, int64_t t0) {
  std::ofstream f(path);
  f << "# t[s] x[m] y[m] err_x[m] err_y[m] err[m]\n" << std::setprecision(9);
  for (const auto& p : run.track) {
    f << secondsSince(p.utime, t0) << ' ' << p.x << ' ' << p.y << ' ';
    if (p.scored) f << p.err_x << ' ' << p.err_y << ' ' << p.err << '\n';
    else f << "? ? ?\n";
  }
}

/// Measurements with a positive, finite innovation distance (plottable on a log scale).
bool writeDecisions(const std::string& path, const FilterRun& run, int64_t t0) {
  std::ofstream f(path);
  f << "# t[s] innovation_distance accepted fault\n" << std::setprecision(9);
  bool any = false;
  for (const auto& r : run.decisions) {
    const double m = r.decision.mahalanobis;
    if (!(m > 0) || !std::isfinite(m)) continue;
    f << secondsSince(r.decision.utime, t0) << ' ' << m << ' ' << (r.decision.accepted ? 1 : 0) << ' '
      << (r.is_fault ? 1 : 0) << '\n';
    any = true;
  }
  return any;
}

struct Series { std::string name, stem; bool live; };

void trajectorySeries(std::ostream& gp, const std::vector<Series>& series, bool faults) {
  gp << "plot 'truth.dat' u 2:3 w l lw 4 lc rgb '#000000' t 'ground truth'";
  for (const auto& s : series)
    gp << ", \\\n  " << gnuplotQuote("track_" + s.stem + ".dat") << " u 2:3 w l lw 2 " << (s.live ? "dt 2 " : "")
       << "lc rgb '" << colour(s.live ? "" : s.name) << "' t " << title(s.name);
  gp << ", \\\n  'markers.dat' u 1:2 w p pt 7 ps 1.2 lc rgb '#7f7f7f' t 'markers'";
  if (faults) gp << ", \\\n  'faults.dat' u 1:2 w p pt 2 ps 2.5 lw 3 lc rgb '#d55e00' t 'fault markers'";
  gp << "\n";
}

void trajectoryPlot(std::ostream& gp, const std::vector<Series>& series, bool faults) {
  gp << "set output 'trajectories.png'\n"
        "set title 'Trajectories: ground truth, dead reckoning and fused estimates'\n"
        "set xlabel 'X [m]'\nset ylabel 'Y [m]'\nset size ratio -1\n"
        "set key inside left bottom box opaque\n";
  trajectorySeries(gp, series, faults);
  gp << "set size noratio\nset key outside right top nobox\n";
}

/// One panel per located fault, 1.5 m around where the faulty marker would lie.
void faultZoomPlot(std::ostream& gp, const std::vector<Series>& series,
                   const std::vector<Evaluation::FaultMark>& faults) {
  std::vector<const Evaluation::FaultMark*> located;
  for (const auto& f : faults) if (f.located) located.push_back(&f);
  if (located.empty()) return;
  const std::size_t n = std::min<std::size_t>(located.size(), 4);
  gp << "set output 'trajectories_faults.png'\n"
     << "set terminal pngcairo size " << 560 * n << ",640 noenhanced font 'Sans,11'\n"
     << "set multiplot layout 1," << n << " title 'Around each fault marker (1.5 m)'\n"
     << "set size ratio -1\nset key inside left bottom box opaque font ',9'\n"
        "set xlabel 'X [m]'\nset ylabel 'Y [m]'\n";
  for (std::size_t i = 0; i < n; ++i) {
    const auto& f = *located[i];
    gp << "set title "
       << gnuplotQuote(f.fault.kind + " (" + f.fault.channel + " seq " + std::to_string(f.fault.measurement_seq) + ")")
       << "\n"
       << "set xrange [" << f.marker_x - 1.5 << ":" << f.marker_x + 1.5 << "]\n"
       << "set yrange [" << f.marker_y - 1.5 << ":" << f.marker_y + 1.5 << "]\n";
    trajectorySeries(gp, series, true);
  }
  gp << "unset multiplot\nset autoscale xy\nset size noratio\nset key outside right top nobox font ',12'\n"
        "set terminal pngcairo size 1100,800 noenhanced font 'Sans,12'\n";
}

void errorPlot(std::ostream& gp, const std::vector<Series>& series, const std::string& axis,
               int column, const std::vector<double>& fault_times) {
  gp << "set output 'error_" << axis << ".png'\n"
     << "set title 'Localization " << (axis == "x" ? "X" : "Y") << " coordinate error'\n"
     << "set xlabel 'time [s]'\nset ylabel '" << axis << " error (estimate - truth) [m]'\n";
  for (double t : fault_times)
    gp << "set arrow from " << t << ", graph 0 to " << t
       << ", graph 1 nohead dt 3 lw 1.5 lc rgb '#d55e00'\n";
  gp << "plot ";
  for (std::size_t i = 0; i < series.size(); ++i)
    gp << (i ? ", \\\n  " : "") << gnuplotQuote("track_" + series[i].stem + ".dat") << " u 1:" << column
       << " w l lw 2 " << (series[i].live ? "dt 2 " : "") << "lc rgb '"
       << colour(series[i].live ? "" : series[i].name) << "' t " << title(series[i].name);
  if (!fault_times.empty()) gp << ", \\\n  NaN w l dt 3 lw 1.5 lc rgb '#d55e00' t 'fault injected'";
  gp << "\nunset arrow\n";
}

void innovationPlot(std::ostream& gp, const std::vector<Series>& with_decisions, double gate) {
  gp << "set output 'innovation.png'\n"
        "set title 'Innovation distance of every ruler measurement against the gate'\n"
        "set xlabel 'time [s]'\nset ylabel 'innovation distance v^T S^-1 v (log scale)'\n"
        "set logscale y\n"
        "plot "
     << gate << " w l lw 2 dt 2 lc rgb '#d55e00' t sprintf('gate %.3f', " << gate << ")";
  for (const auto& s : with_decisions) {
    const std::string file = gnuplotQuote("decisions_" + s.stem + ".dat");
    gp << ", \\\n  " << file << " u 1:($3==1?$2:1/0) w p pt 7 ps 1.3 lc rgb '" << colour(s.name)
       << "' t " << title(s.name, " accepted")
       << ", \\\n  " << file << " u 1:($3==0?$2:1/0) w p pt 5 ps 1.3 lc rgb '" << colour(s.name)
       << "' t " << title(s.name, " rejected");
  }
  if (!with_decisions.empty())
    gp << ", \\\n  " << gnuplotQuote("decisions_" + with_decisions.back().stem + ".dat")
       << " u 1:($4==1?$2:1/0) w p pt 6 ps 3 lw 2 lc rgb '#d55e00' t 'fault measurement'";
  gp << "\nunset logscale y\n";
}

}  // namespace

PlotResult writePlots(const LogData& data, const Evaluation& ev, const core::MarkerMap& map,
                      const std::string& dir) {
  PlotResult res;
  const int64_t t0 = ev.t0_utime;
  {
    std::ofstream f(dir + "/truth.dat");
    f << "# t[s] x[m] y[m] heading[rad]\n" << std::setprecision(9);
    for (const auto& t : data.truth) f << secondsSince(t.utime, t0) << ' ' << t.x << ' ' << t.y << ' ' << t.heading << '\n';
    std::ofstream m(dir + "/markers.dat");
    m << "# x[m] y[m] id\n";
    for (const auto& k : map) m << k.x << ' ' << k.y << ' ' << k.id << '\n';
  }
  std::vector<double> fault_times;
  bool located_faults = false;
  {
    std::ofstream f(dir + "/faults.dat");
    f << "# marker_x[m] marker_y[m] t[s] kind\n";
    for (const auto& mark : ev.faults) {
      fault_times.push_back(secondsSince(mark.fault.utime, t0));
      if (!mark.located) continue;
      located_faults = true;
      f << mark.marker_x << ' ' << mark.marker_y << ' ' << fault_times.back() << ' '
        << withoutControlCharacters(mark.fault.kind) << '\n';
    }
  }
  std::vector<const FilterRun*> runs;
  for (const auto& run : ev.filters) runs.push_back(&run);
  if (ev.live) runs.push_back(&ev.live->run);
  std::vector<std::string> names;
  for (const auto* run : runs) names.push_back(run->name);
  const auto stems = uniqueStems(names);  // "live:ukf_gated" -> live_ukf_gated
  std::vector<Series> series, with_decisions;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const bool live = ev.live && runs[i] == &ev.live->run;
    series.push_back({runs[i]->name, stems[i], live});
    writeTrack(dir + "/track_" + stems[i] + ".dat", *runs[i], t0);
    if (!live && writeDecisions(dir + "/decisions_" + stems[i] + ".dat", *runs[i], t0))
      with_decisions.push_back(series.back());
  }

  {
    std::ofstream gp(dir + "/plot.gp");
    gp << "# Generated by lcmloc-eval; rerun with: gnuplot plot.gp\n"
          "set terminal pngcairo size 1100,800 noenhanced font 'Sans,12'\n"
          "set datafile missing '?'\nset grid\nset key outside right top\n";
    if (!data.truth.empty() || !series.empty()) {
      trajectoryPlot(gp, series, located_faults);
      res.figures.push_back("trajectories.png");
      if (located_faults) {
        faultZoomPlot(gp, series, ev.faults);
        res.figures.push_back("trajectories_faults.png");
      }
    }
    if (!with_decisions.empty()) {
      innovationPlot(gp, with_decisions, ev.gate_threshold);
      res.figures.push_back("innovation.png");
    }
    if (!data.truth.empty()) {
      errorPlot(gp, series, "x", 4, fault_times);
      errorPlot(gp, series, "y", 5, fault_times);
      res.figures.push_back("error_x.png");
      res.figures.push_back("error_y.png");
    }
    gp << "set output\n";
  }
  return drawFigures(res, dir, "plot.gp");
}

}  // namespace lcmloc::eval
