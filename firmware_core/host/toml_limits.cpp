// A one-pass scanner of TOML text: it tracks only what the limits need (strings,
// comments, bracket depth, dots between key separators), not the grammar; the
// parser still judges the syntax.
#include "toml_limits.hpp"

#include <cerrno>
#include <cstring>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace {

enum class Mode { Normal, Comment, Basic, Literal, MultiBasic, MultiLiteral };

// Length of the valid UTF-8 sequence at text[i] (1..4), or 0 if it is not one.
std::size_t utf8_length(std::string_view text, std::size_t i) {
  const auto b = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char c = b(i);
  if (c < 0x80) return 1;
  std::size_t n;
  unsigned long cp;
  if (c >= 0xC2 && c <= 0xDF) {
    n = 2;
    cp = c & 0x1Fu;
  } else if (c >= 0xE0 && c <= 0xEF) {
    n = 3;
    cp = c & 0x0Fu;
  } else if (c >= 0xF0 && c <= 0xF4) {
    n = 4;
    cp = c & 0x07u;
  } else {
    return 0;  // a continuation byte, an overlong lead (C0, C1) or past F4
  }
  if (i + n > text.size()) return 0;
  for (std::size_t k = 1; k < n; ++k) {
    if ((b(i + k) & 0xC0u) != 0x80u) return 0;
    cp = (cp << 6) | (b(i + k) & 0x3Fu);
  }
  const unsigned long min_cp[5] = {0, 0, 0x80, 0x800, 0x10000};
  if (cp < min_cp[n] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return 0;
  return n;
}

bool starts(std::string_view text, std::size_t i, const char *three) {
  return i + 3 <= text.size() && text.compare(i, 3, three) == 0;
}

// After a backslash: a character other than a newline, skipped as escaped (a backslash
// before a newline continues a multi-line string; the line is counted). A non-ASCII one
// was refused before (backslash_non_ascii).
bool escapable(std::string_view text, std::size_t i) { return i + 1 < text.size() && text[i + 1] != '\n'; }

// A backslash before a non-ASCII character in a basic string: no TOML escape (escapes are
// ASCII, a line-ending backslash is followed by blanks or a newline), and toml++ 3.3.0
// reaches code it marks unreachable on some (e.g. U+01A5 after a backslash in a multi-line
// string: its whitespace test for the line ending).
bool backslash_non_ascii(std::string_view text, std::size_t i) {
  return i + 1 < text.size() && static_cast<unsigned char>(text[i + 1]) >= 0x80;
}

// A quote opens a string only where a token may start (what toml++ does): at the start of
// a line or after '=', '[', '{', ',' or '.', blanks aside. Elsewhere (e.g. `s = 0'`) it
// is a character of a bare value, and what follows is checked as outside a string.
bool opens_string(char prev) {
  return prev == '\n' || prev == '=' || prev == '[' || prev == '{' || prev == ',' || prev == '.';
}

bool refuse(std::string &why, const std::string &what, long line) {
  why = what + " (line " + std::to_string(line) + ")";
  return false;
}

}  // namespace

bool toml_input_within_limits(std::string_view text, std::string &why) {
  if (text.size() > kTomlMaxBytes) {
    why = "larger than " + std::to_string(kTomlMaxBytes) + " bytes";
    return false;
  }
  Mode mode = Mode::Normal;
  long line = 1;
  int depth = 0, dots = 0;
  char prev = '\n';  // the last non-blank character outside strings and comments
  std::size_t i = 0;
  while (i < text.size()) {
    const char c = text[i];
    const std::size_t n = utf8_length(text, i);
    if (n == 0) return refuse(why, "invalid UTF-8", line);
    if (n > 1) {
      if (mode == Mode::Normal)
        return refuse(why, "a non-ASCII character outside a string or comment", line);
      i += n;
      continue;
    }
    if (c == '\n') {
      ++line;
      dots = 0;  // a key never spans lines
      if (mode == Mode::Comment || mode == Mode::Basic || mode == Mode::Literal) mode = Mode::Normal;
      if (mode == Mode::Normal) prev = '\n';
      ++i;
      continue;
    }
    switch (mode) {
      case Mode::Normal:
        if (c == '#') {
          mode = Mode::Comment;
        } else if ((c == '"' || c == '\'') && opens_string(prev)) {
          const bool multi = starts(text, i, c == '"' ? "\"\"\"" : "'''");
          mode = c == '"' ? (multi ? Mode::MultiBasic : Mode::Basic)
                          : (multi ? Mode::MultiLiteral : Mode::Literal);
          if (multi) i += 2;
        } else if (c == '[' || c == '{') {
          dots = 0;
          if (++depth > kTomlMaxNesting)
            return refuse(why,
                          "arrays, inline tables or headers nested deeper than " +
                              std::to_string(kTomlMaxNesting),
                          line);
        } else if (c == ']' || c == '}') {
          dots = 0;
          if (depth > 0) --depth;
        } else if (c == '=' || c == ',') {
          dots = 0;
        } else if (c == '.') {
          // a float or a time has one dot; a dotted key has parts - 1
          if (++dots >= kTomlMaxKeyParts)
            return refuse(why,
                          "a key or table header of more than " + std::to_string(kTomlMaxKeyParts) +
                              " dotted parts",
                          line);
        }
        if (mode == Mode::Normal && c != ' ' && c != '\t' && c != '\r') prev = c;
        break;
      case Mode::Comment: break;
      case Mode::Basic:
        if (c == '\\' && backslash_non_ascii(text, i))
          return refuse(why, "a backslash before a non-ASCII character in a string", line);
        if (c == '\\' && escapable(text, i)) ++i;  // the escaped character
        else if (c == '"') mode = Mode::Normal, prev = c;
        break;
      case Mode::Literal:
        if (c == '\'') mode = Mode::Normal, prev = c;
        break;
      case Mode::MultiBasic:
      case Mode::MultiLiteral: {
        const char quote = mode == Mode::MultiBasic ? '"' : '\'';
        if (mode == Mode::MultiBasic && c == '\\' && backslash_non_ascii(text, i))
          return refuse(why, "a backslash before a non-ASCII character in a string", line);
        if (mode == Mode::MultiBasic && c == '\\' && escapable(text, i)) {
          ++i;
        } else if (c == quote && starts(text, i, mode == Mode::MultiBasic ? "\"\"\"" : "'''")) {
          std::size_t run = 3;  // up to two quotes of the content may end it: """"" is legal
          while (run < 5 && i + run < text.size() && text[i + run] == quote) ++run;
          i += run - 1;
          mode = Mode::Normal;
          prev = quote;
        }
        break;
      }
    }
    ++i;
  }
  return true;
}

bool read_toml_file(const char *path, std::string &text, std::string &err) {
  const int fd = ::open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    err = std::string(path) + ": cannot read: " + std::strerror(errno);
    return false;
  }
  struct stat st;
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    err = std::string(path) + ": cannot read: not a regular file";
    return false;
  }
  text.resize(kTomlMaxBytes + 1);
  std::size_t got = 0;
  while (got < text.size()) {
    const ssize_t k = ::read(fd, &text[got], text.size() - got);
    if (k < 0 && errno == EINTR) continue;
    if (k < 0) {
      const int e = errno;
      ::close(fd);
      err = std::string(path) + ": cannot read: " + std::strerror(e);
      return false;
    }
    if (k == 0) break;
    got += static_cast<std::size_t>(k);
  }
  ::close(fd);
  text.resize(got);
  return true;
}
