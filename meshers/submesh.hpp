// A region of a mesh taken out to be reworked on its own and put back: what the remeshing and
// quality passes do when only part of a mesh may change (a local strategy's seams and patches,
// while the operands' own triangles stay bit for bit).
#pragma once

#include "meshers/triangle_mesh.hpp"
#include "nodes/trimesh.hpp"

#include <cstdint>
#include <span>
#include <vector>

namespace ht {

struct Submesh {
  TriangleMesh mesh;                  ///< the triangles taken, their vertices numbered anew
  std::vector<std::uint32_t> origin;  ///< each taken vertex's index in the whole mesh
  /// Taken vertices that must stay: outside the region, or used by a triangle not taken too.
  std::vector<std::uint8_t> rim;
  std::vector<glm::uvec3> rest;       ///< the triangles not taken, in their order
};

/// Takes the triangles with a corner in `region` (one flag per vertex). Where the taken
/// triangles would touch themselves at a vertex (a pinch OpenMesh cannot hold), the whole fan of
/// that vertex is taken too.
Submesh take_region(const TriangleMesh& mesh, std::span<const std::uint8_t> region);

/// Puts the reworked region back. `changed` is the region after the work and `origin` gives each
/// of its vertices' index in the whole mesh, or ~0u for a new vertex. Surviving vertices keep
/// their order, new ones follow, unused ones are dropped; the untaken triangles come first.
void put_back(TriangleMesh& mesh, const Submesh& sub, const TriangleMesh& changed, std::span<const std::uint32_t> origin);

/// Loads `mesh` into an empty `m` for editing (vertex, edge, halfedge and face status requested,
/// as collapses and flips need): vertex v gets locked[v] (or false) and origin[v] (or v when
/// `origin` is empty) in the two properties, which it adds. False when OpenMesh refuses a face
/// (the mesh is not a manifold it can hold).
bool to_openmesh(const TriangleMesh& mesh, std::span<const std::uint8_t> locked, std::span<const std::uint32_t> origin,
                 TriMesh& m, OpenMesh::VPropHandleT<bool>& locked_prop, OpenMesh::VPropHandleT<std::uint32_t>& origin_prop);

/// A reworked OpenMesh region back in flat arrays: garbage-collects `m`, then writes its vertices
/// and triangles in handle order and each vertex's `origin` property.
void from_openmesh(TriMesh& m, OpenMesh::VPropHandleT<std::uint32_t> origin, TriangleMesh& out,
                   std::vector<std::uint32_t>& origins);

}  // namespace ht
