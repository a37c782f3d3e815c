// Loading triangles into OpenMesh in bulk.
//
// OpenMesh's add_face links one face at a time: it looks for each side's edge among the corner's
// outgoing halfedges, checks the corners are on the boundary and relinks boundary patches. Loading
// whole slabs that way was a sixth of the quality pass. When the triangles form a manifold (each
// edge has one side or two walked in opposite directions, each vertex one fan of triangles), every
// link follows from the sides grouped by edge (meshers/edge_sides.hpp), and they are set directly.
#pragma once

#include "nodes/trimesh.hpp"

#include <glm/vec3.hpp>

#include <span>

namespace ht {

/// Adds `triangles` (indices of m's vertices) to `m`, which holds vertices and no edge or face yet,
/// when they form a manifold; otherwise returns false and leaves `m` as it was (add_face then
/// decides what OpenMesh can hold). Edges are numbered as add_face numbers them (in order of first
/// use, halfedge 0 along the first triangle that uses it), each face's halfedge is its last side as
/// with add_face; a vertex's outgoing halfedge is its boundary one, or else its side in the first
/// triangle that uses it.
bool link_manifold_triangles(TriMesh& m, std::span<const glm::uvec3> triangles);

}  // namespace ht
