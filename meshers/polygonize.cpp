// Sparse marching tetrahedra over interval-pruned bricks; see meshers/polygonize.hpp. The
// per-brick extraction is meshers/brick_extract.hpp. Reference: interval pruning of implicit
// surfaces (Duff 1992, libfive).
#include "meshers/polygonize.hpp"

#include "meshers/brick_extract.hpp"
#include "meshers/batch_field.hpp"
#include "meshers/brick_join.hpp"
#include "meshers/brick_region.hpp"
#include "meshers/features.hpp"
#include "meshers/piece_cache.hpp"
#include "meshers/polygonize_passes.hpp"
#include "meshers/polygonize_reuse.hpp"
#include "meshers/quality.hpp"
#include "meshers/snap.hpp"
#include "meshers/surface_field.hpp"
#include "meshers/triangle_shape.hpp"

#include "runtime/tape.hpp"
#include "runtime/tape_eval.hpp"

#include <glm/geometric.hpp>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <numeric>
#include <string>
#include <vector>

namespace ht {
namespace {

using brick::BrickOutput;
using brick::EdgeVertex;
using brick::Grid;
using brick::kBrickPoints;
using brick::kCells;
using brick::kPoints;
using brick::kActive;
using brick::kInside;
using brick::kOutside;

constexpr double kSnap = 0.01;     // of a grid edge: a vertex this near a grid point merges there

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Interval classification of brick ranges: split the longest side until one brick remains.
void classify(const Graph& g, NodeId root, double T, const Grid& grid, glm::ivec3 lo, glm::ivec3 hi,
              std::vector<std::uint8_t>& state) {
  const Interval iv = field_interval(g, root, T, grid.box(lo, hi), false);
  const bool decided = iv.hi < T || iv.lo >= T;
  const glm::ivec3 size = hi - lo;
  if (decided || (size.x == 1 && size.y == 1 && size.z == 1)) {
    const std::uint8_t s = iv.hi < T ? kOutside : iv.lo >= T ? kInside : kActive;
    for (int z = lo.z; z < hi.z; ++z)
      for (int y = lo.y; y < hi.y; ++y)
        for (int x = lo.x; x < hi.x; ++x) state[grid.brick_index({x, y, z})] = s;
    return;
  }
  const int axis = size.x >= size.y && size.x >= size.z ? 0 : size.y >= size.z ? 1 : 2;
  glm::ivec3 mid_hi = hi, mid_lo = lo;
  mid_hi[axis] = lo[axis] + size[axis] / 2;
  mid_lo[axis] = mid_hi[axis];
  // The halves are independent: TBB may run them on both cores.
  if (size.x * size.y * size.z >= 64)
    tbb::parallel_invoke([&] { classify(g, root, T, grid, lo, mid_hi, state); },
                         [&] { classify(g, root, T, grid, mid_lo, hi, state); });
  else {
    classify(g, root, T, grid, lo, mid_hi, state);
    classify(g, root, T, grid, mid_lo, hi, state);
  }
}

// Bricks of a tape block: each active brick's tape is narrowed (runtime/tape.hpp narrow_tape)
// from the tape of its block of kTapeBlock^3 bricks, compiled from the root, so a brick pays for
// the few instructions its block kept, not for an interval walk of the whole tree.
constexpr int kTapeBlock = 4;

// The block tapes, in the order of their block index, and each active brick's block.
struct BlockTapes {
  std::vector<std::shared_ptr<const Tape>> tapes;
  std::vector<std::uint32_t> of;  // per active brick
};

BlockTapes block_tapes(const std::shared_ptr<const Graph>& graph, NodeId root, double T, const Grid& grid,
                       const std::vector<std::uint32_t>& active, bool under_blend = false) {
  const glm::ivec3 blocks = (grid.bricks + (kTapeBlock - 1)) / kTapeBlock;
  auto key = [&](std::uint32_t brick) {
    const glm::ivec3 c = grid.brick_at(brick) / kTapeBlock;
    return std::uint64_t(c.x) + std::uint64_t(blocks.x) * (std::uint64_t(c.y) + std::uint64_t(blocks.y) * std::uint64_t(c.z));
  };
  std::vector<std::uint64_t> keys(active.size());
  for (std::size_t a = 0; a < active.size(); ++a) keys[a] = key(active[a]);
  std::vector<std::uint64_t> distinct = keys;
  std::sort(distinct.begin(), distinct.end());
  distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
  BlockTapes out;
  out.of.resize(active.size());
  for (std::size_t a = 0; a < active.size(); ++a)
    out.of[a] = std::uint32_t(std::lower_bound(distinct.begin(), distinct.end(), keys[a]) - distinct.begin());
  out.tapes.resize(distinct.size());
  tbb::parallel_for(std::size_t(0), distinct.size(), [&](std::size_t i) {
    const std::uint64_t k = distinct[i];
    const glm::ivec3 c(int(k % std::uint64_t(blocks.x)), int(k / std::uint64_t(blocks.x) % std::uint64_t(blocks.y)),
                       int(k / (std::uint64_t(blocks.x) * std::uint64_t(blocks.y))));
    const Aabb box = grid.box(c * kTapeBlock, glm::min(c * kTapeBlock + kTapeBlock, grid.bricks));
    out.tapes[i] = std::make_shared<const Tape>(compile_tape(graph, root, T, &box, under_blend));
  });
  return out;
}

// Vertices a hair from a grid point (a surface through grid points: faces on grid planes) merge
// into one there (meshers/snap.hpp); `snapped` receives the merged vertices put on a crease.
void snap_phase(const Grid& grid, const std::vector<EdgeVertex>& all, const FeatureOptions& features, SurfaceField& field,
                TriangleMesh& mesh, std::vector<glm::vec3>& normals, std::vector<std::uint8_t>& snapped,
                PolygonizeStats& stats) {
  std::vector<std::uint64_t> near(all.size(), ~std::uint64_t(0));
  std::size_t count = 0;
  for (std::size_t i = 0; i < all.size(); ++i) {
    const std::uint64_t lower = all[i].key / 8, dir = all[i].key % 8;
    const glm::i64vec3 lp = grid.point_at(lower);
    const glm::i64vec3 d(std::int64_t(dir & 1), std::int64_t((dir >> 1) & 1), std::int64_t((dir >> 2) & 1));
    const glm::dvec3 dd(d);
    const double s = glm::dot(all[i].position - grid.position(lp), dd) / (glm::dot(dd, dd) * grid.h);
    if (s < kSnap) near[i] = lower;
    else if (s > 1.0 - kSnap) near[i] = grid.point_index(lp + d);
    count += near[i] != ~std::uint64_t(0);
  }
  if (count == 0) return;
  const SnapOptions options{features.sharp_angle_degrees, features.max_error};
  snap_to_grid_points(mesh, near, normals, snapped, gradient_of(field), field.threshold(), grid.h, options, &stats.snap);
}

// One polygonization; `locks` as quality_phase takes them, `retry` receives what it returns.
TriangleMesh polygonize_once(std::shared_ptr<const Graph> graph, NodeId root, double T, const PolygonizeOptions& options,
                             std::span<const Aabb> locks, RetryRequest& retry, PolygonizeStats* stats_out) {
  PolygonizeStats stats;
  const Graph& g = *graph;
  const double h = options.precision;
  if (!(h > 0.0) || !std::isfinite(h)) throw PolygonizeError("precision must be a finite number > 0");
  TriangleMesh mesh;
  Aabb solid = solid_bounds(g, root, T, false);
  if (solid.empty()) {
    if (stats_out) *stats_out = stats;
    return mesh;
  }
  if (const std::string why = unmeshable_extent(solid); !why.empty()) throw PolygonizeError(why);
  if (const std::string why = unresolvable_precision(solid, h); !why.empty()) throw PolygonizeError(why);
  if (!solid.finite()) throw PolygonizeError("the solid {f >= T} is unbounded: no box holds it (a blend over R-function differences?)");
  const bool clipped = !options.clip.empty();
  if (clipped) {
    solid = intersect(solid, options.clip);
    if (solid.empty()) {
      if (stats_out) *stats_out = stats;
      return mesh;
    }
  }
  const Aabb domain = solid.expanded(2.0 * h);
  stats.domain = domain;
  Grid grid;
  grid.origin = domain.lo;
  grid.h = h;
  const glm::dvec3 cells = glm::ceil(domain.size() / h);
  const glm::dvec3 bricks = glm::ceil(cells / double(kCells));
  const double brick_total = bricks.x * bricks.y * bricks.z;
  if (bricks.x > 2e6 || bricks.y > 2e6 || bricks.z > 2e6)
    throw PolygonizeError("precision " + std::to_string(h) + " needs a grid of " + std::to_string(cells.x) + " x " +
                          std::to_string(cells.y) + " x " + std::to_string(cells.z) + " cells, past 2e6 bricks a side");
  MemoryBudget alone(options.memory_budget);
  MemoryBudget& budget = options.budget ? *options.budget : alone;
  // The brick table costs 5 bytes a brick; an active brick about 12 KiB while it is meshed.
  const MemoryReservation table(budget, 5.0 * brick_total,
                                "precision " + std::to_string(h) + ": a grid of " + std::to_string(cells.x) + " x " +
                                    std::to_string(cells.y) + " x " + std::to_string(cells.z) + " cells, whose brick table");
  grid.bricks = glm::ivec3(bricks);
  grid.points = glm::i64vec3(grid.bricks) * std::int64_t(kCells) + std::int64_t(1);
  stats.bricks_total = grid.brick_count();

  // 1. Which bricks may the surface cross?
  auto t0 = std::chrono::steady_clock::now();
  std::vector<std::uint8_t> state(grid.brick_count(), kOutside);
  classify(g, root, T, grid, {0, 0, 0}, grid.bricks, state);
  std::vector<std::uint32_t> active;
  // Bricks the filter rejects stay kActive with no slot: their shared grid points then take the
  // label of the brick that sampled them (they lie where the caller cuts the patch away).
  std::vector<std::uint8_t> wanted;  // per active brick: the octants the filter named
  {
    std::vector<std::uint32_t> candidates;
    for (std::size_t i = 0; i < state.size(); ++i)
      if (state[i] == kActive) candidates.push_back(static_cast<std::uint32_t>(i));
    std::vector<std::uint8_t> mask(candidates.size(), octants::kAll);
    if (options.brick_filter)
      tbb::parallel_for(std::size_t(0), candidates.size(), [&](std::size_t c) {
        const glm::ivec3 b = grid.brick_at(candidates[c]);
        mask[c] = options.brick_filter(grid.box(b, b + 1));
      });
    for (std::size_t c = 0; c < candidates.size(); ++c)
      if (mask[c]) active.push_back(candidates[c]), wanted.push_back(mask[c]);
  }
  stats.bricks_active = active.size();
  // A blend's patch samples its operands one by one and keeps a region value a grid point
  // (PolygonizeOptions::region_operands, meshers/brick_region.hpp).
  const std::size_t operands =
      options.brick_filter && options.region_operands.size() >= 2 ? options.region_operands.size() : 0;
  const MemoryReservation working(budget, double(active.size()) * (12288.0 + (operands ? 4.0 * kBrickPoints : 0.0)),
                                  "precision " + std::to_string(h) + ": the " + std::to_string(active.size()) +
                                      " bricks the surface crosses");
  std::vector<std::uint32_t> slot(grid.brick_count(), kNone);
  for (std::size_t i = 0; i < active.size(); ++i) slot[active[i]] = static_cast<std::uint32_t>(i);
  stats.seconds_classify = seconds_since(t0);
  if (options.progress) options.progress(0.05);

  // 2. Sample every active brick's 9^3 grid points with a tape specialized to the brick. A point
  //    on a brick's + faces belongs to the brick across them (as the labels below say); when
  //    that brick is sampled too, the value is copied from it afterwards, not evaluated twice.
  t0 = std::chrono::steady_clock::now();
  std::vector<float> values(active.size() * kBrickPoints);
  std::vector<std::shared_ptr<const Tape>> tapes(active.size());
  std::atomic<std::size_t> done{0}, evaluated{0}, refined{0};
  auto report = [&](double base, double span) {
    const std::size_t d = ++done;
    if (options.progress && tbb::this_task_arena::current_thread_index() == 0 &&
        d % std::max<std::size_t>(1, active.size() / 50) == 0)
      options.progress(base + span * double(d) / double(active.size()));
  };
  auto cancelled = [&] { return options.cancel && options.cancel->load(std::memory_order_relaxed); };
  // The brick that owns local point `local` of brick b, where it is `at` there; b itself, or a
  // neighbour across a + face that the grid holds.
  auto owner_of = [&](glm::ivec3 b, glm::ivec3 local, glm::ivec3& at) {
    glm::ivec3 owner = b;
    at = local;
    for (int axis = 0; axis < 3; ++axis)
      if (local[axis] == kCells && b[axis] + 1 < grid.bricks[axis]) {
        owner[axis] += 1;
        at[axis] = 0;
      }
    return owner;
  };
  // The slot of the sampled brick that owns the point, or kNone when b evaluates it itself.
  auto sampled_owner = [&](glm::ivec3 b, glm::ivec3 local, std::size_t& at_index) -> std::uint32_t {
    glm::ivec3 at;
    const glm::ivec3 owner = owner_of(b, local, at);
    if (owner == b) return kNone;
    const std::size_t oi = grid.brick_index(owner);
    at_index = std::size_t(at.x + kPoints * (at.y + kPoints * at.z));
    return state[oi] == kActive ? slot[oi] : kNone;
  };
  const BlockTapes blocks = block_tapes(graph, root, T, grid, active);
  tbb::parallel_for(std::size_t(0), active.size(), [&](std::size_t a) {
    const glm::ivec3 b = grid.brick_at(active[a]);
    tapes[a] = std::make_shared<const Tape>(narrow_tape(*blocks.tapes[blocks.of[a]], grid.box(b, b + 1)));
  });
  // A blend's patch: each brick's operand tapes (a brick's side by side), and the region values.
  std::vector<std::shared_ptr<const Tape>> operand_tapes(operands * active.size());
  std::vector<float> region(operands ? active.size() * kBrickPoints : 0);
  for (std::size_t o = 0; o < operands; ++o) {
    const BlockTapes ob = block_tapes(graph, options.region_operands[o], T, grid, active, true);
    tbb::parallel_for(std::size_t(0), active.size(), [&](std::size_t a) {
      const glm::ivec3 b = grid.brick_at(active[a]);
      operand_tapes[a * operands + o] = std::make_shared<const Tape>(narrow_tape(*ob.tapes[ob.of[a]], grid.box(b, b + 1)));
    });
  }
  // Bricks extracted by an earlier run with the same key (meshers/polygonize_reuse.hpp) are
  // neither sampled nor extracted; their neighbours sample the points they own with their tapes.
  brick::BrickView view{&grid, &state, &slot, {}};
  std::vector<std::shared_ptr<const brick::KeptBrick>> kept(active.size());
  std::vector<std::uint64_t> keys;
  if (options.pieces && !options.brick_filter && !clipped) {
    view.tape_hash = brick::tape_hashes(tapes);
    keys.resize(active.size());
    tbb::parallel_for(std::size_t(0), active.size(), [&](std::size_t a) {
      keys[a] = brick::brick_key(view, grid.brick_at(active[a]), T, options);
      kept[a] = brick::find_kept(*options.pieces, keys[a]);
    });
    for (const auto& k : kept) stats.bricks_reused += k != nullptr;
  }
  // Evaluates brick a's points whose sampled owner is `owner` (kNone: a itself, or an owner that
  // was not sampled) with `eval`, into a's values; returns how many.
  // A point outside the octants its brick wants is not evaluated: NaN, which reads as outside
  // and leaves the vertices on its edges unrefined (meshers/brick_extract.hpp).
  const float skipped = std::numeric_limits<float>::quiet_NaN();
  auto sample = [&](std::size_t a, const TapeEvaluator& eval, std::uint32_t owner) {
    const glm::ivec3 b = grid.brick_at(active[a]);
    float xs[kBrickPoints], ys[kBrickPoints], zs[kBrickPoints], fs[kBrickPoints];
    std::uint16_t which[kBrickPoints];
    int m = 0, n = 0;
    for (int k = 0; k < kPoints; ++k)
      for (int j = 0; j < kPoints; ++j)
        for (int i = 0; i < kPoints; ++i, ++n) {
          std::size_t at = 0;
          if (sampled_owner(b, {i, j, k}, at) != owner) continue;
          if (!(wanted[a] & brick::octants_at(i, j, k))) {
            values[a * kBrickPoints + std::size_t(n)] = skipped;
            if (operands) region[a * kBrickPoints + std::size_t(n)] = skipped;
            continue;
          }
          const glm::dvec3 p = grid.position(glm::i64vec3(b) * std::int64_t(kCells) + glm::i64vec3(i, j, k));
          which[m] = static_cast<std::uint16_t>(n);
          xs[m] = static_cast<float>(p.x);
          ys[m] = static_cast<float>(p.y);
          zs[m] = static_cast<float>(p.z);
          ++m;
        }
    float gs[kBrickPoints];
    for (int at = 0; at < m; at += kBlock) {
      const int count = std::min(kBlock, m - at);
      if (operands)  // (no kept neighbours with a filter: `eval` is a's own tape)
        brick::sum_operands(std::span(operand_tapes).subspan(a * operands, operands), xs + at, ys + at, zs + at, count,
                            fs + at, gs + at);
      else
        eval.field_block(xs + at, ys + at, zs + at, count, fs + at);
    }
    for (int q = 0; q < m; ++q) values[a * kBrickPoints + which[q]] = fs[q];
    if (operands)
      for (int q = 0; q < m; ++q) region[a * kBrickPoints + which[q]] = gs[q];
    return std::size_t(m);
  };
  tbb::parallel_for(std::size_t(0), active.size(), [&](std::size_t a) {
    if (cancelled() || kept[a]) return;
    std::size_t m = sample(a, TapeEvaluator(tapes[a]), kNone);
    const glm::ivec3 b = grid.brick_at(active[a]);
    for (int d = 1; d < 8; ++d) {  // + neighbours kept from the cache: their points, their tapes
      const glm::ivec3 c = b + glm::ivec3(d & 1, (d >> 1) & 1, (d >> 2) & 1);
      if (glm::any(glm::greaterThanEqual(c, grid.bricks))) continue;
      const std::size_t ci = grid.brick_index(c);
      if (state[ci] == kActive && slot[ci] != kNone && kept[slot[ci]]) m += sample(a, TapeEvaluator(tapes[slot[ci]]), slot[ci]);
    }
    evaluated += m;
    report(0.05, 0.55);
  });
  if (cancelled()) throw MeshCancelled("meshing was cancelled");
  // The + face points from their owners, which evaluated them themselves (an owner's point at
  // `at` lies on none of its own + faces that lead to a sampled brick).
  tbb::parallel_for(std::size_t(0), active.size(), [&](std::size_t a) {
    if (kept[a]) return;
    const glm::ivec3 b = grid.brick_at(active[a]);
    for (int k = 0; k < kPoints; ++k)
      for (int j = 0; j < kPoints; ++j)
        for (int i = 0; i < kPoints; ++i) {
          if (i < kCells && j < kCells && k < kCells) continue;
          std::size_t at = 0;
          const std::uint32_t s = sampled_owner(b, {i, j, k}, at);
          if (s == kNone || kept[s]) continue;
          const std::size_t here = a * kBrickPoints + std::size_t(i + kPoints * (j + kPoints * k));
          values[here] = values[std::size_t(s) * kBrickPoints + at];
          if (operands) region[here] = region[std::size_t(s) * kBrickPoints + at];
        }
  });
  stats.points_evaluated = evaluated.load();
  stats.seconds_sample = seconds_since(t0);

  // Inside labels: a grid point shared by bricks takes the label of the brick that owns it (the
  // one where it is not on the + faces), so that every cell around it agrees. Where the owner is
  // active its value was sampled into `own` (copied, or evaluated with the owner's tape).
  auto inside = [&](glm::ivec3 b, glm::ivec3 local, const float* own) {
    glm::ivec3 at;
    const glm::ivec3 owner = owner_of(b, local, at);
    const std::size_t oi = grid.brick_index(owner);
    if (owner != b && state[oi] != kActive) return state[oi] == kInside;
    return own[local.x + kPoints * (local.y + kPoints * local.z)] >= float(T);
  };

  // 3. Marching tetrahedra per brick; vertices on grid edges refined along the edge.
  t0 = std::chrono::steady_clock::now();
  std::vector<BrickOutput> outputs(active.size());
  std::atomic<bool> reaches_boundary{false};
  tbb::enumerable_thread_specific<brick::Scratch> scratch;
  done = 0;
  tbb::parallel_for(std::size_t(0), active.size(), [&](std::size_t a) {
    if (cancelled()) return;
    if (kept[a]) {
      outputs[a] = kept[a]->out;
      if (kept[a]->reaches_boundary) reaches_boundary = true;
      return;
    }
    const glm::ivec3 b = grid.brick_at(active[a]);
    const float* own = values.data() + a * kBrickPoints;
    bool boundary = false;
    std::uint8_t label[kBrickPoints];
    for (int k = 0; k < kPoints; ++k)
      for (int j = 0; j < kPoints; ++j)
        for (int i = 0; i < kPoints; ++i) label[i + kPoints * (j + kPoints * k)] = inside(b, {i, j, k}, own) ? 1 : 0;
    // The outermost grid points must be outside, or the solid leaves the domain.
    const glm::i64vec3 base = glm::i64vec3(b) * std::int64_t(kCells);
    for (int n = 0; n < kBrickPoints; ++n) {
      if (!label[n]) continue;
      const glm::i64vec3 p = base + glm::i64vec3(n % kPoints, (n / kPoints) % kPoints, n / (kPoints * kPoints));
      if (p.x == 0 || p.y == 0 || p.z == 0 || p.x == grid.points.x - 1 || p.y == grid.points.y - 1 || p.z == grid.points.z - 1)
        boundary = true;
    }
    if (boundary) reaches_boundary = true;
    BrickOutput& out = outputs[a];
    brick::Scratch& sc = scratch.local();
    std::uint8_t keep_cells[kCells * kCells * kCells];
    if (operands) brick::region_cells(region.data() + a * kBrickPoints, keep_cells);
    brick::march(grid, b, label, sc, operands ? keep_cells : nullptr);
    const TapeEvaluator eval(tapes[a]);
    refined += brick::place_vertices(grid, b, active[a], own, label, eval, T,
                                     {options.refine_steps, options.refine_tolerance}, sc, out);
    // Exact normals for the vertices of cells that may hold a crease (meshers/features.hpp).
    if (options.sharp_features && may_have_creases(*tapes[a])) brick::crease_normals(own, eval, options.features, sc, out);
    if (options.brick_filter) brick::drop_unsampled(grid, b, own, wanted[a], sc, out);
    if (!keys.empty())
      brick::keep(*options.pieces, keys[a], std::make_shared<const brick::KeptBrick>(brick::KeptBrick{out, boundary}));
    report(0.6, 0.3);
  });
  stats.seconds_extract = seconds_since(t0);
  stats.refine_evaluations = refined.load();
  if (cancelled()) throw MeshCancelled("meshing was cancelled");
  if (reaches_boundary && !clipped)
    throw PolygonizeError("the solid reaches the edge of its own bounds: it is unbounded (a blend over R-function differences?)");

  // 4. One vertex per edge key across bricks, then vertices a hair from grid points merged.
  t0 = std::chrono::steady_clock::now();
  // The samples and cache entries are let go before the join, the bricks' outputs during it
  // (the peak of a global run is here): the passes that follow hold their own working sets.
  std::vector<float>().swap(values);
  std::vector<float>().swap(region);
  std::vector<std::shared_ptr<const brick::KeptBrick>>().swap(kept);
  std::vector<EdgeVertex> all = brick::join_bricks(std::move(outputs), mesh);
  std::vector<glm::vec3> normals(all.size());
  for (std::size_t i = 0; i < all.size(); ++i) normals[i] = all[i].normal;
  RootField root_field{graph, root, T, nullptr};
  // The field near the surface on the bricks' own tapes, for the passes that move vertices.
  SurfaceField field(graph, root, T, grid.origin, kCells * h);
  for (std::size_t a = 0; a < active.size(); ++a) field.adopt(grid.brick_at(active[a]), tapes[a]);
  std::vector<std::uint8_t> on_crease;  // snapped vertices put on a crease, then the crease step's points
  if (options.snap) snap_phase(grid, all, options.features, field, mesh, normals, on_crease, stats);
  std::vector<EdgeVertex>().swap(all);
  stats.seconds_merge = seconds_since(t0);

  // 5. Creases: split the edges that cross them (meshers/features.hpp), untangle, unfold.
  t0 = std::chrono::steady_clock::now();
  crease_phase(root_field, options.features, h, mesh, normals, on_crease, stats);
  stats.seconds_features = seconds_since(t0);

  // 6. Well-shaped triangles (meshers/quality.hpp), on the bricks' own tapes; crease points stay.
  //    A patch (filtered or clipped) is the local strategies' to remesh with its bands.
  if (options.quality.enabled && !options.brick_filter && !clipped) {
    const QualityReuse reuse = keys.empty() ? QualityReuse{} : brick::quality_reuse(view, *options.pieces);
    retry = quality_phase(field, root_field, h, options.quality, budget, mesh, on_crease, keys.empty() ? nullptr : &reuse,
                          locks, stats);
  }
  if (options.progress) options.progress(1.0);
  if (stats_out) *stats_out = stats;
  return mesh;
}

// The mesh's smallest angle, degrees (meshers/triangle_shape.hpp thinness is its cosine).
double smallest_angle(const TriangleMesh& mesh) {
  double most = 0.0;
  for (const glm::uvec3& t : mesh.triangles)
    most = std::max(most, thinness(mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]));
  return std::acos(std::min(most, 1.0)) * 180.0 / std::numbers::pi;
}

// A second run for folds is kept when it has fewer and its smallest angle is at least this much of
// the first's: in 19 random scenes with folds, a fold mended at 2.02 -> 1.99 degrees was worth
// it, one at 7.1 -> 1.6 degrees (a new sliver beside the kept vertices) was not.
constexpr double kKeptAngleShare = 0.9;

}  // namespace

