#include "meshers/edges.hpp"

#include "meshers/edge_sides.hpp"

namespace ht {

std::vector<BoundaryEdge> boundary_edges(const TriangleMesh& mesh) {
  const std::vector<Side> sides = sides_by_edge(mesh.positions.size(), mesh.triangles);
  std::vector<BoundaryEdge> out;
  for (std::size_t i = 0; i < sides.size();) {
    std::size_t j = i + 1;
    while (j < sides.size() && sides[j].lo == sides[i].lo && sides[j].hi == sides[i].hi) ++j;
    if (j - i == 1) {  // an edge used once
      const Side& s = sides[i];
      out.push_back({mesh.triangles[s.tri][s.corner], mesh.triangles[s.tri][(s.corner + 1) % 3], 3 * s.tri + s.corner});
    }
    i = j;
  }
  return out;
}

}  // namespace ht
