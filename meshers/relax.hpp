// Tangential relaxation with projection: the vertices a caller chooses move toward the centroid
// of their neighbours within their tangent plane, then back onto the surface {f = T} by Newton
// steps on the field's gradients (meshers/batch_field.hpp: a tape's, or a SurfaceField's bricks').
// The local strategies run it on the few rings of patch vertices next to a seam, where moving
// the seam onto the exact operand's polyline left thin or folded triangles.
//
// Jacobi iterations (every vertex moves from the previous iteration's positions), so the result
// does not depend on the order of vertices or on the thread count.
#pragma once

#include "meshers/batch_field.hpp"
#include "meshers/triangle_mesh.hpp"
#include "runtime/aabb.hpp"

#include <array>

#include <cstdint>
#include <span>
#include <vector>

namespace ht {

struct RelaxOptions {
  int iterations = 4;
  int newton_steps = 2;
};

/// Moves the vertices with movable[v] != 0; every other vertex stays bit for bit.
void relax_vertices(TriangleMesh& mesh, std::span<const std::uint8_t> movable, const BatchGradient& field, double threshold,
                    const RelaxOptions& options = {});

/// Newton steps onto {f = T} along the gradient, at most `steps`: a point whose step was no longer
/// than settled[i] (world units) takes no more, the next being about the curvature times that
/// step squared. `last_gradient`, when given (at.size() entries), receives each point's gradient
/// where its last step began (within that short step of where it ends).
void newton_onto(std::vector<glm::dvec3>& at, const BatchGradient& field, double threshold, int steps,
                 std::span<const double> settled, std::span<glm::dvec3> last_gradient = {});

/// Straightens every boundary loop of `mesh`: each loop vertex moves halfway toward the midpoint
/// of its two loop neighbours, then back onto {f = T}; the vertices one ring inside follow by
/// tangential relaxation, so the loop's own triangles do not fold.
void relax_boundary(TriangleMesh& mesh, const BatchGradient& field, double threshold, int iterations = 3);

/// The intersecting triangle pairs among the triangles whose boxes meet `region` (where a local
/// strategy changed the mesh: the rest is the operands' own), as pairs of triangle indices.
std::vector<std::array<std::uint32_t, 2>> intersections_in(const TriangleMesh& mesh, const Aabb& region);

/// The intersecting pairs among the triangles near the vertices `hit` marks, after those vertices'
/// triangles and one ring around them changed: a triangle that meets a changed one has its
/// vertices within three `longest_edge` lengths of a hit vertex, so only the triangles with a
/// vertex in the cells (of that size) three around the hit vertices' cells, and whose boxes meet
/// `region`, are searched.
std::vector<std::array<std::uint32_t, 2>> intersections_near(const TriangleMesh& mesh, std::span<const std::uint8_t> hit,
                                                             double longest_edge, const Aabb& region);

/// The length of the mesh's longest edge.
double longest_edge(const TriangleMesh& mesh);

/// Untangles a mesh locally: while some triangles in `region` intersect, their vertices and one
/// ring around them, except the `fixed` ones, are relaxed as above. Vertices flagged in `crease`
/// (when not empty: points of a crease line) slide along their crease instead, toward the midpoint
/// of their two crease neighbours. At most `rounds` rounds; returns the intersecting pairs left in
/// the region (triangle indices, lower first). With `changed` (one flag per vertex), every
/// triangle that changed has a flagged corner and the others intersect nothing: the first search
/// looks only near the flagged vertices (as intersections_near does), not at all of `region`.
std::vector<std::array<std::uint32_t, 2>> untangle(TriangleMesh& mesh, std::span<const std::uint8_t> fixed,
                                                   const BatchGradient& field, double threshold, const Aabb& region,
                                                   int rounds = 3, std::span<const std::uint8_t> crease = {},
                                                   std::span<const std::uint8_t> changed = {});

/// The vertices within `rings` edges of a seed, reached through vertices that `allowed` accepts;
/// the seeds themselves are not included.
std::vector<std::uint8_t> rings_around(const TriangleMesh& mesh, std::span<const std::uint8_t> seeds,
                                       std::span<const std::uint8_t> allowed, int rings);

}  // namespace ht
