#include "meshers/warp_mesh.hpp"

#include "meshers/triangle_shape.hpp"
#include "nodes/warps.hpp"
#include "runtime/tape_eval.hpp"

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <unordered_map>
#include <vector>

namespace ht {
namespace {

constexpr int kMaxPasses = 10;
constexpr int kNewtonSteps = 3;
constexpr double kStretch = 1.01;  // an edge the warp lengthens by more than this is stretched

// The median of the warp's stretch (warped over child length) over the child's edges.
double median_stretch(const std::vector<glm::dvec3>& local, const std::vector<glm::dvec3>& world,
                      const std::vector<glm::uvec3>& tris) {
  std::vector<double> stretch;
  stretch.reserve(3 * tris.size());
  for (const auto& t : tris)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = t[k], b = t[(k + 1) % 3];
      const double l = glm::length(local[a] - local[b]);
      if (l > 0) stretch.push_back(glm::length(world[a] - world[b]) / l);
    }
  if (stretch.empty()) return 1.0;
  auto mid = stretch.begin() + std::ptrdiff_t(stretch.size() / 2);
  std::nth_element(stretch.begin(), mid, stretch.end());
  return *mid;
}

std::uint64_t edge_key(std::uint32_t a, std::uint32_t b) {
  return (std::uint64_t(std::min(a, b)) << 32) | std::uint64_t(std::max(a, b));
}

// Newton steps toward f = T along the gradient, for a batch of points. A point that would end
// further than reach[i] from where it started (or not finite) stays there: where no surface is
// near (a weak or negative field, a gradient almost zero) the steps fly off, and an edge split
// at a point far away comes out longer, so refinement would never end.
void project(std::vector<glm::dvec3>& pts, std::span<const double> reach, const TapeEvaluator& field, double T) {
  const std::vector<glm::dvec3> start = pts;
  std::vector<double> f(pts.size());
  std::vector<glm::dvec3> g(pts.size());
  for (int step = 0; step < kNewtonSteps; ++step) {
    field.gradient(pts, f, g);
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const double g2 = glm::dot(g[i], g[i]);
      if (g2 > 0) pts[i] -= ((f[i] - T) / g2) * g[i];
    }
  }
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const glm::dvec3 d = pts[i] - start[i];
    if (!(glm::dot(d, d) <= reach[i] * reach[i])) pts[i] = start[i];
  }
}

}  // namespace

std::function<glm::dvec3(const glm::dvec3&)> forward_map(const Graph& graph, NodeId node) {
  const NodeKind kind = graph.kind[node];
  const auto params = graph.params_of(node);
  std::vector<double> copy(params.begin(), params.end());
  return [kind, copy](const glm::dvec3& p) { return warp_forward(kind, copy.data(), p); };
}

