// The tape against the reference tree evaluator, points per second with 1 and 2 threads, on
// the 250-curve snake, a tree of every node kind, and bunny00 blended with primitives; the tape
// against a hand-written loop for the snake; which build the dispatch picked; and the cost of a
// specialized tape (5 of 10,000 primitives left) against a 5-primitive scene.
#include "bench/bench_util.hpp"
#include "nodes/mesh_leaf.hpp"
#include "nodes/primitives.hpp"
#include "runtime/builder.hpp"
#include "runtime/tape.hpp"
#include "runtime/tape_eval.hpp"
#include "tools/scenes.hpp"

#include <benchmark/benchmark.h>
#include <glm/geometric.hpp>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>

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

// Values with gradients (forward mode), one thread. Args: scene.
void BM_TapeGradient(benchmark::State& state) {
  const Scene& s = scene(static_cast<int>(state.range(0)));
  const TapeEvaluator& eval = s.tree.evaluator();
  std::vector<double> values(s.points.size());
  std::vector<glm::dvec3> gradients(s.points.size());
  tbb::task_arena arena(1);
  for (auto _ : state) arena.execute([&] { eval.gradient(s.points, values, gradients); });
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * s.points.size()));
  state.SetLabel(std::string(kNames[state.range(0)]) + " isa=" + tape_isa_name(tape_isa()));
}
BENCHMARK(BM_TapeGradient)->Arg(0)->Arg(1)->ArgName("scene")->UseRealTime()->Unit(benchmark::kMillisecond);

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

// The snake's field written by hand, as one would without a tape: for each point, the sum over
// the curves whose support box holds it of F (1 - d^2/R^2)^3, d the distance to the curve's
// polyline; in float, from the constants the tape compiler computes (in double, then rounded).
struct HandCurve {
  float lo[3], hi[3];  // the support: the polyline's box grown by R
  float inv_r2, F;
  std::vector<float> segments;  // per segment: a(3), b - a (3), 1/|b - a|^2
};

std::vector<HandCurve> hand_curves(const Tree& tree) {
  const Graph& g = tree.graph();
  std::vector<HandCurve> out;
  for (NodeId n : g.children_of(tree.root())) {
    if (g.kind[n] != NodeKind::Curve) throw std::logic_error("the snake is a blend of curves");
    const double R = g.params_of(n)[kPrimR];
    const double* s = g.skeleton_of(n);  // m, then m polyline points
    const auto m = static_cast<std::size_t>(s[0]);
    auto point = [&](std::size_t i) { return glm::dvec3(s[1 + 3 * i], s[2 + 3 * i], s[3 + 3 * i]); };
    HandCurve c{};
    c.inv_r2 = static_cast<float>(1.0 / (R * R));
    c.F = static_cast<float>(g.params_of(n)[kPrimF]);
    Aabb box;
    for (std::size_t i = 0; i < m; ++i) box.grow(point(i));
    box = box.expanded(R);
    for (int j = 0; j < 3; ++j) {
      c.lo[j] = static_cast<float>(box.lo[j]);
      c.hi[j] = static_cast<float>(box.hi[j]);
    }
    for (std::size_t i = 0; i + 1 < m; ++i) {
      const glm::dvec3 a = point(i), ab = point(i + 1) - a;
      const double len2 = glm::dot(ab, ab);
      for (double v : {a.x, a.y, a.z, ab.x, ab.y, ab.z, len2 > 0 ? 1.0 / len2 : 0.0})
        c.segments.push_back(static_cast<float>(v));
    }
    out.push_back(std::move(c));
  }
  return out;
}

void hand_loop(const std::vector<HandCurve>& curves, const float* x, const float* y, const float* z, std::size_t n,
               float* out) {
  for (std::size_t i = 0; i < n; ++i) {
    float sum = 0.0f;
    for (const HandCurve& c : curves) {
      if (x[i] < c.lo[0] || y[i] < c.lo[1] || z[i] < c.lo[2] || x[i] > c.hi[0] || y[i] > c.hi[1] || z[i] > c.hi[2])
        continue;
      float best = std::numeric_limits<float>::max();
      for (std::size_t k = 0; k < c.segments.size(); k += 7) {
        const float* s = c.segments.data() + k;
        const float px = x[i] - s[0], py = y[i] - s[1], pz = z[i] - s[2];
        const float t = std::clamp((px * s[3] + py * s[4] + pz * s[5]) * s[6], 0.0f, 1.0f);
        const float dx = px - t * s[3], dy = py - t * s[4], dz = pz - t * s[5];
        best = std::min(best, dx * dx + dy * dy + dz * dz);
      }
      const float u = 1.0f - best * c.inv_r2;
      if (u > 0.0f) sum += u * u * u * c.F;
    }
    out[i] = sum;
  }
}

