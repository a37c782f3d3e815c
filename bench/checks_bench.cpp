// The self-intersection search (meshers/self_intersections.hpp), which every global
// polygonization runs after its quality pass and the mesh checks run on every output: the
// 250-curve snake's mesh at h = 0.065 (81k well-shaped triangles) and bunny00 as scanned (75k,
// with the scan's own slivers). Args: threads.
#include "bench/bench_util.hpp"
#include "meshers/polygonize.hpp"
#include "meshers/self_intersections.hpp"
#include "nodes/mesh_leaf.hpp"
#include "runtime/builder.hpp"
#include "tools/scenes.hpp"

#include <benchmark/benchmark.h>
#include <tbb/task_arena.h>

namespace {

using namespace ht;

void search(benchmark::State& state, const TriangleMesh& mesh) {
  tbb::task_arena arena(static_cast<int>(state.range(0)));
  std::size_t pairs = 0;
  for (auto _ : state) arena.execute([&] { pairs = find_self_intersections(mesh).pairs; });
  state.counters["triangles"] = static_cast<double>(mesh.triangles.size());
  state.counters["pairs"] = static_cast<double>(pairs);
}

void BM_SelfIntersectionsSnake(benchmark::State& state) {
  static const TriangleMesh mesh = [] {
    Builder b(0.5);
    const Tree tree = b.build(scenes::snake(b, 250));
    PolygonizeOptions o;
    o.precision = 0.065;
    return polygonize(tree.graph_ptr(), tree.root(), 0.5, o);
  }();
  search(state, mesh);
}
BENCHMARK(BM_SelfIntersectionsSnake)->Arg(1)->Arg(2)->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_SelfIntersectionsBunny00(benchmark::State& state) {
  static const std::shared_ptr<const MeshLeaf> leaf = MeshLeaf::load(bench::cgal_mesh("bunny00.off"));
  search(state, *leaf->surface());
}
BENCHMARK(BM_SelfIntersectionsBunny00)->Arg(1)->Arg(2)->ArgName("threads")->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace
