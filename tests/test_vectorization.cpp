// The tape's lane loops are vectorized by every build of the value path (runtime/tape_eval.hpp
// TapeIsa), checked from the compiler's own report rather than hoped for: the source is compiled
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
  const std::string source = std::string(HYBRIDTREE_SOURCE_DIR) + "/runtime/tape_eval.cpp";
  const std::vector<int> loops = marked_loops(source);
  ASSERT_GE(loops.size(), 2u) << "markers in " << source;
  const auto report = std::filesystem::temp_directory_path() / ("ht_vectorization_" + std::to_string(::getpid()) + ".txt");
  const std::string command = std::string(HYBRIDTREE_CXX) + " " + HYBRIDTREE_CORE_FLAGS + " -O3 -DNDEBUG -std=c++20 -I" +
                              HYBRIDTREE_SOURCE_DIR + " -fopt-info-vec-optimized -c " + source + " -o /dev/null 2> " +
                              report.string();
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  std::ifstream in(report);
  std::stringstream text;
  text << in.rdbuf();
  std::filesystem::remove(report);
  for (const int line : loops) {
    const std::regex hit("tape_eval\\.cpp:" + std::to_string(line) + ":[0-9]+: optimized: loop vectorized using ([0-9]+) byte vectors");
    std::set<int> widths;
    const std::string all = text.str();
    for (auto it = std::sregex_iterator(all.begin(), all.end(), hit); it != std::sregex_iterator(); ++it)
      widths.insert(std::stoi((*it)[1]));
    for (const int bytes : {64, 32, 16})
      EXPECT_TRUE(widths.count(bytes)) << "tape_eval.cpp:" << line << " not vectorized with " << bytes << "-byte vectors";
  }
#endif
}
