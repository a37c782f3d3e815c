// Global polygonization: the 250-curve snake near the paper's 121,524 triangles (9 s on a
// Pentium IV in the paper), the same at half the precision (the time should grow about 4x, with
// the surface's area, not 8x with the volume), bunny00 through a mesh leaf, and a scene of sharp
// creases with and without the feature step (meshers/features.hpp). 2 threads.
#include "bench/bench_util.hpp"
#include "meshers/polygonize.hpp"
#include "nodes/mesh_leaf.hpp"
#include "runtime/builder.hpp"
#include "tools/scenes.hpp"

#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>

namespace {

using namespace ht;

void run(benchmark::State& state, const Tree& tree, double h, bool sharp = true, bool quality = true) {
  PolygonizeOptions o;
  o.precision = h;
  o.sharp_features = sharp;
  o.quality.enabled = quality;
  std::size_t triangles = 0;
  PolygonizeStats stats;
  tbb::task_arena arena(static_cast<int>(state.range(1)));
  for (auto _ : state) arena.execute([&] { triangles = polygonize(tree.graph_ptr(), tree.root(), 0.5, o, &stats).triangles.size(); });
  state.counters["triangles"] = static_cast<double>(triangles);
  state.counters["bricks"] = static_cast<double>(stats.bricks_active);
  state.counters["crease_edges"] = static_cast<double>(stats.crease_edges);
  state.counters["quality_s"] = stats.quality.seconds;
  state.counters["tri_per_s"] = benchmark::Counter(static_cast<double>(triangles) * double(state.iterations()),
                                                   benchmark::Counter::kIsRate);
}

// Args: precision in 1/10000 units, threads.
void BM_MeshSnake(benchmark::State& state) {
  static Builder b(0.5);
  static const Tree tree = b.build(scenes::snake(b, 250));
  // Half the precision takes seconds: quick mode (2 cores, a minute for everything) skips it.
  if (bench::quick_mode && state.range(0) < 650) {
    state.SkipWithError("h = 0.0325: skipped in quick mode");
    return;
  }
  run(state, tree, 1e-4 * static_cast<double>(state.range(0)));
}
BENCHMARK(BM_MeshSnake)
    ->ArgsProduct({{650, 325}, {1, 2}})
    ->ArgNames({"h_e4", "threads"})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

// The quality pass's cost (meshers/quality.hpp): the snake at h = 0.065 with it (1) and without
// (0). Args: quality, threads.
void BM_MeshSnakeQuality(benchmark::State& state) {
  static Builder b(0.5);
  static const Tree tree = b.build(scenes::snake(b, 250));
  run(state, tree, 0.065, true, state.range(0) != 0);
}
BENCHMARK(BM_MeshSnakeQuality)
    ->ArgsProduct({{0, 1}, {1, 2}})
    ->ArgNames({"quality", "threads"})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

void BM_MeshBunny00(benchmark::State& state) {
  static Builder b(0.5);
  static const Tree tree = b.build(b.mesh(MeshLeaf::load(bench::cgal_mesh("bunny00.off")), {0.03}));
  run(state, tree, 1e-4 * static_cast<double>(state.range(0)));
}
BENCHMARK(BM_MeshBunny00)->ArgsProduct({{100}, {2}})->ArgNames({"h_e4", "threads"})->UseRealTime()->Unit(benchmark::kMillisecond);

// A sphere cut by a box with eight spheres carved out of it (min/max): creases and corners.
// Args: precision in 1/10000 units, threads, sharp features on (1) or off (0).
void BM_MeshCreases(benchmark::State& state) {
  static Builder b(0.5);
  static const Tree tree = [] {
    std::vector<NodeId> holes;
    for (int i = 0; i < 8; ++i)
      holes.push_back(b.point({0.5 * ((i & 1) ? 1 : -1), 0.45 * ((i & 2) ? 1 : -1), 0.4 * ((i & 4) ? 1 : -1)}, {0.6}));
    const NodeId body = b.crop(b.point({0, 0, 0}, {1.6}), {-0.55, -0.5, -0.45}, {0.55, 0.5, 0.45});
    holes.insert(holes.begin(), body);
    return b.build(b.subtract(holes, BooleanMode::MinMax));
  }();
  run(state, tree, 1e-4 * static_cast<double>(state.range(0)), state.range(2) != 0);
}
BENCHMARK(BM_MeshCreases)
    ->ArgsProduct({{100}, {2}, {0, 1}})
    ->ArgNames({"h_e4", "threads", "sharp"})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace
