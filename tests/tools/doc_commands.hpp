#pragma once
// Reads the shell commands shown in a Markdown file: the fenced blocks tagged `sh` (run them) or
// `sh no-run` (check them only), split into commands, and each command into shell words.
// The convention is stated in the README ("The commands in these docs are tested").
#include <cctype>
#include <string>
#include <vector>

namespace doccmd {

struct Block {
  int line = 0;        ///< 1-based line of the opening fence
  std::string info;    ///< the fence's info string ("sh", "sh no-run", "", "yaml", ...)
  std::vector<std::string> lines;
  std::vector<int> line_numbers;
};

/// The fenced code blocks of a Markdown text (``` or ~~~, indented or not).
inline std::vector<Block> fencedBlocks(const std::string& text) {
  std::vector<Block> out;
  std::vector<std::string> lines;
  std::string cur;
  for (char c : text) {
    if (c == '\n') {
      lines.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (!cur.empty()) lines.push_back(cur);
  auto fenceOf = [](const std::string& l, std::string& rest) -> std::string {
    std::size_t i = l.find_first_not_of(' ');
    if (i == std::string::npos || i > 3) return "";
    const char c = l[i];
    if (c != '`' && c != '~') return "";
    std::size_t j = i;
    while (j < l.size() && l[j] == c) ++j;
    if (j - i < 3) return "";
    rest = l.substr(j);
    return l.substr(i, j - i);
  };
  for (std::size_t i = 0; i < lines.size(); ++i) {
    std::string rest;
    const std::string fence = fenceOf(lines[i], rest);
    if (fence.empty()) continue;
    Block b;
    b.line = static_cast<int>(i) + 1;
    const auto a = rest.find_first_not_of(" \t");
    b.info = a == std::string::npos ? "" : rest.substr(a, rest.find_last_not_of(" \t") - a + 1);
    std::size_t j = i + 1;
    for (; j < lines.size(); ++j) {
      std::string r;
      const std::string f = fenceOf(lines[j], r);
      if (!f.empty() && f[0] == fence[0] && f.size() >= fence.size() &&
          r.find_first_not_of(" \t") == std::string::npos)
        break;
      b.lines.push_back(lines[j]);
      b.line_numbers.push_back(static_cast<int>(j) + 1);
    }
    out.push_back(b);
    i = j;
  }
  return out;
}

inline std::vector<std::string> infoWords(const std::string& info) {
  std::vector<std::string> w;
  std::string cur;
  for (char c : info + " ") {
    if (c == ' ' || c == '\t') {
      if (!cur.empty()) w.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  return w;
}

/// A shell block: tagged sh, bash or shell.
inline bool isShell(const Block& b) {
  const auto w = infoWords(b.info);
  return !w.empty() && (w[0] == "sh" || w[0] == "bash" || w[0] == "shell");
}

/// A shell block the test runs (not tagged no-run).
inline bool isRun(const Block& b) {
  if (!isShell(b)) return false;
  for (const auto& w : infoWords(b.info))
    if (w == "no-run") return false;
  return true;
}

struct Command {
  int line = 0;
  std::string text;  ///< as written (continuation lines and a here-document joined with newlines)
};

/// The commands of a block: one per line, a line ending in a backslash continued on the next, a
/// here-document (`<<'EOF'` ... `EOF`) kept with its command; blank and comment lines skipped.
inline std::vector<Command> commands(const Block& b) {
  std::vector<Command> out;
  for (std::size_t i = 0; i < b.lines.size(); ++i) {
    const std::string& l = b.lines[i];
    const auto first = l.find_first_not_of(" \t");
    if (first == std::string::npos || l[first] == '#') continue;
    Command c{b.line_numbers[i], l};
    while (!c.text.empty() && c.text.back() == '\\' && i + 1 < b.lines.size()) c.text += "\n" + b.lines[++i];
    const auto h = c.text.find("<<");
    if (h != std::string::npos) {
      std::string word;
      for (std::size_t k = h + 2; k < c.text.size() && c.text[k] != ' '; ++k)
        if (c.text[k] != '\'' && c.text[k] != '"' && c.text[k] != '-') word += c.text[k];
      while (i + 1 < b.lines.size()) {
        c.text += "\n" + b.lines[++i];
        if (b.lines[i] == word) break;
      }
    }
    out.push_back(c);
  }
  return out;
}

/// Shell words of one command, split at the operators | & ; && || (each a word of its own), with
/// quotes removed, a comment (# at the start of a word) and a here-document's body left out.
inline std::vector<std::string> words(const std::string& text) {
  std::vector<std::string> w;
  std::string cur;
  bool have = false;
  auto flush = [&] {
    if (have) w.push_back(cur);
    cur.clear();
    have = false;
  };
  // A here-document's body is data: only its command line counts.
  const std::string line = text.find("<<") == std::string::npos ? text : text.substr(0, text.find('\n'));
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (c == '\\' && i + 1 < line.size()) {
      if (line[i + 1] == '\n') {
        ++i;
        continue;
      }
      cur += line[++i];
      have = true;
    } else if (c == '\'' || c == '"') {
      const auto end = line.find(c, i + 1);
      cur += line.substr(i + 1, end == std::string::npos ? std::string::npos : end - i - 1);
      have = true;
      if (end == std::string::npos) break;
      i = end;
    } else if (c == ' ' || c == '\t' || c == '\n') {
      flush();
    } else if (c == '#' && !have) {
      const auto nl = line.find('\n', i);
      if (nl == std::string::npos) break;
      i = nl - 1;
    } else if (c == '&' && have && cur.back() == '>') {  // 2>&1
      cur += c;
    } else if (c == '|' || c == '&' || c == ';') {
      flush();
      std::string op(1, c);
      if (i + 1 < line.size() && line[i + 1] == c) op += line[++i];
      w.push_back(op);
    } else {
      cur += c;
      have = true;
    }
  }
  flush();
  return w;
}

inline bool isOperator(const std::string& w) {
  return w == "|" || w == "||" || w == "&" || w == "&&" || w == ";" || w == ";;";
}

/// The simple commands of a command line: its words split at the operators, leading variable
/// assignments (NAME=value) dropped, redirections (> FILE, 2>&1, <<WORD) dropped.
inline std::vector<std::vector<std::string>> simpleCommands(const std::vector<std::string>& ws) {
  std::vector<std::vector<std::string>> out(1);
  for (std::size_t i = 0; i < ws.size(); ++i) {
    const std::string& w = ws[i];
    if (isOperator(w)) {
      if (!out.back().empty()) out.emplace_back();
      continue;
    }
    if (w.rfind(">", 0) == 0 || w.rfind("<", 0) == 0 || w.rfind("2>", 0) == 0) {
      if (w == ">" || w == ">>" || w == "<" || w == "2>" || w == "<<") ++i;  // its file
      continue;
    }
    if (out.back().empty()) {
      const auto eq = w.find('=');
      bool assign = eq != std::string::npos && eq > 0 && !std::isdigit(static_cast<unsigned char>(w[0]));
      for (std::size_t k = 0; assign && k < eq; ++k)
        assign = std::isalnum(static_cast<unsigned char>(w[k])) || w[k] == '_';
      if (assign) continue;
    }
    out.back().push_back(w);
  }
  if (out.back().empty()) out.pop_back();
  return out;
}

/// The options a simple command uses: words starting with "--" (up to an "="), and single-letter
/// ones ("-o"); synopsis brackets and ellipses removed.
inline std::vector<std::string> options(const std::vector<std::string>& cmd) {
  std::vector<std::string> out;
  for (std::size_t i = 1; i < cmd.size(); ++i) {
    std::string w = cmd[i];
    while (!w.empty() && (w.front() == '[')) w.erase(0, 1);
    while (!w.empty() && (w.back() == ']' || w.back() == '.')) w.pop_back();
    if (w.rfind("--", 0) == 0 && w.size() > 2) {
      out.push_back(w.substr(0, w.find('=')));
    } else if (w.size() == 2 && w[0] == '-' && std::isalpha(static_cast<unsigned char>(w[1]))) {
      out.push_back(w);
    }
  }
  return out;
}

/// Whether a --help text names the option: "--name" or "-x" not followed by more of a name.
inline bool helpNames(const std::string& help, const std::string& opt) {
  for (std::size_t p = help.find(opt); p != std::string::npos; p = help.find(opt, p + 1)) {
    const std::size_t e = p + opt.size();
    const bool left_ok = p == 0 || !(std::isalnum(static_cast<unsigned char>(help[p - 1])) || help[p - 1] == '-');
    const bool right_ok = e >= help.size() || !(std::isalnum(static_cast<unsigned char>(help[e])) || help[e] == '-' ||
                                                help[e] == '_');
    if (left_ok && right_ok) return true;
  }
  return false;
}

}  // namespace doccmd