TriangleMesh warp_mesh(const TriangleMesh& child, const std::function<glm::dvec3(const glm::dvec3&)>& warp,
                       const TapeEvaluator* field, double T, double max_edge, WarpRemeshStats* stats,
                       const Aabb* region, std::span<const std::uint8_t> only, std::size_t max_triangles,
                       double max_relative_stretch) {
  auto eligible = [&](std::uint32_t v) { return only.empty() || v >= only.size() || only[v] != 0; };
  std::vector<glm::dvec3> local = child.positions;  // child space
  std::vector<glm::uvec3> tris = child.triangles;
  std::vector<glm::dvec3> world(local.size());
  // An ffd's warp (a trivariate Bernstein sum) costs more than the rest of this function.
  tbb::parallel_for(std::size_t(0), local.size(), [&](std::size_t i) { world[i] = warp(local[i]); });
  WarpRemeshStats s;
  const double limit2 = max_edge * max_edge;
  // Across a tear, halving an edge leaves a half as long as the edge: its stretch doubles each
  // pass, and such edges are left as they are past max_relative_stretch times the median's.
  const double tear = std::isfinite(max_relative_stretch) ? max_relative_stretch * median_stretch(local, world, tris)
                                                          : std::numeric_limits<double>::infinity();
  const double tear2 = tear * tear;
  for (int pass = 0; pass < kMaxPasses; ++pass) {
    // Edges too long after warping, each once, in a deterministic order.
    std::vector<std::uint64_t> long_edges;
    for (const auto& t : tris)
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t a = t[k], b = t[(k + 1) % 3];
        // Long after warping, and longer than in the child: a rigid warp leaves the child's
        // own edges as they were (the paper: it preserves the triangles' shapes).
        const double warped2 = glm::dot(world[a] - world[b], world[a] - world[b]);
        const double local2 = glm::dot(local[a] - local[b], local[a] - local[b]);
        if (warped2 > limit2 && (region || warped2 > kStretch * kStretch * local2) &&
            (!region || region->contains(0.5 * (world[a] + world[b]))) && eligible(a) && eligible(b)) {
          if (warped2 > tear2 * local2)
            s.torn = true;
          else
            long_edges.push_back(edge_key(a, b));
        }
      }
    std::sort(long_edges.begin(), long_edges.end());
    long_edges.erase(std::unique(long_edges.begin(), long_edges.end()), long_edges.end());
    if (long_edges.empty()) break;
    // Each split edge adds one triangle on either side, at most.
    if (tris.size() + 2 * long_edges.size() > max_triangles) {
      s.stopped = true;
      break;
    }
    s.passes = pass + 1;
    s.edges_split += long_edges.size();
    // New vertices: midpoints in the child's space, projected onto the child's surface.
    // A midpoint may move up to half its edge: as far as the surface bulges from a chord.
    std::vector<glm::dvec3> mids(long_edges.size());
    std::vector<double> reach(long_edges.size());
    for (std::size_t i = 0; i < long_edges.size(); ++i) {
      const auto a = std::uint32_t(long_edges[i] >> 32), b = std::uint32_t(long_edges[i] & 0xffffffffu);
      mids[i] = 0.5 * (local[a] + local[b]);
      reach[i] = 0.5 * glm::length(local[a] - local[b]);
    }
    if (field) project(mids, reach, *field, T);
    std::unordered_map<std::uint64_t, std::uint32_t> mid_of;
    mid_of.reserve(long_edges.size() * 2);
    // Sized exactly (an insert past the capacity doubles it): the result is held as long as
    // the operand it refines.
    const std::size_t first = local.size();
    local.reserve(first + mids.size());
    local.insert(local.end(), mids.begin(), mids.end());
    world.reserve(local.size());
    world.resize(local.size());
    tbb::parallel_for(std::size_t(0), mids.size(), [&](std::size_t i) { world[first + i] = warp(mids[i]); });
    for (std::size_t i = 0; i < long_edges.size(); ++i) mid_of.emplace(long_edges[i], static_cast<std::uint32_t>(first + i));
    // Red-green refinement, orientation kept: rotate each triangle so its split edges come first.
    // The triangles with a split edge are few: those without a split end skip the lookups. A
    // triangle with c split edges becomes c + 1, counted first so the result is sized exactly.
    std::vector<std::uint8_t> split_end(local.size(), 0);
    for (const std::uint64_t e : long_edges) split_end[e >> 32] = split_end[e & 0xffffffffu] = 1;
    auto midpoints = [&](const glm::uvec3& t, std::array<std::uint32_t, 3>& m) {
      m = {kNone, kNone, kNone};
      if (!(split_end[t[0]] | split_end[t[1]] | split_end[t[2]])) return 0;
      int count = 0;
      for (int k = 0; k < 3; ++k) {
        const auto it = mid_of.find(edge_key(t[k], t[(k + 1) % 3]));
        if (it != mid_of.end()) m[std::size_t(k)] = it->second, ++count;
      }
      return count;
    };
    std::size_t made = 0;
    std::array<std::uint32_t, 3> m;
    for (const glm::uvec3& t : tris) made += std::size_t(midpoints(t, m)) + 1;
    std::vector<glm::uvec3> next;
    next.reserve(made);
    for (const glm::uvec3& t : tris) {
      const int count = midpoints(t, m);
      if (count == 0) {
        next.push_back(t);
      } else if (count == 3) {
        next.push_back({t[0], m[0], m[2]});
        next.push_back({m[0], t[1], m[1]});
        next.push_back({m[2], m[1], t[2]});
        next.push_back({m[0], m[1], m[2]});
      } else {
        // Rotate so that edge 0 (t0 -> t1) is split, and for two splits edge 1 as well.
        int r = 0;
        while (!(m[r] != kNone && (count == 1 || m[(r + 1) % 3] != kNone))) ++r;
        const std::uint32_t a = t[r], b = t[(r + 1) % 3], c = t[(r + 2) % 3];
        const std::uint32_t mab = m[r], mbc = m[(r + 1) % 3];
        if (count == 1) {
          next.push_back({a, mab, c});
          next.push_back({mab, b, c});
        } else {
          // The quad a, mab, mbc, c takes the diagonal that leaves its thinner triangle less
          // thin (a projected midpoint can put one diagonal almost along a side).
          next.push_back({mab, b, mbc});
          const double by_a = std::max(thinness(world[a], world[mab], world[mbc]), thinness(world[a], world[mbc], world[c]));
          const double by_c = std::max(thinness(world[a], world[mab], world[c]), thinness(world[mab], world[mbc], world[c]));
          if (by_c < by_a) {
            next.push_back({a, mab, c});
            next.push_back({mab, mbc, c});
          } else {
            next.push_back({a, mab, mbc});
            next.push_back({a, mbc, c});
          }
        }
      }
    }
    tris = std::move(next);
  }
  if (stats) *stats = s;
  return {std::move(world), std::move(tris)};
}

}  // namespace ht
