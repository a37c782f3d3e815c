// Sparse marching tetrahedra over interval-pruned bricks; see meshers/polygonize.hpp.
// References: Kuhn's triangulation of the cube (Kuhn 1960, as used by Freudenthal); marching
// tetrahedra (Doi & Koide 1991); interval pruning of implicit surfaces (Duff 1992, libfive).
#include "meshers/polygonize.hpp"

#include "meshers/features.hpp"
#include "meshers/quality.hpp"
#include "meshers/relax.hpp"
#include "meshers/self_intersections.hpp"
#include "meshers/snap.hpp"
#include "meshers/surface_field.hpp"
#include "meshers/unfold.hpp"

#include "runtime/tape.hpp"
#include "runtime/tape_eval.hpp"

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

namespace ht {
namespace {

constexpr double kSnap = 0.01;      // of a grid edge: a vertex this near a grid point merges there
constexpr int kUntangleRounds = 4;
constexpr int kUnfoldRounds = 12;  // of collapsing the folds sliding left  // of sliding crease points where the feature step folded
constexpr int kCells = 8;              // cells per brick side
constexpr int kPoints = kCells + 1;    // grid points per brick side
constexpr int kBrickPoints = kPoints * kPoints * kPoints;
enum State : std::uint8_t { kOutside = 0, kInside = 1, kActive = 2 };

// The six tetrahedra of Kuhn's triangulation: monotone paths from corner 000 to 111, one per
// order of the axes. Corners are bit masks (x = 1, y = 2, z = 4).
constexpr std::array<std::array<int, 4>, 6> kTets = {{{0, 1, 3, 7},
                                                      {0, 1, 5, 7},
                                                      {0, 2, 3, 7},
                                                      {0, 2, 6, 7},
                                                      {0, 4, 5, 7},
                                                      {0, 4, 6, 7}}};

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::string gib(double bytes) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.2f GiB", bytes / double(1u << 30));
  return buf;
}

struct Grid {
  glm::dvec3 origin;
  double h;
  glm::ivec3 bricks;     // bricks per axis
  glm::i64vec3 points;   // grid points per axis: 8 * bricks + 1

  std::size_t brick_count() const { return std::size_t(bricks.x) * std::size_t(bricks.y) * std::size_t(bricks.z); }
  std::size_t brick_index(glm::ivec3 b) const {
    return std::size_t(b.x) + std::size_t(bricks.x) * (std::size_t(b.y) + std::size_t(bricks.y) * std::size_t(b.z));
  }
  glm::ivec3 brick_at(std::size_t i) const {
    return {int(i % std::size_t(bricks.x)), int((i / std::size_t(bricks.x)) % std::size_t(bricks.y)),
            int(i / (std::size_t(bricks.x) * std::size_t(bricks.y)))};
  }
  Aabb box(glm::ivec3 lo, glm::ivec3 hi) const {  // bricks [lo, hi)
    return {origin + glm::dvec3(lo) * (kCells * h), origin + glm::dvec3(hi) * (kCells * h)};
  }
  std::uint64_t point_index(glm::i64vec3 p) const {
    return std::uint64_t(p.x + points.x * (p.y + points.y * p.z));
  }
  glm::dvec3 position(glm::i64vec3 p) const { return origin + glm::dvec3(p) * h; }
};

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

struct EdgeVertex {
  std::uint64_t key;  // lower grid point * 8 + direction (x = 1, y = 2, z = 4)
  std::uint32_t brick;
  glm::dvec3 position;
  glm::vec3 normal;  // outward unit normal where a crease is suspected, else zero
};

struct BrickOutput {
  std::vector<EdgeVertex> vertices;
  std::vector<std::array<std::uint64_t, 3>> triangles;  // edge keys
};

}  // namespace

