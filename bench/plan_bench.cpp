// The mesh plan (meshers/mesh_plan.hpp) against global polygonization, on the scenes:
//   BunnyEarBlend     bunny00 blended with a small sphere at one ear: local vs global at the
//                     same precision (the local result keeps the untouched bunny triangles)
//   WingedBunny       bunny00 blended with wings cropped out of armadillo (the paper's Figure 7,
//                     70 s for 91,961 triangles in its Table 1), at 1 and 2 threads
//   FourBunnies       four independent subtrees (each a bunny blended with a sphere) under one
//                     blend: the flow graph runs them side by side, 1 vs 2 threads
// Counters: triangles, and seconds per run as real time. Ratios are what to read: local/global
// in one run, 2 threads / 1 thread in one run.
#include "bench/bench_util.hpp"
#include "meshers/mesh_plan.hpp"
#include "nodes/mesh_leaf.hpp"
#include "runtime/builder.hpp"

#include <benchmark/benchmark.h>
#include <glm/gtc/matrix_transform.hpp>
#include <tbb/task_arena.h>

#include <map>
#include <string>

namespace {

using namespace ht;

std::shared_ptr<const MeshLeaf> leaf(const char* name) {
  static std::map<std::string, std::shared_ptr<const MeshLeaf>> cache;
  auto& l = cache[name];
  if (!l) l = MeshLeaf::load(bench::cgal_mesh(name));
  return l;
}

void run(benchmark::State& state, const Tree& tree, double h, MeshStrategy strategy, int threads) {
  MeshOptions o;
  o.precision = h;
  o.strategy = strategy;
  std::size_t triangles = 0;
  bool fallback = false;
  tbb::task_arena arena(threads);
  for (auto _ : state)
    arena.execute([&] {
      const MeshResult r = mesh_tree(tree, o);
      triangles = r.mesh->triangles.size();
      for (const NodeReport& n : r.nodes) fallback |= n.reason == JobReason::Fallback;
    });
  state.counters["triangles"] = static_cast<double>(triangles);
  state.counters["fallbacks"] = fallback ? 1 : 0;
}

// bunny00's ear tip is near (-0.005, 0.494, -0.12).
NodeId bunny_with_sphere(Builder& b, const glm::dvec3& shift) {
  const NodeId bunny = b.affine(b.mesh(leaf("bunny00.off"), {0.05}), glm::translate(glm::dmat4(1.0), shift));
  return b.blend({bunny, b.point(shift + glm::dvec3(-0.005, 0.5, -0.12), {0.12})});
}

// Args: strategy (0 auto, 1 global), threads. Precision 0.005 (0.01 in quick mode).
void BM_BunnyEarBlend(benchmark::State& state) {
  static Builder b(0.5);
  static const Tree tree = b.build(b.blend({b.mesh(leaf("bunny00.off"), {0.05}), b.point({-0.005, 0.5, -0.12}, {0.12})}));
  run(state, tree, bench::precision(0.005), state.range(0) ? MeshStrategy::Global : MeshStrategy::Auto, int(state.range(1)));
}
BENCHMARK(BM_BunnyEarBlend)->ArgsProduct({{0, 1}, {2}})->ArgNames({"global", "threads"})->UseRealTime()->Unit(benchmark::kMillisecond);

// The wings: armadillo scaled to the bunny's size, cut to the slab of its spread arms, turned
// and set on the bunny's back (examples/winged_bunny.json is the same scene).
Tree winged_bunny(Builder& b) {
  const NodeId armadillo = b.affine(b.mesh(leaf("armadillo.off"), {6.0}), glm::scale(glm::dmat4(1.0), glm::dvec3(0.005)));
  const NodeId wings = b.crop(armadillo, {-1, 0.25, -1}, {1, 0.42, 1});
  glm::dmat4 place = glm::translate(glm::dmat4(1.0), glm::dvec3(0.2, -0.22, 0.1));
  place = glm::rotate(place, glm::radians(90.0), glm::dvec3(0, 1, 0));
  return b.build(b.blend({b.mesh(leaf("bunny00.off"), {0.03}), b.affine(wings, place)}));
}

// Args: strategy (0 auto, 1 global), threads. Precision 0.008 (about the paper's triangle count).
void BM_WingedBunny(benchmark::State& state) {
  static Builder b(0.5);
  static const Tree tree = winged_bunny(b);
  // The global run takes seconds: quick mode (2 cores, a minute for everything) skips it.
  if (bench::quick_mode && state.range(0) != 0) {
    state.SkipWithError("global: skipped in quick mode");
    return;
  }
  run(state, tree, 0.008, state.range(0) ? MeshStrategy::Global : MeshStrategy::Auto, int(state.range(1)));
  state.counters["paper_seconds"] = 70.0;
  state.counters["paper_triangles"] = 91961.0;
}
BENCHMARK(BM_WingedBunny)
    ->ArgsProduct({{0}, {1, 2}})
    ->Args({1, 2})
    ->ArgNames({"global", "threads"})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

// Args: threads.
void BM_FourBunnies(benchmark::State& state) {
  static Builder b(0.5);
  static const Tree tree = [] {
    std::vector<NodeId> parts;
    for (int i = 0; i < 4; ++i) parts.push_back(bunny_with_sphere(b, glm::dvec3(1.5 * i, 0, 0)));
    return b.build(b.blend(parts));
  }();
  run(state, tree, 0.006, MeshStrategy::Auto, int(state.range(0)));
}
BENCHMARK(BM_FourBunnies)->Arg(1)->Arg(2)->ArgNames({"threads"})->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace
