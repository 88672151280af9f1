// Bounds on TOML text before it reaches the parser (toml++ 3.3.0, Debian 12's):
// that release overflows the stack on a key or table header of tens of
// thousands of dotted parts, and reaches code it marks unreachable (undefined
// behaviour) on a non-ASCII character outside a string or comment, e.g. the
// two-line file `zz = 1` / `é`, and on some after a backslash in a string. A file
// that breaks a limit is refused with a clean message; the parser never sees it.
//
// Limits:
//   - at most kTomlMaxBytes bytes;
//   - valid UTF-8 (no overlong forms, surrogates or code points past U+10FFFF);
//   - non-ASCII characters only inside strings and comments, and never right after a
//     backslash in a basic string (no TOML escape is);
//   - a key or table header of at most kTomlMaxKeyParts dotted parts;
//   - arrays and inline tables nested at most kTomlMaxNesting deep
//     (a [[table]] header counts as two).
// Usage (any loader of TOML text):
//   std::string text, err, why;
//   if (!read_toml_file(path, text, err)) fail(err);
//   if (!toml_input_within_limits(text, why)) fail(path + ": TOML input refused: " + why);
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

constexpr std::size_t kTomlMaxBytes = 1024 * 1024;
constexpr int kTomlMaxKeyParts = 16;
constexpr int kTomlMaxNesting = 16;

// True when text is within the limits; else false with why set to a one-line
// reason that names the line, e.g. "a key or table header of more than 16 dotted
// parts (line 3)". Linear in the text, no allocation besides why.
bool toml_input_within_limits(std::string_view text, std::string &why);

// Reads the file every TOML reader (models, robots' leg files, scenes) opens: a regular
// file only, at most kTomlMaxBytes + 1 bytes (a larger file is then refused by the limits
// without being held whole). Anything else (a FIFO, a device, a folder) is refused without
// blocking: it is opened non-blocking and checked before the first read. False with err =
// "PATH: cannot read: REASON" (e.g. "not a regular file", "No such file or directory").
bool read_toml_file(const char *path, std::string &text, std::string &err);
