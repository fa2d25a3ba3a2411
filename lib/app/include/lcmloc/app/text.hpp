#pragma once
// Strings from the bus or a log (channel, filter and sensor names, details) as a terminal or a
// log line may show them.
#include <cstdint>
#include <string>

namespace lcmloc::app {

/// text as a terminal or a log line may show it: every control character (bytes below 0x20,
/// 0x7f, and the C1 controls U+0080..U+009F, which some terminals take as escape sequences) and
/// every byte that is not part of valid UTF-8 becomes '?'. A string from the bus or a log may
/// hold any bytes: printed as it is, an escape sequence would move the cursor, clear the screen or
/// set the terminal's title, and a newline would fake a line of output.
inline std::string printable(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  const std::size_t n = text.size();
  for (std::size_t i = 0; i < n;) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c < 0x80) {
      out += c < 0x20 || c == 0x7f ? '?' : static_cast<char>(c);
      ++i;
      continue;
    }
    // A multi-byte sequence: its length from the lead byte, then continuation bytes 10xxxxxx,
    // no overlong form, no surrogate, nothing beyond U+10FFFF.
    const std::size_t len = c >= 0xc2 && c <= 0xdf ? 2 : c >= 0xe0 && c <= 0xef ? 3 : c >= 0xf0 && c <= 0xf4 ? 4 : 0;
    bool ok = len > 0 && i + len <= n;
    uint32_t cp = len == 2 ? c & 0x1fu : len == 3 ? c & 0x0fu : c & 0x07u;
    for (std::size_t k = 1; ok && k < len; ++k) {
      const auto b = static_cast<unsigned char>(text[i + k]);
      ok = (b & 0xc0) == 0x80;
      cp = (cp << 6) | (b & 0x3fu);
    }
    if (ok) ok = len != 3 || (cp >= 0x800 && (cp < 0xd800 || cp > 0xdfff));
    if (ok) ok = len != 4 || (cp >= 0x10000 && cp <= 0x10ffff);
    if (!ok) {
      out += '?';
      ++i;
      continue;
    }
    if (cp <= 0x9f) out += '?';  // a C1 control (two bytes, U+0080..U+009F)
    else out.append(text, i, len);
    i += len;
  }
  return out;
}

}  // namespace lcmloc::app
