// Vertex snapping for marching tetrahedra (as Manifold's level set does before marching). Where
// the surface passes through a grid point (faces on grid planes: a crop whose box lies on the
// grid, a box whose size is a multiple of the cell), marching tetrahedra puts a vertex a hair
// from that point on every grid edge around it: specks of triangles a thousandth of a cell wide,
// which fold into each other where a crease runs through the point. All vertices near one grid
// point merge into one and the triangles that collapse go. The merge contracts a small patch
// around the grid point; where that would break the manifold (a patch that is not a disc, or a
// neighbour left with other than two triangles on its edge to the merged vertex), that grid
// point's vertices stay as they are.
//
// The merged vertex goes to the mean of its cluster projected onto {f = T}; where the cluster's
// normals spread past the sharp angle (a crease or a corner through the grid point) it goes to
// the point of the cluster's tangent planes instead and is flagged as a crease point.
#pragma once

#include "meshers/batch_field.hpp"
#include "meshers/triangle_mesh.hpp"

#include <cstdint>
#include <span>
#include <vector>

namespace ht {

struct SnapOptions {
  double sharp_angle_degrees = 25.0;  ///< cluster normals further apart: the point is on a crease
  double max_error = 0.05;            ///< a crease point off the surface by at most this many cells
};

struct SnapStats {
  std::size_t merged_vertices = 0;    ///< vertices merged into another
  std::size_t removed_triangles = 0;  ///< triangles that collapsed
  std::size_t skipped_points = 0;     ///< grid points whose cluster could not merge (not a disc)
  std::size_t crease_points = 0;      ///< merged vertices placed on a crease or corner
};

/// `near[v]` names the grid point vertex v lies close to, or ~0 when none. `normals` (one per
/// vertex; zero where unknown) follow the merge: a merged vertex keeps its cluster's first known
/// normal, or none when it became a crease point. `crease` receives one flag per vertex of the
/// result. `field` gives the surface's field and gradient (threshold T; the polygonizer passes its
/// bricks' tapes, meshers/surface_field.hpp), h the cell size. Deterministic: the
/// clusters are visited in the order of their grid points. Cost: O(n) per round plus two
/// gradients per merged cluster (a cluster on a crease: one, two more when its corner point is
/// refused).
void snap_to_grid_points(TriangleMesh& mesh, std::span<const std::uint64_t> near, std::vector<glm::vec3>& normals,
                         std::vector<std::uint8_t>& crease, const BatchGradient& field, double threshold, double h,
                         const SnapOptions& options = {}, SnapStats* stats = nullptr);

}  // namespace ht
