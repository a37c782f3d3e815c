// Whether a winding leaf's own triangles are its solid's surface.
//
// A mesh leaf with "inside": "winding" may be open, non-manifold or crossing itself, so the mesh
// plan polygonizes its solid ({w > 1/2}, nodes/winding.hpp) instead of returning its triangles.
// Many such files are clean closed meshes all the same (the user asked for winding to be safe),
// and there the triangles are the surface: polygonizing them cost knot2.off 15 s at precision
// 0.015 (the quality pass's Newton steps each pay for winding numbers near the surface).
#pragma once

#include "nodes/mesh_leaf.hpp"

namespace ht {

/// True when `leaf`'s triangles bound {w > 1/2} exactly: closed, manifold, consistently oriented
/// and without degenerate triangles (check_watertight), crossing nowhere (exact predicates:
/// meshers/self_intersections.hpp), and every shell has winding number 1 just behind its largest
/// triangle and 0 just in front of it, a step off that no other triangle comes within (so no
/// shell is turned inward into a solid, nor nested in another of the same orientation, where w
/// would be 2 or -1 and the shell no boundary). For a closed leaf, true as well. O(n log n);
/// thread-safe.
bool winding_leaf_is_its_surface(const MeshLeaf& leaf);

}  // namespace ht
