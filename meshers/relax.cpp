#include "meshers/relax.hpp"

#include "meshers/bridge.hpp"
#include "meshers/self_intersections.hpp"
#include "runtime/tape_eval.hpp"

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numeric>

namespace ht {
namespace {

constexpr double kSettled = 1e-3;  // of a ring's mean edge: a Newton step this short is the last

// The neighbours of the chosen vertices only (one scan of the triangles, no sort of the
// whole mesh): rows in the order of `chosen`.
struct Neighbours {
  std::vector<std::uint32_t> begin, list;
};

Neighbours neighbours_of(const TriangleMesh& m, const std::vector<std::uint32_t>& chosen) {
  std::vector<std::uint32_t> row(m.positions.size(), ~0u);
  for (std::uint32_t i = 0; i < chosen.size(); ++i) row[chosen[i]] = i;
  std::vector<std::vector<std::uint32_t>> rows(chosen.size());
  for (const glm::uvec3& t : m.triangles)
    for (int k = 0; k < 3; ++k)
      if (row[t[k]] != ~0u) {
        rows[row[t[k]]].push_back(t[(k + 1) % 3]);
        rows[row[t[k]]].push_back(t[(k + 2) % 3]);
      }
  Neighbours n;
  n.begin.push_back(0);
  for (auto& r : rows) {
    std::sort(r.begin(), r.end());
    r.erase(std::unique(r.begin(), r.end()), r.end());
    n.list.insert(n.list.end(), r.begin(), r.end());
    n.begin.push_back(std::uint32_t(n.list.size()));
  }
  return n;
}

// Newton steps onto {f = T}.
void project(std::vector<glm::dvec3>& at, const BatchGradient& field, double T, int steps) {
  std::vector<glm::dvec3> grad(at.size());
  std::vector<double> value(at.size());
  for (int s = 0; s < steps; ++s) {
    field(at, value, grad);
    for (std::size_t i = 0; i < at.size(); ++i) {
      const double g2 = glm::dot(grad[i], grad[i]);
      if (g2 > 0 && std::isfinite(g2)) at[i] -= (value[i] - T) / g2 * grad[i];
    }
  }
}

// Each chosen crease vertex with exactly two crease neighbours moves halfway to their midpoint:
// along the chord of its crease, which stays within a sliver of the crease (a chord of length l
// is at most l^2 / (8 r) from a crease of radius r), so the edge stays sharp.
void slide_along_creases(TriangleMesh& mesh, std::span<const std::uint8_t> chosen, std::span<const std::uint8_t> fixed,
                         std::span<const std::uint8_t> crease) {
  std::vector<std::uint32_t> picked;
  for (std::uint32_t v = 0; v < mesh.positions.size(); ++v)
    if (chosen[v] && crease[v] && !fixed[v]) picked.push_back(v);
  const Neighbours n = neighbours_of(mesh, picked);
  std::vector<glm::dvec3> to(picked.size());
  for (std::size_t i = 0; i < picked.size(); ++i) {
    to[i] = mesh.positions[picked[i]];
    std::uint32_t ends[2], count = 0;
    for (std::uint32_t k = n.begin[i]; k < n.begin[i + 1]; ++k)
      if (crease[n.list[k]] && count++ < 2) ends[count - 1] = n.list[k];
    if (count == 2) to[i] = 0.5 * to[i] + 0.25 * (mesh.positions[ends[0]] + mesh.positions[ends[1]]);
  }
  for (std::size_t i = 0; i < picked.size(); ++i) mesh.positions[picked[i]] = to[i];
}

// The intersecting pairs among the triangles `take` accepts, as indices in `mesh`.
template <class Take>
std::vector<std::array<std::uint32_t, 2>> intersections_among(const TriangleMesh& mesh, Take take) {
  // The taken triangles with their own vertices only (renumbered in order: which corners are
  // shared is what the search reads, not the numbers), counted first to size the arrays.
  TriangleMesh near;
  std::vector<std::uint32_t> source, vertex(mesh.positions.size(), ~0u);
  std::size_t used = 0;
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
    if (take(t)) {
      source.push_back(t);
      for (int k = 0; k < 3; ++k) used += vertex[mesh.triangles[t][k]] == ~0u, vertex[mesh.triangles[t][k]] = 0;
    }
  std::fill(vertex.begin(), vertex.end(), ~0u);
  near.positions.reserve(used);
  near.triangles.reserve(source.size());
  for (const std::uint32_t t : source) {
    glm::uvec3 tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      if (vertex[tri[k]] == ~0u) {
        vertex[tri[k]] = std::uint32_t(near.positions.size());
        near.positions.push_back(mesh.positions[tri[k]]);
      }
      tri[k] = vertex[tri[k]];
    }
    near.triangles.push_back(tri);
  }
  std::vector<std::array<std::uint32_t, 2>> pairs = find_self_intersections(near, std::size_t(-1)).examples;
  for (auto& p : pairs) p = {source[p[0]], source[p[1]]};
  return pairs;
}

}  // namespace

