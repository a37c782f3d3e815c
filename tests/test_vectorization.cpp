// The tape's lane loops are vectorized by every build of the value path (runtime/tape_eval.hpp
// TapeIsa), checked from the compiler's own report rather than hoped for: the evaluator is compiled
// again with the library's flags and -fopt-info-vec-optimized, and every loop marked "vectorized
// in every build" must be reported vectorized with 64-, 32- and 16-byte vectors (the AVX-512,
// AVX2 and SSE4/baseline builds). GCC on x86-64 only, as the builds are.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

namespace {

// The 1-based lines of `source` that hold a marked loop: the marker's own line, or the line after
// a comment-only marker line.
std::vector<int> marked_loops(const std::string& source) {
  std::ifstream in(source);
  std::vector<int> out;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    const auto at = line.find("// vectorized in every build");
    if (at == std::string::npos) continue;
    const bool alone = line.find_first_not_of(" \t") == at;
    out.push_back(alone ? n + 1 : n);
  }
  return out;
}

}  // namespace

TEST(Vectorization, EveryBuildVectorizesTheMarkedLoops) {
#if !(defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__))
  GTEST_SKIP() << "the value path has one build here";
#else
  // The loops live in the evaluator and the curve header it includes (inlined into each build):
  // the evaluator is compiled, and each file's marked loops are looked up under its own name.
  const std::string source = std::string(HYBRIDTREE_SOURCE_DIR) + "/runtime/tape_eval.cpp";
  const std::vector<std::string> files = {"tape_eval.cpp", "tape_curve.hpp"};
  const auto report = std::filesystem::temp_directory_path() / ("ht_vectorization_" + std::to_string(::getpid()) + ".txt");
  const std::string command = std::string(HYBRIDTREE_CXX) + " " + HYBRIDTREE_CORE_FLAGS + " -O3 -DNDEBUG -std=c++20 -I" +
                              HYBRIDTREE_SOURCE_DIR + " -fopt-info-vec-optimized -c " + source + " -o /dev/null 2> " +
                              report.string();
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  std::ifstream in(report);
  std::stringstream text;
  text << in.rdbuf();
  std::filesystem::remove(report);
  const std::string all = text.str();
  std::size_t marked = 0;
  for (const std::string& file : files) {
    const std::vector<int> loops = marked_loops(std::string(HYBRIDTREE_SOURCE_DIR) + "/runtime/" + file);
    marked += loops.size();
    const std::string escaped = std::regex_replace(file, std::regex("\\."), "\\.");
    for (const int line : loops) {
      const std::regex hit(escaped + ":" + std::to_string(line) + ":[0-9]+: optimized: loop vectorized using ([0-9]+) byte vectors");
      std::set<int> widths;
      for (auto it = std::sregex_iterator(all.begin(), all.end(), hit); it != std::sregex_iterator(); ++it)
        widths.insert(std::stoi((*it)[1]));
      for (const int bytes : {64, 32, 16})
        EXPECT_TRUE(widths.count(bytes)) << file << ":" << line << " not vectorized with " << bytes << "-byte vectors";
    }
  }
  ASSERT_GE(marked, 2u) << "markers in runtime/tape_eval.cpp and runtime/tape_curve.hpp";
#endif
}
