// The paper's Table 1, reproduced where our examples stand for its figures: each scene meshed
// with its own precision and the default strategy, at 1 and 2 threads, its triangles beside the
// paper's (Pentium IV 2.4 GHz, seconds and triangles as the paper prints them). Figure 7 is
// examples/winged_bunny.json (bunny00 and armadillo's crop standing for the Stanford Bunny and the
// Victory's wings), Figure 8 examples/bowl.json and Figure 10 examples/restoration.json (the
// paper's Igea), Figures 1-2 examples/snake_woman.json (the 250-curve snake, its head cut off by a
// sphere, Igea blended on as the head, armadillo's crop standing for the Victory's wings) and
// Figure 9 examples/spiky_snake_woman.json (that body and head deformed by an ffd, minus a
// segment's tunnel). A scene whose meshes are missing (Igea comes from ../shared) is skipped with
// a message. Counter quality_s: the seconds of the quality pass in the scene's global
// polygonizations (the 250-curve bodies of the two snake-woman rows), for the pass's share of the meshing.
#include "bench/bench_util.hpp"
#include "meshers/mesh_plan.hpp"
#include "runtime/scene.hpp"

#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>

#include <filesystem>
#include <memory>
#include <string>

namespace {

using namespace ht;

struct PaperRow {
  const char* scene;
  double seconds;
  double triangles;
};
constexpr PaperRow kTable1[] = {{"snake_woman.json", 79, 164903}, {"winged_bunny.json", 70, 91961},
                                {"bowl.json", 65, 138976},         {"spiky_snake_woman.json", 78, 110713},
                                {"restoration.json", 18, 67589}};

// Arg 0: the row of kTable1; arg 1: threads.
void BM_Table1(benchmark::State& state) {
  const PaperRow& row = kTable1[state.range(0)];
  // The snake-woman rows take seconds each, and every row twice: quick mode (2 cores, a minute
  // for everything) skips the snake-woman rows and runs the others on 2 threads only.
  if (bench::quick_mode && (std::string(row.scene).find("snake") != std::string::npos || state.range(1) == 1)) {
    state.SkipWithError((std::string(row.scene) + ": skipped in quick mode").c_str());
    return;
  }
  const auto file = std::filesystem::path(HYBRIDTREE_SOURCE_DIR) / "examples" / row.scene;
  std::unique_ptr<Tree> tree;
  try {
    tree = std::make_unique<Tree>(load_scene(file));
  } catch (const std::exception& e) {
    state.SkipWithError((std::string(row.scene) + ": " + e.what()).c_str());
    return;
  }
  MeshOptions o;
  o.precision = tree->mesher_settings().precision;
  std::size_t triangles = 0;
  double pass = 0.0;  // the quality pass inside the run's global polygonizations, seconds
  tbb::task_arena arena(static_cast<int>(state.range(1)));
  for (auto _ : state)
    arena.execute([&] {
      const MeshResult r = mesh_tree(*tree, o);
      triangles = r.mesh->triangles.size();
      pass = 0.0;
      for (const NodeReport& n : r.nodes) pass += n.polygonize.quality.seconds;
    });
  state.SetLabel(row.scene);
  state.counters["triangles"] = static_cast<double>(triangles);
  state.counters["paper_triangles"] = row.triangles;
  state.counters["paper_s"] = row.seconds;
  // Issue 9's cost target reads the pass against the rest of the meshing: quality_s / (the
  // row's time - quality_s). Slabs and bands run in parallel, so at 2 threads quality_s is
  // their wall time, like the row's. The local strategies' seam polish is not counted here.
  state.counters["quality_s"] = pass;
}
BENCHMARK(BM_Table1)
    ->ArgsProduct({{0, 1, 2, 3, 4}, {1, 2}})
    ->ArgNames({"figure_row", "threads"})
    ->UseRealTime()
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);

}  // namespace
