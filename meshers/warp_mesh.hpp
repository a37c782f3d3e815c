// Warped meshes (the paper, section 3.3.1): a warp's mesh is its child's mesh with every vertex
// moved by the warp. Where the warp stretches triangles (non-uniform scaling, twist, taper,
// bend, free-form deformation), local remeshing splits every edge that comes out longer than the
// target: the new vertex is the midpoint in the child's space, projected onto the child's
// surface by Newton steps on the child's field, then warped, so it lies on the warped surface
// too. Splits use red-green templates (a triangle with 1, 2 or 3 split edges becomes 2, 3 or 4
// triangles, orientation kept; with 2, the quad beside the corner triangle takes the diagonal
// that leaves its thinner half less thin), so a closed manifold stays a closed manifold.
#pragma once

#include "meshers/triangle_mesh.hpp"
#include "runtime/graph.hpp"

#include <functional>
#include <limits>
#include <memory>
#include <span>

namespace ht {

class TapeEvaluator;

struct WarpRemeshStats {
  int passes = 0;
  std::size_t edges_split = 0;
  /// A pass would have made more than max_triangles: refinement stopped there, and the mesh
  /// returned is the last pass's, with edges still longer than max_edge.
  bool stopped = false;
  /// Some long edges were left unsplit, stretched more than max_relative_stretch times the
  /// median stretch (a tear).
  bool torn = false;
};

/// Moves child_mesh (in the child's space) by `warp` and splits edges longer than max_edge after
/// warping, projecting new vertices onto {f_child = T} with `child_field` (the child's tape).
/// Only edges the warp lengthens are split (a rigid motion splits none). With `region`, every
/// edge longer than max_edge whose warped midpoint lies in that box is split, stretched or not
/// (the local strategies refine a coarse operand near a seam this way).
/// A null `child_field` leaves new vertices at the midpoints (for meshes with no one field of
/// their own, such as a partial Boolean result). `warp` is called from several threads at once.
/// With `only` (one flag per vertex of child_mesh), an edge is split only when both its ends are
/// flagged or new. No pass makes more than `max_triangles` (WarpRemeshStats::stopped): a warp
/// that stretches edges without end (a twist of 1e6 radians a unit) would fill memory. An edge
/// the warp stretches more than `max_relative_stretch` times the median over the child's edges is
/// not split (WarpRemeshStats::torn): where a map jumps (an ffd whose lattice's outer control
/// points are moved tears the child at the lattice box, outside which points stay), halving
/// leaves a half as long as the edge, and ten passes filled the tear with slivers.
TriangleMesh warp_mesh(const TriangleMesh& child_mesh, const std::function<glm::dvec3(const glm::dvec3&)>& warp,
                       const TapeEvaluator* child_field, double threshold, double max_edge,
                       WarpRemeshStats* stats = nullptr, const Aabb* region = nullptr,
                       std::span<const std::uint8_t> only = {},
                       std::size_t max_triangles = std::numeric_limits<std::size_t>::max(),
                       double max_relative_stretch = std::numeric_limits<double>::infinity());

/// What refining a warped mesh holds a triangle at its peak (both copies of the positions, the
/// triangles, a pass's long edges, midpoints and their table), rounded up: the mesh plan caps
/// max_triangles at what its memory budget has room for at this rate.
inline constexpr double kWarpedBytesPerTriangle = 256.0;

/// The forward map of warp node `node` (affine, twist, taper, bend or ffd).
std::function<glm::dvec3(const glm::dvec3&)> forward_map(const Graph& graph, NodeId node);

}  // namespace ht