TriangleMesh polygonize(std::shared_ptr<const Graph> graph, NodeId root, double T, const PolygonizeOptions& options,
                        PolygonizeStats* stats_out) {
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
  if (!solid.finite()) throw PolygonizeError("the solid {f >= T} cannot be bounded (is a blend over R-function differences?)");
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
  // The brick table costs 5 bytes a brick; an active brick about 12 KiB while it is meshed.
  const double table_bytes = 5.0 * brick_total;
  if (table_bytes > double(options.memory_budget) || bricks.x > 2e6 || bricks.y > 2e6 || bricks.z > 2e6)
    throw PolygonizeError("precision " + std::to_string(h) + " needs a grid of " + std::to_string(cells.x) + " x " +
                          std::to_string(cells.y) + " x " + std::to_string(cells.z) + " cells; its brick table alone needs " +
                          gib(table_bytes) + ", over the memory budget of " + gib(double(options.memory_budget)));
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
  for (std::size_t i = 0; i < state.size(); ++i)
    if (state[i] == kActive) {
      const glm::ivec3 b = grid.brick_at(i);
      if (!options.brick_filter || options.brick_filter(grid.box(b, b + 1))) active.push_back(static_cast<std::uint32_t>(i));
    }
  stats.bricks_active = active.size();
  const double need = table_bytes + double(active.size()) * 12288.0;
  if (need > double(options.memory_budget))
    throw PolygonizeError("precision " + std::to_string(h) + " needs about " + gib(need) + " (" +
                          std::to_string(active.size()) + " bricks the surface crosses), over the memory budget of " +
                          gib(double(options.memory_budget)));
  std::vector<std::uint32_t> slot(grid.brick_count(), kNone);
  for (std::size_t i = 0; i < active.size(); ++i) slot[active[i]] = static_cast<std::uint32_t>(i);
  stats.seconds_classify = seconds_since(t0);
  if (options.progress) options.progress(0.05);

  // 2. Sample every active brick's 9^3 grid points with a tape specialized to the brick.
  t0 = std::chrono::steady_clock::now();
  std::vector<float> values(active.size() * kBrickPoints);
  std::vector<std::shared_ptr<const Tape>> tapes(active.size());
  std::atomic<std::size_t> done{0};
  auto report = [&](double base, double span) {
    const std::size_t d = ++done;
    if (options.progress && tbb::this_task_arena::current_thread_index() == 0 &&
        d % std::max<std::size_t>(1, active.size() / 50) == 0)
      options.progress(base + span * double(d) / double(active.size()));
  };
  auto cancelled = [&] { return options.cancel && options.cancel->load(std::memory_order_relaxed); };
  tbb::parallel_for(std::size_t(0), active.size(), [&](std::size_t a) {
    if (cancelled()) return;
    const glm::ivec3 b = grid.brick_at(active[a]);
    const Aabb box = grid.box(b, b + 1);
    tapes[a] = std::make_shared<const Tape>(compile_tape(graph, root, T, &box));
    const TapeEvaluator eval(tapes[a]);
    float xs[kBrickPoints], ys[kBrickPoints], zs[kBrickPoints];
    int n = 0;
    for (int k = 0; k < kPoints; ++k)
      for (int j = 0; j < kPoints; ++j)
        for (int i = 0; i < kPoints; ++i, ++n) {
          const glm::dvec3 p = grid.position(glm::i64vec3(b) * std::int64_t(kCells) + glm::i64vec3(i, j, k));
          xs[n] = static_cast<float>(p.x);
          ys[n] = static_cast<float>(p.y);
          zs[n] = static_cast<float>(p.z);
        }
    for (int at = 0; at < kBrickPoints; at += kBlock)
      eval.field_block(xs + at, ys + at, zs + at, std::min(kBlock, kBrickPoints - at), values.data() + a * kBrickPoints + at);
    report(0.05, 0.55);
  });
  if (cancelled()) throw MeshCancelled("meshing was cancelled");
  stats.points_evaluated = active.size() * kBrickPoints;
  stats.seconds_sample = seconds_since(t0);

  // Inside labels: a grid point shared by bricks takes the label of the brick that owns it (the
  // one where it is not on the + faces), so that every cell around it agrees.
  auto inside = [&](glm::ivec3 b, glm::ivec3 local, const float* own) {
    glm::ivec3 owner = b, at = local;
    for (int axis = 0; axis < 3; ++axis)
      if (local[axis] == kCells && b[axis] + 1 < grid.bricks[axis]) {
        owner[axis] += 1;
        at[axis] = 0;
      }
    if (owner == b) return own[local.x + kPoints * (local.y + kPoints * local.z)] >= float(T);
    const std::size_t oi = grid.brick_index(owner);
    if (state[oi] != kActive) return state[oi] == kInside;
    if (slot[oi] == kNone) return own[local.x + kPoints * (local.y + kPoints * local.z)] >= float(T);
    return values[std::size_t(slot[oi]) * kBrickPoints + std::size_t(at.x + kPoints * (at.y + kPoints * at.z))] >= float(T);
  };

  // 3. Marching tetrahedra per brick; vertices on grid edges refined along the edge.
  t0 = std::chrono::steady_clock::now();
  std::vector<BrickOutput> outputs(active.size());
  std::atomic<bool> reaches_boundary{false};
  done = 0;
  tbb::parallel_for(std::size_t(0), active.size(), [&](std::size_t a) {
    if (cancelled()) return;
    const glm::ivec3 b = grid.brick_at(active[a]);
    const float* own = values.data() + a * kBrickPoints;
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
        reaches_boundary = true;
    }
    BrickOutput& out = outputs[a];
    std::vector<std::uint64_t> keys;          // this brick's edge keys, in order of creation
    std::vector<std::array<int, 2>> ends;     // their local grid points
    auto local_index = [](glm::ivec3 l) { return l.x + kPoints * (l.y + kPoints * l.z); };
    auto edge = [&](glm::ivec3 p, glm::ivec3 q) {
      const glm::ivec3 d = q - p;  // monotone: every component 0 or 1
      const std::uint64_t key = grid.point_index(base + glm::i64vec3(p)) * 8 + std::uint64_t(d.x + 2 * d.y + 4 * d.z);
      keys.push_back(key);
      ends.push_back({local_index(p), local_index(q)});
      return key;
    };
    std::vector<std::uint32_t> cell_begin;  // triangles of each cell, x fastest
    cell_begin.reserve(kCells * kCells * kCells + 1);
    for (int cz = 0; cz < kCells; ++cz)
      for (int cy = 0; cy < kCells; ++cy)
        for (int cx = 0; cx < kCells; ++cx) {
          cell_begin.push_back(static_cast<std::uint32_t>(out.triangles.size()));
          int mask = 0;
          glm::ivec3 corner[8];
          for (int c = 0; c < 8; ++c) {
            corner[c] = {cx + (c & 1), cy + ((c >> 1) & 1), cz + ((c >> 2) & 1)};
            mask |= label[local_index(corner[c])] << c;
          }
          if (mask == 0 || mask == 255) continue;
          for (const auto& tet : kTets) {
            int in[4], out_[4], ni = 0, no = 0;
            for (int v : tet) (label[local_index(corner[v])] ? in[ni++] : out_[no++]) = v;
            if (ni == 0 || no == 0) continue;
            // Orientation: normals point from the inside corners toward the outside ones.
            glm::dvec3 cin(0.0), cout(0.0);
            for (int i = 0; i < ni; ++i) cin += glm::dvec3(corner[in[i]]);
            for (int i = 0; i < no; ++i) cout += glm::dvec3(corner[out_[i]]);
            const glm::dvec3 outward = cout / double(no) - cin / double(ni);
            auto emit = [&](std::array<std::pair<int, int>, 3> e) {
              std::array<glm::dvec3, 3> mid;
              for (int i = 0; i < 3; ++i) mid[i] = 0.5 * glm::dvec3(corner[e[i].first] + corner[e[i].second]);
              if (glm::dot(glm::cross(mid[1] - mid[0], mid[2] - mid[0]), outward) < 0) std::swap(e[1], e[2]);
              std::array<std::uint64_t, 3> tri;
              for (int i = 0; i < 3; ++i) {
                glm::ivec3 p = corner[e[i].first], q = corner[e[i].second];
                if (p.x > q.x || p.y > q.y || p.z > q.z) std::swap(p, q);
                tri[i] = edge(p, q);
              }
              out.triangles.push_back(tri);
            };
            if (ni == 1) {
              emit({{{in[0], out_[0]}, {in[0], out_[1]}, {in[0], out_[2]}}});
            } else if (no == 1) {
              emit({{{out_[0], in[0]}, {out_[0], in[1]}, {out_[0], in[2]}}});
            } else {  // a quad, cut along one diagonal
              emit({{{in[0], out_[0]}, {in[0], out_[1]}, {in[1], out_[1]}}});
              emit({{{in[0], out_[0]}, {in[1], out_[1]}, {in[1], out_[0]}}});
            }
          }
        }
    cell_begin.push_back(static_cast<std::uint32_t>(out.triangles.size()));
    // Vertices: one per distinct edge, by false position along the edge on this brick's tape.
    std::vector<std::size_t> order(keys.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](std::size_t x, std::size_t y) { return keys[x] < keys[y]; });
    std::vector<std::size_t> unique;
    for (std::size_t i : order)
      if (unique.empty() || keys[unique.back()] != keys[i]) unique.push_back(i);
    const std::size_t nv = unique.size();
    std::vector<glm::dvec3> pa(nv), pb(nv);
    std::vector<double> fa(nv), fb(nv), t(nv), span(nv);
    for (std::size_t v = 0; v < nv; ++v) {
      const auto [ia, ib] = ends[unique[v]];
      auto pos = [&](int li) {
        return grid.position(base + glm::i64vec3(li % kPoints, (li / kPoints) % kPoints, li / (kPoints * kPoints)));
      };
      // Keep the inside end as `a`.
      const bool a_in = label[ia] != 0;
      pa[v] = pos(a_in ? ia : ib);
      pb[v] = pos(a_in ? ib : ia);
      fa[v] = std::max(double(own[a_in ? ia : ib]), T);
      fb[v] = std::min(double(own[a_in ? ib : ia]), T);
      span[v] = fa[v] - fb[v];
      // An inside end exactly at T (a face through the grid point) says nothing of where the
      // solid ends along the edge: bisect there.
      t[v] = fa[v] > T && fa[v] > fb[v] ? (fa[v] - T) / (fa[v] - fb[v]) : 0.5;
    }
    // Illinois false position, the brick's unconverged vertices per batch. Most converge in a
    // few steps; those next to a crease of a min/max field need more.
    constexpr double kMargin = 1e-3;  // keeps vertices off grid points: no degenerate triangles
    std::vector<double> ta(nv, 0.0), tb(nv, 1.0);
    std::vector<float> xs(nv), ys(nv), zs(nv), fv(nv);
    std::vector<std::uint32_t> live(nv);
    std::iota(live.begin(), live.end(), 0u);
    const TapeEvaluator eval(tapes[a]);
    for (int step = 0; step < options.refine_steps && !live.empty(); ++step) {
      const std::size_t nl = live.size();
      for (std::size_t i = 0; i < nl; ++i) {
        const std::uint32_t v = live[i];
        t[v] = std::clamp(t[v], kMargin, 1.0 - kMargin);
        const glm::dvec3 p = pa[v] + t[v] * (pb[v] - pa[v]);
        xs[i] = float(p.x);
        ys[i] = float(p.y);
        zs[i] = float(p.z);
      }
      for (std::size_t at = 0; at < nl; at += kBlock)
        eval.field_block(xs.data() + at, ys.data() + at, zs.data() + at, int(std::min<std::size_t>(kBlock, nl - at)),
                         fv.data() + at);
      std::size_t kept = 0;
      for (std::size_t i = 0; i < nl; ++i) {
        const std::uint32_t v = live[i];
        const double f = fv[i];
        if (f >= T) {
          ta[v] = t[v];
          fa[v] = f;
          fb[v] = T + 0.5 * (fb[v] - T);  // Illinois: halve the stale end's weight
        } else {
          tb[v] = t[v];
          fb[v] = f;
          fa[v] = T + 0.5 * (fa[v] - T);
        }
        // Done when f - T, or the bracket, is a small fraction of the change across the edge.
        // A value exactly T is a plateau of the surface along the edge (a crease line on it): the
        // crossing is where the plateau ends, found by bisection.
        const double tol = options.refine_tolerance;
        const bool converged = (f != T && std::abs(f - T) <= tol * span[v]) || tb[v] - ta[v] <= tol;
        if (converged) continue;  // t[v] is the last point evaluated
        t[v] = fa[v] > T && fa[v] > fb[v] ? ta[v] + (fa[v] - T) / (fa[v] - fb[v]) * (tb[v] - ta[v]) : 0.5 * (ta[v] + tb[v]);
        live[kept++] = v;
      }
      live.resize(kept);
    }
    out.vertices.resize(nv);
    for (std::size_t v = 0; v < nv; ++v)
      out.vertices[v] = {keys[unique[v]], active[a], pa[v] + std::clamp(t[v], kMargin, 1.0 - kMargin) * (pb[v] - pa[v]),
                         glm::vec3(0.0f)};
    if (options.sharp_features && may_have_creases(*tapes[a])) {
      // Exact normals for the vertices of cells that may hold a crease (meshers/features.hpp).
      std::uint8_t suspect[kCells * kCells * kCells];
      mark_suspect_cells({own, std::size_t(kBrickPoints)}, kCells, options.features, suspect);
      std::vector<std::uint8_t> wanted(nv, 0);
      for (int c = 0; c < kCells * kCells * kCells; ++c) {
        if (!suspect[c]) continue;
        for (std::uint32_t i = cell_begin[std::size_t(c)]; i < cell_begin[std::size_t(c) + 1]; ++i)
          for (std::uint64_t key : out.triangles[i])
            wanted[std::size_t(std::lower_bound(out.vertices.begin(), out.vertices.end(), key,
                                                [](const EdgeVertex& e, std::uint64_t k) { return e.key < k; }) -
                               out.vertices.begin())] = 1;
      }
      std::vector<glm::dvec3> at, grad;
      for (std::size_t v = 0; v < nv; ++v)
        if (wanted[v]) at.push_back(out.vertices[v].position);
      grad.resize(at.size());
      if (!at.empty()) eval.gradient(at, {}, grad);
      for (std::size_t v = 0, i = 0; v < nv; ++v) {
        if (!wanted[v]) continue;
        const double len = glm::length(grad[i]);
        // The field grows inward: the outward normal is -grad f.
        if (len > 0 && std::isfinite(len)) out.vertices[v].normal = glm::vec3(-grad[i] / len);
        ++i;
      }
    }
    report(0.6, 0.3);
  });
  stats.seconds_extract = seconds_since(t0);
  if (cancelled()) throw MeshCancelled("meshing was cancelled");
  if (reaches_boundary && !clipped)
    throw PolygonizeError("the solid reaches the edge of its own bounds: it is unbounded (a blend over R-function differences?)");

  // 4. One vertex per edge key across bricks (the lowest brick's copy), triangles renumbered.
  t0 = std::chrono::steady_clock::now();
  std::vector<EdgeVertex> all;
  std::size_t tri_count = 0;
  for (const BrickOutput& o : outputs) {
    all.insert(all.end(), o.vertices.begin(), o.vertices.end());
    tri_count += o.triangles.size();
  }
  // The copy kept is the lowest brick's, among those with a normal if any has one.
  std::sort(all.begin(), all.end(), [](const EdgeVertex& x, const EdgeVertex& y) {
    const bool nx = x.normal != glm::vec3(0.0f), ny = y.normal != glm::vec3(0.0f);
    return x.key != y.key ? x.key < y.key : nx != ny ? nx : x.brick < y.brick;
  });
  all.erase(std::unique(all.begin(), all.end(), [](const EdgeVertex& x, const EdgeVertex& y) { return x.key == y.key; }),
            all.end());
  mesh.positions.resize(all.size());
  for (std::size_t i = 0; i < all.size(); ++i) mesh.positions[i] = all[i].position;
  mesh.triangles.reserve(tri_count);
  auto id = [&](std::uint64_t key) {
    const auto it = std::lower_bound(all.begin(), all.end(), key, [](const EdgeVertex& e, std::uint64_t k) { return e.key < k; });
    return static_cast<std::uint32_t>(it - all.begin());
  };
  for (const BrickOutput& o : outputs)
    for (const auto& tri : o.triangles) mesh.triangles.push_back({id(tri[0]), id(tri[1]), id(tri[2])});
  std::vector<glm::vec3> normals(all.size());
  for (std::size_t i = 0; i < all.size(); ++i) normals[i] = all[i].normal;
  std::shared_ptr<const TapeEvaluator> root_eval;
  auto root_field = [&]() -> const TapeEvaluator& {
    if (!root_eval) root_eval = std::make_shared<const TapeEvaluator>(std::make_shared<const Tape>(compile_tape(graph, root, T)));
    return *root_eval;
  };
  std::vector<std::uint8_t> snapped;  // merged vertices put on a crease or a corner
  {
    const SnapOptions snap_options{options.features.sharp_angle_degrees, options.features.max_error};
    // Vertices a hair from a grid point (a surface through grid points: faces on grid planes)
    // merge into one there (meshers/snap.hpp).
    std::vector<std::uint64_t> near(all.size(), ~std::uint64_t(0));
    std::size_t count = 0;
    for (std::size_t i = 0; i < all.size(); ++i) {
      const std::uint64_t lower = all[i].key / 8, dir = all[i].key % 8;
      const glm::i64vec3 lp(std::int64_t(lower % std::uint64_t(grid.points.x)),
                            std::int64_t((lower / std::uint64_t(grid.points.x)) % std::uint64_t(grid.points.y)),
                            std::int64_t(lower / std::uint64_t(grid.points.x * grid.points.y)));
      const glm::i64vec3 d(std::int64_t(dir & 1), std::int64_t((dir >> 1) & 1), std::int64_t((dir >> 2) & 1));
      const glm::dvec3 dd(d);
      const double s = glm::dot(all[i].position - grid.position(lp), dd) / (glm::dot(dd, dd) * h);
      if (s < kSnap) near[i] = lower;
      else if (s > 1.0 - kSnap) near[i] = grid.point_index(lp + d);
      count += near[i] != ~std::uint64_t(0);
    }
    if (count > 0 && options.snap) snap_to_grid_points(mesh, near, normals, snapped, root_field(), T, h, snap_options, &stats.snap);
  }
  stats.seconds_merge = seconds_since(t0);

  // 5. Creases: split the edges that cross them (meshers/features.hpp).
  t0 = std::chrono::steady_clock::now();
  bool any_normal = false;
  for (const glm::vec3& n : normals) any_normal |= n != glm::vec3(0.0f);
  std::vector<std::uint8_t> on_crease = snapped;
  if (any_normal) {
    const TapeEvaluator& eval = root_field();
    const CreaseStats crease = split_creases(mesh, normals, eval, T, h, options.features, &on_crease);
    stats.crease_edges = crease.split_edges;
    stats.corner_vertices = crease.corners;
    // Crease points placed past their neighbours' fold triangles into each other: where pieces
    // intersect, the crease points slide along their crease and the vertices away from it relax.
    if (crease.split_edges + crease.corners > 0) {
      Aabb near;
      for (std::size_t v = 0; v < on_crease.size(); ++v)
        if (on_crease[v]) near.grow(mesh.positions[v]);
      const std::vector<std::uint8_t> none(mesh.positions.size(), 0);
      const auto left = untangle(mesh, none, eval, T, near.expanded(2.0 * h), kUntangleRounds, on_crease);
      stats.crease_intersections = left.size();
      // What sliding left, collapses take away (meshers/unfold.hpp).
      if (!left.empty()) {
        stats.unfold = unfold(mesh, on_crease, left, kUnfoldRounds);
        stats.crease_intersections = stats.unfold.pairs_after;
      }
    }
  }
  stats.seconds_features = seconds_since(t0);

  // 6. Well-shaped triangles (meshers/quality.hpp), on the bricks' own tapes; crease points stay.
  //    A patch (filtered or clipped) is the local strategies' to remesh with its bands.
  if (options.quality.enabled && !options.brick_filter && !clipped) {
    SurfaceField field(graph, root, T, grid.origin, kCells * h);
    for (std::size_t a = 0; a < active.size(); ++a) field.adopt(grid.brick_at(active[a]), tapes[a]);
    const BatchField on_bricks = [&field](std::span<const glm::dvec3> p, std::span<double> v) { field.values(p, v); };
    // The feature step's work stays as it is: crease points and two rings around them.
    std::vector<std::uint8_t> keep = on_crease;
    if (!keep.empty()) {
      const std::vector<std::uint8_t> any(keep.size(), 1), near = rings_around(mesh, on_crease, any, 2);
      for (std::size_t v = 0; v < keep.size(); ++v) keep[v] |= near[v];
    }
    std::vector<std::uint8_t> crease_after;
    improve_quality(mesh, keep, on_crease, on_bricks, T, h, options.quality, &stats.quality, &crease_after);
    // A move can push a face through a sheet close by (a thin wing, two sheets beside a crease):
    // what the pass left intersecting is collapsed away too.
    {
      auto left = find_self_intersections(mesh, std::numeric_limits<std::size_t>::max()).examples;
      stats.quality_intersections = stats.crease_intersections = left.size();
      if (!left.empty()) {
        const UnfoldStats more = unfold(mesh, crease_after, std::move(left), kUnfoldRounds);
        stats.unfold.collapses += more.collapses;
        stats.unfold.seconds += more.seconds;
        stats.crease_intersections = more.pairs_after;
      }
    }
  }
  if (options.progress) options.progress(1.0);
  if (stats_out) *stats_out = stats;
  return mesh;
}

}  // namespace ht