std::string unresolvable_precision(const Aabb& solid, double precision) {
  const double far = std::max({std::abs(solid.lo.x), std::abs(solid.lo.y), std::abs(solid.lo.z), std::abs(solid.hi.x),
                               std::abs(solid.hi.y), std::abs(solid.hi.z)});
  const double step = std::nextafter(far, std::numeric_limits<double>::infinity()) - far;
  if (!std::isfinite(far) || precision >= kCoordinateSteps * step) return {};
  char buf[320];
  std::snprintf(buf, sizeof buf,
                "the solid lies %.3g from the origin, where doubles step by %.3g: precision %g cannot be resolved "
                "there (use at least %.3g, or move the scene nearer the origin)",
                far, step, precision, kCoordinateSteps * step);
  return buf;
}

std::string unmeshable_extent(const Aabb& solid) {
  const double far = std::max({std::abs(solid.lo.x), std::abs(solid.lo.y), std::abs(solid.lo.z), std::abs(solid.hi.x),
                               std::abs(solid.hi.y), std::abs(solid.hi.z)});
  if (!std::isfinite(far) || far <= kMaxCoordinate) return {};
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "the solid reaches %.3g from the origin: HybridTree meshes solids within %.0e of it (a radius, "
                "scale or offset of extreme size?)",
                far, kMaxCoordinate);
  return buf;
}

