// The tape against the reference tree evaluator, points per second with 1 and 2 threads, on
// the 250-curve snake, a tree of every node kind, and bunny00 blended with primitives; and the
// cost of a specialized tape (5 of 10,000 primitives left) against a 5-primitive scene.
#include "bench/bench_util.hpp"
#include "nodes/mesh_leaf.hpp"
#include "runtime/builder.hpp"
#include "runtime/tape.hpp"
#include "runtime/tape_eval.hpp"
#include "tools/scenes.hpp"

#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>

#include <random>

namespace {

using namespace ht;

struct Scene {
  Tree tree;
  std::vector<glm::dvec3> points;
};

std::vector<glm::dvec3> points_in(const Aabb& box, std::size_t count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<glm::dvec3> out(count);
  for (auto& p : out) p = box.lo + glm::dvec3(u(rng), u(rng), u(rng)) * box.size();
  return out;
}

Scene make_scene(int which) {
  Builder b(0.5);
  NodeId root;
  if (which == 0) {
    root = scenes::snake(b, 250);
  } else if (which == 1) {
    root = scenes::every_kind(b, MeshLeaf::load(bench::cgal_mesh("eight.off")));
  } else {
    root = scenes::mesh_with_primitives(b, MeshLeaf::load(bench::cgal_mesh("bunny00.off")));
  }
  Tree tree = b.build(root);
  const Aabb box = tree.graph().support(root, false);
  const std::size_t n = bench::quick_mode ? 4096 : 16384;
  return {tree, points_in(box.finite() ? box : Aabb{glm::dvec3(-2), glm::dvec3(2)}, n, 9)};
}

const Scene& scene(int which) {
  static const Scene scenes_[3] = {make_scene(0), make_scene(1), make_scene(2)};
  return scenes_[which];
}

const char* kNames[] = {"snake250", "every_kind", "bunny00_blend"};

// Args: scene, threads.
void BM_Tape(benchmark::State& state) {
  const Scene& s = scene(static_cast<int>(state.range(0)));
  const TapeEvaluator& eval = s.tree.evaluator();
  std::vector<double> values(s.points.size());
  tbb::task_arena arena(static_cast<int>(state.range(1)));
  for (auto _ : state) arena.execute([&] { eval.field(s.points, values); });
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * s.points.size()));
  state.SetLabel(kNames[state.range(0)]);
  state.counters["instructions"] = static_cast<double>(eval.tape().size());
}
BENCHMARK(BM_Tape)->ArgsProduct({{0, 1, 2}, {1, 2}})->ArgNames({"scene", "threads"})->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_Tree(benchmark::State& state) {
  const Scene& s = scene(static_cast<int>(state.range(0)));
  const std::span<const glm::dvec3> pts(s.points);
  std::vector<double> values(pts.size());
  tbb::task_arena arena(static_cast<int>(state.range(1)));
  for (auto _ : state) arena.execute([&] { s.tree.reference(pts, values); });
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * pts.size()));
  state.SetLabel(kNames[state.range(0)]);
}
BENCHMARK(BM_Tree)->ArgsProduct({{0, 1, 2}, {1, 2}})->ArgNames({"scene", "threads"})->UseRealTime()->Unit(benchmark::kMillisecond);

// Region specialization: a 10,000-point grid specialized to a box touching 5 supports, against
// a scene of just those 5 primitives; same points, one thread.
void BM_Specialized(benchmark::State& state) {
  static Builder b(0.5);
  static const NodeId grid = scenes::point_grid(b, 10000);
  static const NodeId five = [] {
    std::vector<NodeId> p;
    for (int i = 0; i < 5; ++i) p.push_back(b.point({i, 0, 0}, {0.6, 1.0}));
    return b.blend(p);
  }();
  static const Tree tree = b.build(grid);
  const Aabb region{{0.0, -0.3, -0.3}, {4.0, 0.3, 0.3}};  // supports of (0..4, 0, 0) only
  const bool specialized = state.range(0) == 1;
  const auto tape = std::make_shared<const Tape>(specialized ? compile_tape(tree.graph_ptr(), grid, 0.5, &region)
                                                             : compile_tape(tree.graph_ptr(), five, 0.5));
  const TapeEvaluator eval(tape);
  const auto pts = points_in(region, 65536, 10);
  std::vector<float> x(pts.size()), y(pts.size()), z(pts.size()), v(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    x[i] = static_cast<float>(pts[i].x);
    y[i] = static_cast<float>(pts[i].y);
    z[i] = static_cast<float>(pts[i].z);
  }
  tbb::task_arena arena(1);
  for (auto _ : state) arena.execute([&] { eval.field(x.data(), y.data(), z.data(), pts.size(), v.data()); });
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * pts.size()));
  state.SetLabel(specialized ? "10000 grid specialized" : "5-primitive scene");
  state.counters["leaves"] = static_cast<double>(tape->leaf_count());
}
BENCHMARK(BM_Specialized)->Arg(0)->Arg(1)->ArgName("specialized")->UseRealTime()->Unit(benchmark::kMicrosecond);

// The compile itself: a full 10,000-primitive tape and a region-specialized one.
void BM_Compile(benchmark::State& state) {
  static Builder b(0.5);
  static const NodeId grid = scenes::point_grid(b, 10000);
  static const Tree tree = b.build(grid);
  const Aabb region{{0.0, -0.3, -0.3}, {4.0, 0.3, 0.3}};
  for (auto _ : state)
    benchmark::DoNotOptimize(compile_tape(tree.graph_ptr(), grid, 0.5, state.range(0) ? &region : nullptr));
}
BENCHMARK(BM_Compile)->Arg(0)->Arg(1)->ArgName("specialized")->Unit(benchmark::kMillisecond);

}  // namespace