void relax_boundary(TriangleMesh& mesh, const BatchGradient& field, double T, int iterations) {
  const auto loops = boundary_loops(mesh);
  std::vector<std::uint8_t> on_loop(mesh.positions.size(), 0), all(mesh.positions.size(), 1);
  for (const auto& l : loops)
    for (std::uint32_t v : l) on_loop[v] = 1;
  const std::vector<std::uint8_t> behind = rings_around(mesh, on_loop, all, 1);
  for (int it = 0; it < iterations; ++it) {
    for (const auto& l : loops) {
      std::vector<glm::dvec3> at(l.size());
      for (std::size_t k = 0; k < l.size(); ++k) {
        const glm::dvec3 p = mesh.positions[l[k]];
        const glm::dvec3 mid = 0.5 * (mesh.positions[l[(k + 1) % l.size()]] + mesh.positions[l[(k + l.size() - 1) % l.size()]]);
        at[k] = p + 0.5 * (mid - p);
      }
      project(at, field, T, 2);
      for (std::size_t k = 0; k < l.size(); ++k) mesh.positions[l[k]] = at[k];
    }
    relax_vertices(mesh, behind, field, T, {1, 2});
  }
}

double longest_edge(const TriangleMesh& mesh) {
  // A maximum: the same whichever way the ranges split.
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, mesh.triangles.size(), 4096), 0.0,
      [&](const tbb::blocked_range<std::size_t>& r, double longest) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          const glm::uvec3& t = mesh.triangles[i];
          for (int k = 0; k < 3; ++k)
            longest = std::max(longest, glm::length(mesh.positions[t[k]] - mesh.positions[t[(k + 1) % 3]]));
        }
        return longest;
      },
      [](double a, double b) { return std::max(a, b); });
}

std::vector<std::array<std::uint32_t, 2>> intersections_in(const TriangleMesh& mesh, const Aabb& region) {
  return intersections_among(mesh, [&](std::uint32_t t) {
    Aabb box;
    for (int k = 0; k < 3; ++k) box.grow(mesh.positions[mesh.triangles[t][k]]);
    return !intersect(box, region).empty();
  });
}