TriangleMesh polygonize(std::shared_ptr<const Graph> graph, NodeId root, double T, const PolygonizeOptions& options,
                        PolygonizeStats* stats_out) {
  RetryRequest retry;
  PolygonizeStats first;
  TriangleMesh mesh = polygonize_once(graph, root, T, options, {}, retry, &first);
  if (retry.boxes.empty()) {
    if (stats_out) *stats_out = first;
    return mesh;
  }
  // Where pairs or folds are left (two sheets closer than a cell, pushed through each other;
  // triangles the pass turned over beside a crease), the pass runs again from the extracted mesh
  // with the vertices around them kept where extraction put them. The extracted mesh is made
  // again (extraction is deterministic) rather than kept through the pass: a copy held beside the
  // pass's slabs was up to a sixth of a global run's peak memory. For folds alone the first
  // result is held instead, and kept unless the second has fewer folds and about as large a
  // smallest angle (in 120 random scenes, two of four such second runs mended nothing and one made
  // a sliver).
  TriangleMesh kept;
  if (!retry.crossing) kept = std::move(mesh);
  mesh = TriangleMesh();
  PolygonizeOptions again = options;
  again.progress = nullptr;
  PolygonizeStats second;
  RetryRequest none;  // a run with locks asks for no other
  mesh = polygonize_once(std::move(graph), root, T, again, retry.boxes, none, &second);
  const bool better = retry.crossing || (second.folds.pairs_after < first.folds.pairs_after &&
                                         second.crease_intersections <= first.crease_intersections &&
                                         smallest_angle(mesh) >= kKeptAngleShare * smallest_angle(kept));
  PolygonizeStats& taken = better ? second : first;
  const PolygonizeStats& other = better ? first : second;
  taken.quality += other.quality;
  ++taken.quality.retries;
  taken.quality_intersections += other.quality_intersections;
  taken.folds.pairs_before += other.folds.pairs_before, taken.folds.collapses += other.folds.collapses;
  taken.seconds_classify += other.seconds_classify, taken.seconds_sample += other.seconds_sample;
  taken.seconds_extract += other.seconds_extract, taken.seconds_merge += other.seconds_merge;
  taken.seconds_features += other.seconds_features;
  if (!better) mesh = std::move(kept);
  if (options.progress) options.progress(1.0);
  if (stats_out) *stats_out = taken;
  return mesh;
}

}  // namespace ht
