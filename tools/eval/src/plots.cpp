// Running gnuplot (pngcairo) on the figures' scripts, and quoting text for the scripts.
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

std::string withoutControlCharacters(std::string text) { return app::printable(text); }

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

}  // namespace lcmloc::eval