// The intersecting pairs near the vertices `hit` marks, after their triangles and one ring moved:
// a triangle that meets a moved one has its vertices within three of the mesh's longest edges of
// a hit vertex, so only triangles with a vertex in the cells (of that edge's size) three around
// the hit vertices' cells are searched (those that meet `region`, as intersections_in does).
std::vector<std::array<std::uint32_t, 2>> intersections_near(const TriangleMesh& mesh, std::span<const std::uint8_t> hit,
                                                             double longest_edge, const Aabb& region) {
  auto cell_of = [&](const glm::dvec3& p) { return glm::i64vec3(glm::floor(p / longest_edge)); };
  auto key = [](glm::i64vec3 c) {
    return std::uint64_t(c.x & 0x1fffff) | std::uint64_t(c.y & 0x1fffff) << 21 | std::uint64_t(c.z & 0x1fffff) << 42;
  };
  std::vector<std::uint64_t> cells;
  for (std::size_t v = 0; v < hit.size(); ++v)
    if (hit[v])
      for (int dz = -3; dz <= 3; ++dz)
        for (int dy = -3; dy <= 3; ++dy)
          for (int dx = -3; dx <= 3; ++dx) cells.push_back(key(cell_of(mesh.positions[v]) + glm::i64vec3(dx, dy, dz)));
  std::sort(cells.begin(), cells.end());
  cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
  std::vector<std::uint8_t> near(mesh.positions.size(), 0);
  for (std::size_t v = 0; v < near.size(); ++v) near[v] = std::binary_search(cells.begin(), cells.end(), key(cell_of(mesh.positions[v])));
  return intersections_among(mesh, [&](std::uint32_t t) {
    const glm::uvec3 tri = mesh.triangles[t];
    if (!near[tri[0]] && !near[tri[1]] && !near[tri[2]]) return false;
    Aabb box;
    for (int k = 0; k < 3; ++k) box.grow(mesh.positions[tri[k]]);
    return !intersect(box, region).empty();
  });
}

std::vector<std::array<std::uint32_t, 2>> untangle(TriangleMesh& mesh, std::span<const std::uint8_t> fixed,
                                                   const BatchGradient& field, double T, const Aabb& region, int rounds,
                                                   std::span<const std::uint8_t> crease, std::span<const std::uint8_t> changed) {
  std::vector<std::uint8_t> far(mesh.positions.size());
  for (std::size_t v = 0; v < far.size(); ++v) far[v] = !fixed[v] && (crease.empty() || !crease[v]);
  // Beside a crease, a vertex's projection may land on the other sheet and round the edge: only
  // the crease slides there.
  if (!crease.empty()) {
    const std::vector<std::uint8_t> any(mesh.positions.size(), 1), beside = rings_around(mesh, crease, any, 1);
    for (std::size_t v = 0; v < far.size(); ++v) far[v] &= !beside[v];
  }
  const double longest = longest_edge(mesh);
  // Moves reach one ring beyond the hit vertices: later rounds search only around them.
  std::vector<std::uint8_t> hit(changed.begin(), changed.end());
  for (int r = 0;; ++r) {
    const auto pairs = r == 0 && changed.empty() ? intersections_in(mesh, region) : intersections_near(mesh, hit, longest, region);
    if (pairs.empty() || r == rounds) return pairs;
    hit.assign(mesh.positions.size(), 0);
    for (const auto& pair : pairs)
      for (std::uint32_t t : pair)
        for (int k = 0; k < 3; ++k) hit[mesh.triangles[t][k]] = 1;
    if (!crease.empty()) slide_along_creases(mesh, hit, fixed, crease);
    std::vector<std::uint8_t> movable = rings_around(mesh, hit, far, 1);
    for (std::size_t v = 0; v < movable.size(); ++v) movable[v] |= hit[v] && far[v];
    relax_vertices(mesh, movable, field, T, {2, 2});
  }
}

