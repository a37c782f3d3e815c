// The boundary of a triangle mesh in linear time: the edges that exactly one triangle uses, found
// from the sides filed under their lower vertex (nodes/edge_keys.hpp) instead of sorting them all.
// The local strategies call it on whole operand meshes, where a sort would dominate; its scratch
// is eight bytes a side and eight a vertex.
#pragma once

#include "meshers/triangle_mesh.hpp"

#include <cstdint>
#include <vector>

namespace ht {

struct BoundaryEdge {
  std::uint32_t from, to;  ///< in the direction the triangle runs along it
  std::uint32_t slot;      ///< 3 * triangle + the corner where the edge starts
};

/// Every edge used by exactly one triangle, ordered by its lower vertex, then its upper one.
std::vector<BoundaryEdge> boundary_edges(const TriangleMesh& mesh);

}  // namespace ht
