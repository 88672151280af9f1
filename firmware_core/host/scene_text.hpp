// Text helpers shared by the scene files' parser, runner and writers (internal to them).
#ifndef LEGSIM_HOST_SCENE_TEXT_HPP
#define LEGSIM_HOST_SCENE_TEXT_HPP

#include <charconv>
#include <cmath>
#include <cstring>
#include <string>

#include "legsim/legsim.h"

namespace legsim_host {
namespace scene_text {

// 'name', as messages quote names
inline std::string q(const std::string &s) { return "'" + s + "'"; }

// x in its shortest round-trip form
inline std::string num(double x) {
  if (!std::isfinite(x)) return std::isnan(x) ? "nan" : (x > 0 ? "inf" : "-inf");
  char buf[64];
  auto r = std::to_chars(buf, buf + sizeof buf, x);
  return std::string(buf, r.ptr);
}

// a model's fixed-size name field as a string
inline std::string name_of(const char (&n)[LEGSIM_NAME_LEN]) {
  return std::string(n, strnlen(n, LEGSIM_NAME_LEN));
}

}  // namespace scene_text
}  // namespace legsim_host

#endif  // LEGSIM_HOST_SCENE_TEXT_HPP
