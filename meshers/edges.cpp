#include "meshers/edges.hpp"

#include "meshers/edge_sides.hpp"

namespace ht {

std::vector<BoundaryEdge> boundary_edges(const TriangleMesh& mesh) {
  const std::vector<Side> sides = sides_by_edge(mesh.positions.size(), mesh.triangles);
  std::vector<BoundaryEdge> out;
  for_each_edge(sides, [&](std::span<const Side> run) {
    if (run.size() != 1) return;  // an edge used once
    const Side& s = run[0];
    out.push_back({mesh.triangles[s.tri][s.corner], mesh.triangles[s.tri][(s.corner + 1) % 3], 3 * s.tri + s.corner});
  });
  return out;
}

}  // namespace ht
