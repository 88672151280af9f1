// Runs a fuzz target's entry point (LLVMFuzzerTestOneInput) over files and folders
// (recursively, in name order) without libFuzzer: the regression and seed corpora as plain
// CTest tests in every build (host, asan). A violated invariant aborts (non-zero exit);
// the last "run" line names the input. --min-robot N fails the run when fewer than N inputs
// reached the two-leg robot's code (fuzz/reach.h): the check that a target reaches the robot;
// --min-hexapod N so for the hexapod's node (fuzz_can).
//
//   fuzz_<target>_corpus [--max-seconds S] [--min-robot N] [--min-hexapod N] PATH...
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
extern "C" int64_t fuzz_robot_inputs();  // fuzz/reach.h
extern "C" int64_t fuzz_hexapod_inputs();

namespace fs = std::filesystem;

int main(int argc, char **argv) {
  double max_seconds = 0;  // per input; 0: no limit
  long long min_robot = 0, min_hexapod = 0;
  std::vector<fs::path> inputs;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--max-seconds" && i + 1 < argc) {
      max_seconds = std::atof(argv[++i]);
      continue;
    }
    if (a == "--min-robot" && i + 1 < argc) {
      min_robot = std::atoll(argv[++i]);
      continue;
    }
    if (a == "--min-hexapod" && i + 1 < argc) {
      min_hexapod = std::atoll(argv[++i]);
      continue;
    }
    std::error_code ec;
    if (fs::is_directory(a, ec)) {
      std::vector<fs::path> found;
      for (const auto &e : fs::recursive_directory_iterator(a, ec))
        if (e.is_regular_file()) found.push_back(e.path());
      std::sort(found.begin(), found.end());
      inputs.insert(inputs.end(), found.begin(), found.end());
    } else if (fs::is_regular_file(a, ec)) {
      inputs.emplace_back(a);
    } else {
      std::fprintf(stderr, "%s: no such file or folder: %s\n", argv[0], a.c_str());
      return 2;
    }
  }
  if (inputs.empty()) {
    std::fprintf(stderr, "%s: no inputs (usage: %s [--max-seconds S] [--min-robot N] [--min-hexapod N] PATH...)\n",
                 argv[0], argv[0]);
    return 2;
  }
  int slow = 0;
  for (const fs::path &p : inputs) {
    std::ifstream f(p, std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    std::printf("run %s (%zu bytes)\n", p.c_str(), bytes.size());
    std::fflush(stdout);
    const auto t0 = std::chrono::steady_clock::now();
    LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t *>(bytes.data()), bytes.size());
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (max_seconds > 0 && s > max_seconds) {
      std::fprintf(stderr, "too slow: %s took %.2f s (limit %.2f s)\n", p.c_str(), s, max_seconds);
      ++slow;
    }
  }
  const long long robot = static_cast<long long>(fuzz_robot_inputs());
  const long long hexapod = static_cast<long long>(fuzz_hexapod_inputs());
  std::printf("%zu inputs, %d too slow, %lld reached the robot, %lld the hexapod\n", inputs.size(), slow, robot,
              hexapod);
  if (robot < min_robot)
    std::fprintf(stderr, "%s: %lld inputs reached the robot, fewer than --min-robot %lld\n", argv[0],
                 robot, min_robot);
  if (hexapod < min_hexapod)
    std::fprintf(stderr, "%s: %lld inputs reached the hexapod, fewer than --min-hexapod %lld\n", argv[0],
                 hexapod, min_hexapod);
  return slow || robot < min_robot || hexapod < min_hexapod ? 1 : 0;
}
