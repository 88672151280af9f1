// The scene files' TOML reading helpers, shared by the planar scenes' reader (scene_parse.cpp)
// and the hexapod's (scene_hexapod.cpp): the refusal (a message naming the key and the
// problem), the keys' check, numbers. Internal to them.
#ifndef LEGSIM_HOST_SCENE_READ_HPP
#define LEGSIM_HOST_SCENE_READ_HPP

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <toml++/toml.h>

#include "scene_text.hpp"

namespace legsim_host {
namespace scene_read {

// A scene refused: the message names the key and the problem (the caller adds the file).
struct SceneError {
  std::string message;
};
[[noreturn]] inline void fail(const std::string &problem) { throw SceneError{problem}; }

using Node = const toml::node *;
using Table = const toml::table *;

inline bool is_number(Node v) { return v && (v->is_integer() || v->is_floating_point()); }
inline double to_double(Node v) {
  if (v->is_integer()) return static_cast<double>(*v->value<int64_t>());
  return v->as_floating_point()->get();
}

// A finite number (an integer or a float), else refused naming `what`.
inline double real_of(Node v, const std::string &what) {
  if (!is_number(v)) fail(what + " must be a number");
  const double x = to_double(v);
  if (!std::isfinite(x)) fail(what + " is not finite");
  return x;
}

// Every key of t among `allowed`, else refused with the sorted list (where: the table's path).
inline void check_keys(Table t, const std::vector<std::string> &allowed, const std::string &where) {
  for (auto &&kv : *t) {
    const std::string key(kv.first.str());
    if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
      std::vector<std::string> sorted = allowed;
      std::sort(sorted.begin(), sorted.end());
      std::string list;
      for (size_t i = 0; i < sorted.size(); ++i) list += (i ? ", " : "") + sorted[i];
      fail(where + "unknown key " + scene_text::q(key) + " (allowed: " + list + ")");
    }
  }
}

}  // namespace scene_read
}  // namespace legsim_host

#endif