// The hand loop timed against the tape, both on one thread at the snake's points; the counter
// tape_speedup is loop time / tape time (best passes) on the build the dispatch picks, and
// tape_speedup_<isa> the same on every build the CPU runs. Refuses to report if they disagree.
void BM_HandLoop(benchmark::State& state) {
  const Scene& s = scene(0);
  const std::vector<HandCurve> curves = hand_curves(s.tree);
  const std::size_t n = s.points.size();
  std::vector<float> x(n), y(n), z(n), hand(n), taped(n);
  for (std::size_t i = 0; i < n; ++i) {
    x[i] = static_cast<float>(s.points[i].x);
    y[i] = static_cast<float>(s.points[i].y);
    z[i] = static_cast<float>(s.points[i].z);
  }
  using clock = std::chrono::steady_clock;
  auto seconds = [](clock::time_point t0) { return std::chrono::duration<double>(clock::now() - t0).count(); };
  const TapeEvaluator& eval = s.tree.evaluator();
  tbb::task_arena arena(1);
  // The tape on each build this CPU runs (runtime/tape_eval.hpp TapeIsa), the default last.
  const TapeIsa chosen = tape_isa();
  std::vector<std::pair<TapeIsa, double>> builds;
  for (const TapeIsa isa : {TapeIsa::Baseline, TapeIsa::Sse4, TapeIsa::Avx2, TapeIsa::Avx512})
    if (tape_isa_supported(isa) && isa != chosen) builds.push_back({isa, 0.0});
  builds.push_back({chosen, 0.0});
  for (auto& [isa, best] : builds) {
    force_tape_isa(isa);
    best = std::numeric_limits<double>::infinity();
    for (int pass = 0; pass < 5; ++pass) {
      const auto t0 = clock::now();
      arena.execute([&] { eval.field(x.data(), y.data(), z.data(), n, taped.data()); });
      best = std::min(best, seconds(t0));
    }
  }
  double tape_s = builds.back().second, loop_s = std::numeric_limits<double>::infinity(), diff = 0.0;
  hand_loop(curves, x.data(), y.data(), z.data(), n, hand.data());
  for (std::size_t i = 0; i < n; ++i) diff = std::max(diff, double(std::abs(hand[i] - taped[i])));
  if (diff > 1e-5) {
    state.SkipWithError(("the hand loop differs from the tape by " + std::to_string(diff)).c_str());
    return;
  }
  for (auto _ : state) {
    const auto t0 = clock::now();
    hand_loop(curves, x.data(), y.data(), z.data(), n, hand.data());
    benchmark::DoNotOptimize(hand.data());
    loop_s = std::min(loop_s, seconds(t0));
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * n));
  state.SetLabel("snake250, 1 thread, hand loop vs tape");
  state.counters["loop_pts_per_s"] = double(n) / loop_s;
  state.counters["tape_pts_per_s"] = double(n) / tape_s;
  state.counters["tape_speedup"] = loop_s / tape_s;
  for (const auto& [isa, best] : builds) state.counters[std::string("tape_speedup_") + tape_isa_name(isa)] = loop_s / best;
  state.counters["max_abs_diff"] = diff;
}
BENCHMARK(BM_HandLoop)->UseRealTime()->Unit(benchmark::kMillisecond);

// Which build of the value path the run-time dispatch picked on this CPU, and the instruction
// size (the tape streams through L1 once per block), timed on one block of the snake.
void BM_TapeDispatch(benchmark::State& state) {
  const Scene& s = scene(0);
  const TapeEvaluator& eval = s.tree.evaluator();
  std::vector<float> x(kBlock), y(kBlock), z(kBlock), v(kBlock);
  for (int i = 0; i < kBlock; ++i) {
    x[std::size_t(i)] = static_cast<float>(s.points[std::size_t(i)].x);
    y[std::size_t(i)] = static_cast<float>(s.points[std::size_t(i)].y);
    z[std::size_t(i)] = static_cast<float>(s.points[std::size_t(i)].z);
  }
  for (auto _ : state) {
    eval.field_block(x.data(), y.data(), z.data(), kBlock, v.data());
    benchmark::DoNotOptimize(v.data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * kBlock));
  state.SetLabel(std::string("isa=") + tape_isa_name(tape_isa()) + " instruction=" + std::to_string(sizeof(Instruction)) + "B");
  state.counters["bytes_per_instruction"] = static_cast<double>(sizeof(Instruction));
  state.counters["tape_bytes"] = static_cast<double>(eval.tape().bytes());
}
BENCHMARK(BM_TapeDispatch)->Unit(benchmark::kMicrosecond);

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
