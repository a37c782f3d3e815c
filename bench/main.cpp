// The benchmark harness: Google Benchmark with a quick mode for 2-core CI machines.
//   hybridtree_bench            full runs
//   hybridtree_bench --quick    every benchmark briefly (the whole harness in well under a minute)
// Any other flag goes to Google Benchmark (e.g. --benchmark_filter=Mesh).
//   hybridtree_bench --peak-child NAME ARG   internal: one task's peak memory (bench/peak_memory.hpp)
#include "bench/bench_util.hpp"
#include "bench/peak_memory.hpp"

#include <benchmark/benchmark.h>

#include <cstring>
#include <string>
#include <vector>

namespace ht::bench {
bool quick_mode = false;
}

int main(int argc, char** argv) {
  if (argc == 4 && std::strcmp(argv[1], "--peak-child") == 0) return ht::bench::peak_child_main(argv[2], argv[3]);
  std::vector<char*> args;
  static char min_time[] = "--benchmark_min_time=0.05";
  for (int i = 0; i < argc; ++i) {
    if (std::strcmp(argv[i], "--quick") == 0) {
      ht::bench::quick_mode = true;
      continue;
    }
    args.push_back(argv[i]);
  }
  if (ht::bench::quick_mode) args.insert(args.begin() + 1, min_time);
  int count = static_cast<int>(args.size());
  benchmark::Initialize(&count, args.data());
  if (benchmark::ReportUnrecognizedArguments(count, args.data())) return 2;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
