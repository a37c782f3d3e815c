#include "meshers/relax.hpp"

#include "meshers/bridge.hpp"
#include "meshers/self_intersections.hpp"
#include "runtime/tape_eval.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

namespace ht {
namespace {

// Vertex neighbours in compressed rows (each undirected edge seen from both ends, duplicates
// removed).
struct Neighbours {
  std::vector<std::uint32_t> begin, list;
};

Neighbours neighbours(const TriangleMesh& m) {
  std::vector<std::uint64_t> pairs;
  pairs.reserve(6 * m.triangles.size());
  for (const glm::uvec3& t : m.triangles)
    for (int k = 0; k < 3; ++k) {
      const std::uint64_t a = t[k], b = t[(k + 1) % 3];
      pairs.push_back(a << 32 | b);
      pairs.push_back(b << 32 | a);
    }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  Neighbours n;
  n.begin.assign(m.positions.size() + 1, 0);
  for (std::uint64_t p : pairs) ++n.begin[(p >> 32) + 1];
  for (std::size_t v = 0; v < m.positions.size(); ++v) n.begin[v + 1] += n.begin[v];
  n.list.reserve(pairs.size());
  for (std::uint64_t p : pairs) n.list.push_back(std::uint32_t(p));
  return n;
}

// Newton steps onto {f = T}.
void project(std::vector<glm::dvec3>& at, const TapeEvaluator& field, double T, int steps) {
  std::vector<glm::dvec3> grad(at.size());
  std::vector<double> value(at.size());
  for (int s = 0; s < steps; ++s) {
    field.gradient(at, value, grad);
    for (std::size_t i = 0; i < at.size(); ++i) {
      const double g2 = glm::dot(grad[i], grad[i]);
      if (g2 > 0 && std::isfinite(g2)) at[i] -= (value[i] - T) / g2 * grad[i];
    }
  }
}

}  // namespace

void relax_boundary(TriangleMesh& mesh, const TapeEvaluator& field, double T, int iterations) {
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

std::size_t untangle(TriangleMesh& mesh, std::span<const std::uint8_t> fixed, const TapeEvaluator& field, double T,
                     int rounds) {
  std::vector<std::uint8_t> free(mesh.positions.size());
  for (std::size_t v = 0; v < free.size(); ++v) free[v] = !fixed[v];
  for (int r = 0;; ++r) {
    const SelfIntersections si = find_self_intersections(mesh, std::size_t(-1));
    if (si.pairs == 0 || r == rounds) return si.pairs;
    std::vector<std::uint8_t> hit(mesh.positions.size(), 0);
    for (const auto& pair : si.examples)
      for (std::uint32_t t : pair)
        for (int k = 0; k < 3; ++k) hit[mesh.triangles[t][k]] = 1;
    std::vector<std::uint8_t> movable = rings_around(mesh, hit, free, 1);
    for (std::size_t v = 0; v < movable.size(); ++v) movable[v] |= hit[v] && free[v];
    relax_vertices(mesh, movable, field, T, {2, 2});
  }
}

std::vector<std::uint8_t> rings_around(const TriangleMesh& mesh, std::span<const std::uint8_t> seeds,
                                       std::span<const std::uint8_t> allowed, int rings) {
  const Neighbours n = neighbours(mesh);
  std::vector<std::uint8_t> out(mesh.positions.size(), 0);
  std::vector<std::uint32_t> front, next;
  for (std::uint32_t v = 0; v < mesh.positions.size(); ++v)
    if (seeds[v]) front.push_back(v);
  for (int r = 0; r < rings; ++r) {
    next.clear();
    for (std::uint32_t v : front)
      for (std::uint32_t i = n.begin[v]; i < n.begin[v + 1]; ++i) {
        const std::uint32_t w = n.list[i];
        if (seeds[w] || out[w] || !allowed[w]) continue;
        out[w] = 1;
        next.push_back(w);
      }
    std::sort(next.begin(), next.end());
    front.swap(next);
  }
  return out;
}

void relax_vertices(TriangleMesh& mesh, std::span<const std::uint8_t> movable, const TapeEvaluator& field, double T,
                    const RelaxOptions& o) {
  std::vector<std::uint32_t> moving;
  for (std::uint32_t v = 0; v < mesh.positions.size(); ++v)
    if (movable[v]) moving.push_back(v);
  if (moving.empty()) return;
  const Neighbours n = neighbours(mesh);
  std::vector<glm::dvec3> at(moving.size()), grad(moving.size());
  std::vector<double> value(moving.size());
  for (int it = 0; it < o.iterations; ++it) {
    for (std::size_t i = 0; i < moving.size(); ++i) at[i] = mesh.positions[moving[i]];
    field.gradient(at, {}, grad);
    for (std::size_t i = 0; i < moving.size(); ++i) {
      const std::uint32_t v = moving[i];
      glm::dvec3 c(0.0);
      for (std::uint32_t k = n.begin[v]; k < n.begin[v + 1]; ++k) c += mesh.positions[n.list[k]];
      c /= double(n.begin[v + 1] - n.begin[v]);
      const double len = glm::length(grad[i]);
      glm::dvec3 d = c - at[i];
      if (len > 0 && std::isfinite(len)) d -= glm::dot(d, grad[i] / len) * (grad[i] / len);
      at[i] += d;
    }
    for (int s = 0; s < o.newton_steps; ++s) {
      field.gradient(at, value, grad);
      for (std::size_t i = 0; i < moving.size(); ++i) {
        const double g2 = glm::dot(grad[i], grad[i]);
        if (g2 > 0 && std::isfinite(g2)) at[i] -= (value[i] - T) / g2 * grad[i];
      }
    }
    for (std::size_t i = 0; i < moving.size(); ++i) mesh.positions[moving[i]] = at[i];
  }
}

}  // namespace ht
