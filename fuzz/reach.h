// What the fuzz targets reached: each entry point counts the inputs that reached the two-leg
// robot's code (fuzz/README.md, "Reaching the robot") and the hexapod's (fuzz_can: its node;
// fuzz_scene: its scene reader), prints
// the counts at exit, and gives them to the corpus driver (its --min-robot and --min-hexapod
// checks).
#ifndef LEGSIM_FUZZ_REACH_H
#define LEGSIM_FUZZ_REACH_H

#include <cstdint>
#include <cstdio>
#include <cstdlib>

extern "C" int64_t fuzz_robot_inputs();
extern "C" int64_t fuzz_hexapod_inputs();

namespace fuzz_reach {

struct Counts {
  const char *target = "";
  int64_t inputs = 0, robot = 0, hexapod = 0;
  int64_t robot_input = 0, hexapod_input = 0;  // the input last counted (once per input)
};
inline Counts g_counts;

inline void print_counts() {
  std::fprintf(stderr, "%s: %lld of %lld inputs reached the robot\n", g_counts.target,
               static_cast<long long>(g_counts.robot), static_cast<long long>(g_counts.inputs));
  if (g_counts.hexapod > 0)
    std::fprintf(stderr, "%s: %lld of %lld inputs reached the hexapod\n", g_counts.target,
                 static_cast<long long>(g_counts.hexapod), static_cast<long long>(g_counts.inputs));
}

// At the start of every input.
inline void input(const char *target) {
  if (g_counts.inputs++ == 0) {
    g_counts.target = target;
    std::atexit(print_counts);
  }
}

// The input in progress reached the robot's code (counted once per input).
inline void robot() {
  if (g_counts.robot_input == g_counts.inputs) return;
  g_counts.robot_input = g_counts.inputs;
  ++g_counts.robot;
}

// The input in progress reached the hexapod's node or scene reader (counted once per input).
inline void hexapod() {
  if (g_counts.hexapod_input == g_counts.inputs) return;
  g_counts.hexapod_input = g_counts.inputs;
  ++g_counts.hexapod;
}

}  // namespace fuzz_reach

#define FUZZ_REACH_DEFINE                                                           \
  extern "C" int64_t fuzz_robot_inputs() { return fuzz_reach::g_counts.robot; }     \
  extern "C" int64_t fuzz_hexapod_inputs() { return fuzz_reach::g_counts.hexapod; }

#endif
