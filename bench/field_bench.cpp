// Mesh-leaf field queries through the reference evaluator (double, one Embree point query per
// point): bunny00 at points within its support radius; 1 and 2 threads (TBB arenas). Winding
// numbers (nodes/winding.hpp) on bunny00 with holes, one thread: the exact sum, the
// hierarchical estimate, and the exact-where-it-matters inside test. Mesh-leaf queries in
// brick-shaped blocks, point by point and batched.
#include "bench/bench_util.hpp"
#include "nodes/mesh_leaf.hpp"
#include "nodes/winding.hpp"
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

// Arg: 0 exact sum, 1 hierarchical estimate (tau = WindingTree::kTau), 2 inside() (certified,
// refined near the 1/2 level set). Points uniform in the mesh's box grown by a quarter of its
// diagonal (near 0), or within 1/200 of the diagonal of a vertex (near 1); bunny00 with every
// 50th triangle removed (open, 1.3k holes).
void BM_Winding_Bunny00(benchmark::State& state) {
  static const auto leaf = MeshLeaf::load(bench::cgal_mesh("bunny00.off"));
  static const WindingTree tree = [] {
    std::vector<glm::uvec3> tris;
    for (std::size_t t = 0; t < leaf->triangles().size(); ++t)
      if (t % 50 != 0) tris.push_back(leaf->triangles()[t]);
    return WindingTree(leaf->positions(), tris);
  }();
  const Aabb box = leaf->bounds().expanded(0.25 * glm::length(leaf->bounds().size()));
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  const std::size_t count = state.range(0) == 0 ? (bench::quick_mode ? 20 : 200) : (bench::quick_mode ? 2000 : 20000);
  std::vector<glm::dvec3> pts(count);
  for (auto& p : pts) p = box.lo + glm::dvec3(u(rng), u(rng), u(rng)) * box.size();
  if (state.range(1) == 1) {  // near the surface: vertices moved by up to 1/200 of the diagonal
    const double r = 0.005 * glm::length(leaf->bounds().size());
    for (auto& p : pts)
      p = leaf->positions()[static_cast<std::size_t>(u(rng) * 0.999 * static_cast<double>(leaf->positions().size()))] +
          r * (glm::dvec3(u(rng), u(rng), u(rng)) * 2.0 - 1.0);
  }
  for (auto _ : state) {
    double sum = 0;
    for (const auto& p : pts)
      sum += state.range(0) == 0   ? tree.exact(p)
             : state.range(0) == 1 ? tree.estimate(p, 0.0, WindingTree::kTau).w
                                   : (tree.inside(p) ? 1.0 : 0.0);
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * pts.size()));
}
BENCHMARK(BM_Winding_Bunny00)
    ->ArgsProduct({{0, 1, 2}, {0, 1}})
    ->ArgNames({"exact_estimate_inside", "near"})
    ->Unit(benchmark::kMillisecond);

// Mesh-leaf queries in blocks, as the polygonizer's bricks ask them: 8 x 8 x 4 points a cell
// apart (1/100 of the box's diagonal) at every block position of bunny00's box grown by a tenth,
// radius 3 cells. Arg: 0 query() point by point, 1 query_batch() a block at a time (a block the
// radius does not reach answered by one query and one inside test). One thread.
void BM_MeshLeafBlocks(benchmark::State& state) {
  static const auto leaf = MeshLeaf::load(bench::cgal_mesh("bunny00.off"));
  const Aabb box = leaf->bounds().expanded(0.1 * glm::length(leaf->bounds().size()));
  const float h = static_cast<float>(0.01 * glm::length(leaf->bounds().size())), radius = 3.0f * h;
  std::vector<float> xs, ys, zs;  // blocks of 256 consecutive points
  const glm::ivec3 blocks = glm::ivec3(glm::ceil(box.size() / (glm::dvec3(8, 8, 4) * double(h))));
  for (int bz = 0; bz < blocks.z; ++bz)
    for (int by = 0; by < blocks.y; ++by)
      for (int bx = 0; bx < blocks.x; ++bx)
        for (int k = 0; k < 4; ++k)
          for (int j = 0; j < 8; ++j)
            for (int i = 0; i < 8; ++i) {
              xs.push_back(float(box.lo.x) + h * float(8 * bx + i));
              ys.push_back(float(box.lo.y) + h * float(8 * by + j));
              zs.push_back(float(box.lo.z) + h * float(4 * bz + k));
            }
  std::vector<float> d(256);
  std::vector<std::uint8_t> in(256);
  std::size_t inside = 0;
  for (auto _ : state) {
    inside = 0;
    for (std::size_t at = 0; at < xs.size(); at += 256) {
      if (state.range(0) == 1) {
        leaf->query_batch(&xs[at], &ys[at], &zs[at], 256, radius, d.data(), in.data());
      } else {
        for (std::size_t i = 0; i < 256; ++i) {
          const MeshLeaf::Closest c = leaf->query({xs[at + i], ys[at + i], zs[at + i]}, double(radius));
          in[i] = c.inside ? 1 : 0;
        }
      }
      for (std::uint8_t f : in) inside += f;
    }
    benchmark::DoNotOptimize(inside);
  }
  state.counters["inside"] = static_cast<double>(inside);
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * xs.size()));
}
BENCHMARK(BM_MeshLeafBlocks)->Arg(0)->Arg(1)->ArgNames({"batch"})->Unit(benchmark::kMillisecond);

}  // namespace
