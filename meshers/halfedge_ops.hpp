// OpenMesh's edge collapse and flip and their validity checks, compiled here.
//
// Debian's libopenmesh is built with assertions on, and every status or property access inside
// the library then builds the property's type name as a std::string (35 characters: a heap
// allocation and a free) to compare it with the stored one. TriConnectivity::is_collapse_ok makes
// about twenty such accesses a call and PolyConnectivity::collapse about as many: measured with
// callgrind on the snake-woman's Table 1 row, 7,800 and 9,100 instructions a call, 7% of the
// whole run (TriConnectivity::flip even checks is_flip_ok again in an assertion). The same steps written against OpenMesh's inline accessors (its headers, compiled
// with this project's NDEBUG) cost a few hundred. They are OpenMesh's operations, not new ones:
// tests/test_halfedge_ops.cpp holds them to the library's own on random sequences of collapses
// and flips (the same verdict on every edge, the same links, handles and deletion flags after
// each step).
#pragma once

#include "nodes/trimesh.hpp"

namespace ht {

/// The verdict of `m.is_collapse_ok(h)`: false when the edge or an end is deleted, when a
/// triangle on the edge has its two other edges on the boundary, when the far corners of the
/// edge's two sides coincide (or both sides are boundary), when both ends lie on the boundary but
/// the edge does not, or when the ends' one-rings share a vertex besides those far corners (the
/// link condition). Unlike OpenMesh's, it leaves the vertices' `tagged` flags alone. `m` needs
/// vertex and edge status. O(valence^2); reads `m` only.
bool collapse_ok(const TriMesh& m, TriMesh::HalfedgeHandle h);

/// What `m.collapse(h)` does to a triangle mesh: the from-vertex of `h` goes into its
/// to-vertex, the edge and the triangles on it are deleted (marked; garbage collection is the
/// caller's), and the links, outgoing halfedges and face halfedges come out as OpenMesh sets them.
/// The caller checks collapse_ok() first. `m` needs vertex, edge and face status. O(valence).
void collapse(TriMesh& m, TriMesh::HalfedgeHandle h);

/// The verdict of `m.is_flip_ok(e)`: false on a boundary edge, and when the far corners of its
/// two triangles coincide or are joined by an edge already. O(valence); reads `m` only.
bool flip_ok(const TriMesh& m, TriMesh::EdgeHandle e);

/// What `m.flip(e)` does: the edge turns to join the far corners of its two triangles, with the
/// same halfedges, faces and outgoing halfedges as OpenMesh leaves. The caller checks flip_ok()
/// first. O(1).
void flip(TriMesh& m, TriMesh::EdgeHandle e);

/// The number of edges at `v` (`m.valence(v)`). O(valence).
unsigned valence(const TriMesh& m, TriMesh::VertexHandle v);

}  // namespace ht
