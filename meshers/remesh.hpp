// Isotropic remeshing of a region of a mesh on its implicit surface (Botsch & Kobbelt 2004), on
// an OpenMesh halfedge mesh with its validity checks: split edges longer than 4/3 of the target
// (the new vertex projected onto {f = T} by Newton steps on the field's gradients), collapse
// edges shorter than 4/5 (is_collapse_ok, and no triangle turned over), flip edges toward
// valence 6 where the two triangles are nearly coplanar (is_flip_ok), and relax vertices
// tangentially, projected back onto the surface. Last, the slivers those rounds leave (under 15 degrees, mostly beside the
// locked rim) lose an edge by a collapse from a free corner, or their longest edge by a flip, when
// that leaves the faces around less thin. The local strategies run it where they made new
// triangles: their seams, fans and bands, whose slivers it removes.
//
// What stays: every vertex outside the region, every `fixed` vertex (exact seams), every vertex on
// a crease (an edge whose triangles meet at more than 30 degrees; such a point may only go into a
// neighbour 0.3 of the target away), and every edge between two of
// those. The region's boundary therefore does not move, and
// vertices outside it keep their positions bit for bit (their indices may change).
//
// The region is cut into slabs 24 target lengths thick across the mesh's longest axis, at fixed
// places (meshers/submesh.hpp slab_of_vertices), remeshed in parallel with their rims locked;
// then the triangles across slabs with three rings of the region around them, each connected band
// on its own, in parallel too. The slabs come from the mesh and the target alone, so the result is
// the same at any thread count.
#pragma once

#include "meshers/batch_field.hpp"
#include "meshers/triangle_mesh.hpp"

#include <cstdint>
#include <span>
#include <vector>

namespace ht {

struct RemeshOptions {
  double target = 0.0;  ///< edge length aimed at (world units); > 0
  int iterations = 4;
};

struct RemeshStats {
  std::size_t splits = 0, collapses = 0, flips = 0;
  std::size_t sliver_fixes = 0;  ///< slivers collapsed or flipped after the isotropic rounds
};

/// Remeshes the triangles with a corner in `region` (one flag per vertex); `fixed` vertices do
/// not move and stay. Deterministic. The caller checks the result. `renumber` (if given)
/// receives each old vertex's index in the result, ~0u for those collapsed away (as put_back).
void remesh_region(TriangleMesh& mesh, std::span<const std::uint8_t> region, std::span<const std::uint8_t> fixed,
                   const BatchGradient& field, double threshold, const RemeshOptions& options, RemeshStats* stats = nullptr,
                   std::vector<std::uint32_t>* renumber = nullptr);

}  // namespace ht
