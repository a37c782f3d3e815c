// The optimizer (runtime/optimize.hpp) on the scene it is for: 900 small primitives scattered in
// space, written as a left-deep chain of binary blends in random order (tools/scenes.hpp scatter).
//   OptimizeScatter        the optimizer itself
//   ScatterEval/opt        the field at 2^20 random points in the scene's box (2^16 in quick
//                          mode), one thread, as written (opt 0) and optimized (opt 1)
//   ScatterMesh/opt/quality  global polygonization at h = 0.1 (0.2 in quick mode), one thread,
//                          without and with the quality pass (meshers/quality.hpp)
// Counters: instructions of the tape, and triangles. Read the ratios opt 0 / opt 1 of one run.
#include "bench/bench_util.hpp"
#include "meshers/mesh_plan.hpp"
#include "runtime/builder.hpp"
#include "runtime/optimize.hpp"
#include "runtime/tape_eval.hpp"
#include "tools/scenes.hpp"

#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>

#include <random>

namespace {

using namespace ht;

const Tree& scatter_tree(bool optimized) {
  static Builder b(0.5);
  static const Tree written = b.build(scenes::scatter(b, 900, 1));
  static const Tree best = optimize(written);
  return optimized ? best : written;
}

void BM_OptimizeScatter(benchmark::State& state) {
  const Tree& tree = scatter_tree(false);
  OptimizeStats s;
  for (auto _ : state) benchmark::DoNotOptimize(optimize(tree, {}, &s));
  state.counters["nodes_before"] = double(s.nodes_before);
  state.counters["nodes_after"] = double(s.nodes_after);
  state.counters["tape_before"] = double(s.tape_before);
  state.counters["tape_after"] = double(s.tape_after);
}
BENCHMARK(BM_OptimizeScatter)->Unit(benchmark::kMillisecond);

void BM_ScatterEval(benchmark::State& state) {
  const Tree& tree = scatter_tree(state.range(0) != 0);
  const std::size_t n = bench::quick_mode ? (1u << 16) : (1u << 20);
  const Aabb box = tree.graph().support(tree.root(), false);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<glm::dvec3> pts(n);
  for (auto& p : pts) p = box.lo + glm::dvec3(u(rng), u(rng), u(rng)) * box.size();
  std::vector<double> values(n);
  tbb::task_arena arena(1);
  tree.evaluator();
  for (auto _ : state) arena.execute([&] { tree.field(pts, values); });
  state.counters["instructions"] = double(tree.evaluator().tape().size());
  state.counters["points_per_s"] = benchmark::Counter(double(n), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_ScatterEval)->ArgName("opt")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_ScatterMesh(benchmark::State& state) {
  // The quality pass on the tree as written repeats what opt 1 shows about the pass and takes
  // seconds: quick mode (2 cores, a minute for everything) skips it.
  if (bench::quick_mode && state.range(0) == 0 && state.range(1) != 0) {
    state.SkipWithError("as written with the quality pass: skipped in quick mode");
    return;
  }
  const Tree& tree = scatter_tree(state.range(0) != 0);
  MeshOptions o;
  o.precision = bench::quick_mode ? 0.2 : 0.1;
  o.strategy = MeshStrategy::Global;
  o.polygonize.quality.enabled = state.range(1) != 0;
  std::size_t triangles = 0;
  tbb::task_arena arena(1);
  for (auto _ : state) arena.execute([&] { triangles = mesh_tree(tree, o).mesh->triangles.size(); });
  state.counters["triangles"] = double(triangles);
}
BENCHMARK(BM_ScatterMesh)->ArgNames({"opt", "quality"})->ArgsProduct({{0, 1}, {0, 1}})->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
