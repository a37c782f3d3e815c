// Vertices whose fan of triangles is certainly embedded: no two of its triangles meet beyond the
// edges and the vertex they share. The self-intersection search (meshers/self_intersections.hpp)
// skips every candidate pair that shares such a vertex; on a well-shaped closed mesh that is
// 99% of the pairs whose boxes overlap (on the 250-curve snake's 81k triangles, 500k of 505k).
//
// The certificate. Project the fan of v along some direction n onto a plane (any linear map P
// onto R^2). If every triangle (v, a, b) of the fan, with its corners in the mesh's order,
// projects to a triangle turning counter-clockwise, and the projected link a -> b closes into
// cycles that wind around P(v) exactly once in all, the projected triangles tile a star-shaped
// polygon around P(v) without overlap. P is then one-to-one on each triangle, so a point where
// two fan triangles meet projects to where their projections meet: their shared edge or P(v),
// whose preimages in both are that edge or v. Hence the fan is embedded in space.
//
// Rounding. Each projected corner is computed once per fan and used by both triangles it
// belongs to; a triangle counts only when its projected turn exceeds kMargin (1e-8) times the
// product of its two sides in space, which bound the rounding of the differences and dot products
// (below 1e-15 of them). Against the projected sides it would not be sound: a corner almost along
// the projection's direction has a tiny projection whose direction rounding can turn (a review
// built such a fan whose exact fold passed). The exact projection's turns then have the same signs and
// the winding number, a sum of angles each strictly between 0 and pi, cannot change between the
// computed and the exact corners. So a certified fan is embedded in exact arithmetic: skipping
// its pairs loses no intersection the exact tests would find. A fan that fails is simply not
// certified (its pairs are tested).
#pragma once

#include "meshers/triangle_mesh.hpp"

#include <cstdint>
#include <vector>

namespace ht {

/// One byte per vertex of `mesh`: 1 when the fan of triangles using that vertex (by index) is
/// certified embedded (above), else 0 (no triangles, a boundary or a pinch, a fold, a corner
/// repeated in a triangle, a turn too small to decide, more than 64 triangles). Positions must be
/// finite. O(n) time and memory; uses the TBB thread pool; deterministic; reads `mesh` only
/// (thread-safe).
std::vector<std::uint8_t> embedded_fans(const TriangleMesh& mesh);

}  // namespace ht
