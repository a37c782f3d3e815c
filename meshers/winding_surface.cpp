#include "meshers/winding_surface.hpp"

#include "meshers/mesh_checks.hpp"
#include "meshers/self_intersections.hpp"
#include "meshers/union_find.hpp"
#include "nodes/winding.hpp"

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
  // A step of a thousandth of the triangle's size off its centroid: a shell nearer than that on
  // either side, or the shell itself folded back that close, shows as a wrong winding number
  // and only costs the polygonization.
  const WindingTree winding(m.positions, m.triangles);
  for (std::uint32_t s = 0; s < m.positions.size(); ++s) {
    if (largest[s] < 0) continue;
    const glm::uvec3& t = m.triangles[pick[s]];
    const glm::dvec3 a = m.positions[t[0]], b = m.positions[t[1]], c = m.positions[t[2]];
    const glm::dvec3 normal = glm::normalize(glm::cross(b - a, c - a)), centre = (a + b + c) / 3.0;
    const double step = 1e-3 * std::sqrt(0.5 * largest[s]);
    const double behind = winding.estimate(centre - step * normal, 0.0, 1e-3).w;
    const double ahead = winding.estimate(centre + step * normal, 0.0, 1e-3).w;
    if (!(std::abs(behind - 1.0) < 0.25 && std::abs(ahead) < 0.25)) return false;
  }
  return true;
}

}  // namespace ht
