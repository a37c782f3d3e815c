#include "meshers/winding_surface.hpp"

#include "meshers/mesh_checks.hpp"
#include "meshers/self_intersections.hpp"
#include "meshers/union_find.hpp"

#include <glm/geometric.hpp>

#include <cmath>
#include <vector>

namespace ht {

bool winding_leaf_is_its_surface(const MeshLeaf& leaf) {
  if (leaf.inside_mode() == MeshInside::Closed) return true;
  const TriangleMesh& m = *leaf.surface();
  if (m.triangles.empty() || !check_watertight(m).watertight()) return false;
  if (find_self_intersections(m, 0).pairs != 0) return false;
  // Each shell's largest triangle (the first of equals), by the shell's first vertex.
  UnionFind shells(m.positions.size());
  for (const glm::uvec3& t : m.triangles) shells.unite(t[0], t[1]), shells.unite(t[0], t[2]);
  std::vector<double> largest(m.positions.size(), -1.0);
  std::vector<std::uint32_t> pick(m.positions.size(), 0);
  for (std::uint32_t i = 0; i < m.triangles.size(); ++i) {
    const glm::uvec3& t = m.triangles[i];
    const double area = glm::length(glm::cross(m.positions[t[1]] - m.positions[t[0]], m.positions[t[2]] - m.positions[t[0]]));
    const std::uint32_t s = shells.find(t[0]);
    if (area > largest[s]) largest[s] = area, pick[s] = i;
  }
  // The winding number a step off the triangle's centroid on either side, the step short enough
  // that nothing else lies within it: the nearest triangle to each end is then no nearer than the
  // step, as it would be were another surface crossed on the way (a plate a hair inside a wall).
  for (std::uint32_t s = 0; s < m.positions.size(); ++s) {
    if (largest[s] < 0) continue;
    const glm::uvec3& t = m.triangles[pick[s]];
    const glm::dvec3 a = m.positions[t[0]], b = m.positions[t[1]], c = m.positions[t[2]];
    const glm::dvec3 normal = glm::normalize(glm::cross(b - a, c - a)), centre = (a + b + c) / 3.0;
    bool checked = false;
    for (const double fraction : {1e-3, 1e-5, 1e-7}) {
      const double step = fraction * std::sqrt(0.5 * largest[s]);
      const glm::dvec3 behind = centre - step * normal, ahead = centre + step * normal;
      if (!(leaf.query(behind, 2.0 * step).distance >= 0.999 * step && leaf.query(ahead, 2.0 * step).distance >= 0.999 * step))
        continue;
      const double w_behind = leaf.winding_number(behind, 1e-3), w_ahead = leaf.winding_number(ahead, 1e-3);
      if (!(std::abs(w_behind - 1.0) < 0.25 && std::abs(w_ahead) < 0.25)) return false;
      checked = true;
      break;
    }
    if (!checked) return false;
  }
  return true;
}

}  // namespace ht