std::vector<std::uint8_t> rings_around(const TriangleMesh& mesh, std::span<const std::uint8_t> seeds,
                                       std::span<const std::uint8_t> allowed, int rings) {
  std::vector<std::uint8_t> reached(seeds.begin(), seeds.end()), out(mesh.positions.size(), 0);
  for (int r = 0; r < rings; ++r) {
    std::vector<std::uint8_t> next = reached;
    // Triangles in parallel: a flag is only ever set to 1, so any order of the stores leaves the
    // same flags (atomic stores, since two triangles may set one vertex's at once).
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.triangles.size(), 4096), [&](const tbb::blocked_range<std::size_t>& range) {
      for (std::size_t i = range.begin(); i != range.end(); ++i) {
        const glm::uvec3& t = mesh.triangles[i];
        if (!reached[t[0]] && !reached[t[1]] && !reached[t[2]]) continue;
        for (int k = 0; k < 3; ++k)
          if (!reached[t[k]] && allowed[t[k]] && !seeds[t[k]]) {
            std::atomic_ref<std::uint8_t>(next[t[k]]).store(1, std::memory_order_relaxed);
            std::atomic_ref<std::uint8_t>(out[t[k]]).store(1, std::memory_order_relaxed);
          }
      }
    });
    reached.swap(next);
  }
  return out;
}

void newton_onto(std::vector<glm::dvec3>& at, const BatchGradient& field, double T, int steps,
                 std::span<const double> settled, std::span<glm::dvec3> last_gradient) {
  std::vector<std::uint32_t> who(at.size());
  std::iota(who.begin(), who.end(), 0u);
  std::vector<glm::dvec3> pts, grad;
  std::vector<double> value;
  for (int s = 0; s < steps && !who.empty(); ++s) {
    pts.resize(who.size()), grad.resize(who.size()), value.resize(who.size());
    for (std::size_t k = 0; k < who.size(); ++k) pts[k] = at[who[k]];
    field(pts, value, grad);
    std::size_t kept = 0;
    for (std::size_t k = 0; k < who.size(); ++k) {
      if (!last_gradient.empty()) last_gradient[who[k]] = grad[k];
      const double g2 = glm::dot(grad[k], grad[k]);
      if (!(g2 > 0 && std::isfinite(g2))) continue;
      const double step = (value[k] - T) / g2;
      at[who[k]] -= step * grad[k];
      if (std::abs(step) * std::sqrt(g2) > settled[who[k]]) who[kept++] = who[k];
    }
    who.resize(kept);
  }
}

void relax_vertices(TriangleMesh& mesh, std::span<const std::uint8_t> movable, const BatchGradient& field, double T,
                    const RelaxOptions& o) {
  std::vector<std::uint32_t> moving;
  for (std::uint32_t v = 0; v < mesh.positions.size(); ++v)
    if (movable[v]) moving.push_back(v);
  if (moving.empty()) return;
  const Neighbours n = neighbours_of(mesh, moving);
  std::vector<glm::dvec3> at(moving.size()), grad(moving.size());
  std::vector<double> settled(moving.size());
  for (int it = 0; it < o.iterations; ++it) {
    for (std::size_t i = 0; i < moving.size(); ++i) at[i] = mesh.positions[moving[i]];
    // The tangent planes: after the first round, the gradients where the last Newton steps began
    // (a settled step's length from the point) stand in for a field call of their own.
    if (it == 0) field(at, {}, grad);
    for (std::size_t i = 0; i < moving.size(); ++i) {
      glm::dvec3 c(0.0);
      double ring = 0.0;
      for (std::uint32_t k = n.begin[i]; k < n.begin[i + 1]; ++k)
        c += mesh.positions[n.list[k]], ring += glm::length(mesh.positions[n.list[k]] - at[i]);
      const double count = double(std::max<std::uint32_t>(1, n.begin[i + 1] - n.begin[i]));
      c /= count;
      settled[i] = kSettled * ring / count;
      const double len = glm::length(grad[i]);
      glm::dvec3 d = c - at[i];
      if (len > 0 && std::isfinite(len)) d -= glm::dot(d, grad[i] / len) * (grad[i] / len);
      at[i] += d;
    }
    // Newton steps until a point's step is under kSettled of its ring's mean edge.
    newton_onto(at, field, T, o.newton_steps, settled, grad);
    for (std::size_t i = 0; i < moving.size(); ++i) mesh.positions[moving[i]] = at[i];
  }
}

}  // namespace ht
