// Mesh-leaf field queries through the reference evaluator (double, one Embree point query per
// point): bunny00 at points within its support radius; 1 and 2 threads (TBB arenas).
#include "bench/bench_util.hpp"
#include "nodes/mesh_leaf.hpp"
#include "runtime/builder.hpp"

#include <benchmark/benchmark.h>
#include <glm/geometric.hpp>
#include <tbb/task_arena.h>

#include <random>

namespace {

using namespace ht;

// Points within the support: a random vertex, moved by a random offset shorter than R.
std::vector<glm::dvec3> near_surface(const MeshLeaf& m, double R, std::size_t count) {
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<std::size_t> vertex(0, m.positions().size() - 1);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<glm::dvec3> pts;
  while (pts.size() < count) {
    const glm::dvec3 d(u(rng), u(rng), u(rng));
    if (glm::length(d) > 1) continue;
    pts.push_back(m.positions()[vertex(rng)] + R * d);
  }
  return pts;
}

void run(benchmark::State& state, const Tree& tree, const std::vector<glm::dvec3>& pts) {
  std::vector<double> values(pts.size());
  tbb::task_arena arena(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    arena.execute([&] { tree.reference(pts, values); });
    benchmark::DoNotOptimize(values.data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * pts.size()));
}

// Args: threads, support radius R in thousandths of the mesh's bounding-box diagonal. Points
// are uniform in balls of radius R about random vertices, in random order (no coherence).
void BM_Reference_Bunny00(benchmark::State& state) {
  static const auto leaf = MeshLeaf::load(bench::cgal_mesh("bunny00.off"));
  const double R = 1e-3 * static_cast<double>(state.range(1)) * glm::length(leaf->bounds().size());
  Builder b(0.5);
  const Tree tree = b.build(b.mesh(leaf, {R, 1.0}));
  const auto pts = near_surface(*leaf, R, bench::quick_mode ? 20000 : 200000);
  run(state, tree, pts);
}
BENCHMARK(BM_Reference_Bunny00)
    ->ArgsProduct({{1, 2}, {10, 20}})
    ->ArgNames({"threads", "R_permille"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
