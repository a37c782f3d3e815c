// Cutting a mesh along a level set: the trimming step of the paper's local strategies
// (sections 3.2.1-3.2.3). The part of a closed mesh where a cut function c is negative is kept;
// every triangle that c crosses is clipped exactly along {c = 0}: each crossing edge gets one new
// vertex at the root of c along it (false position on c itself, not linear interpolation of the
// end values), shared by the two triangles of that edge. So the kept part is an oriented manifold
// whose boundary is a set of simple closed polylines lying on {c = 0}, ready for stitching
// (meshers/stitch.hpp).
//
// A vertex that lies within `snap` of the cut along one of its edges is moved onto the cut
// instead (as Manifold's level set snaps vertices before marching): the kept part then has no
// sliver along its boundary. Every other kept vertex (c < 0) keeps its position bit for bit, in
// its original order, before the new vertices.
#pragma once

#include "meshers/batch_field.hpp"
#include "meshers/triangle_mesh.hpp"

#include <functional>
#include <limits>
#include <span>

namespace ht {

struct CutOptions {
  /// A vertex with a root of c within this fraction of one of its edges moves onto that root...
  double snap = 0.2;
  /// ... if that is no farther than this (world units): moving a vertex bends its other faces,
  /// which on a coarse mesh would leave the surface by a fraction of its long edges.
  double snap_distance = std::numeric_limits<double>::infinity();
  /// Vertices from this index on (a refinement's own, not the input's) snap within `snap` of an
  /// edge at any distance: they lie inside the input's faces or on its edges, so moving one bends
  /// the faces around it only by the turn between two neighbouring faces of the input.
  std::size_t snap_freely_from = std::numeric_limits<std::size_t>::max();
  int refine_steps = 20;        ///< at most this many false-position steps per crossing edge
  double refine_tolerance = 1e-4;  ///< of c's change along the edge, or of the edge's length
};

struct CutStats {
  std::size_t kept_vertices = 0, new_vertices = 0, snapped_vertices = 0;
  std::size_t kept_triangles = 0, clipped_triangles = 0, dropped_triangles = 0;
  std::size_t root_evaluations = 0;  ///< values of c the crossing edges' roots took (all attempts)
};

/// The part of `mesh` where c < 0. `mesh` should be an oriented manifold (closed or not); the
/// result keeps its orientation. Linear in the mesh plus the evaluations of c (the vertices once,
/// then the crossing edges' roots in batches).
TriangleMesh cut_mesh(const TriangleMesh& mesh, const BatchField& c, const CutOptions& options = {},
                      CutStats* stats = nullptr);

/// The same with c's values at the vertices already known (values.size() == positions.size()).
TriangleMesh cut_mesh(const TriangleMesh& mesh, std::span<const double> vertex_values, const BatchField& c,
                      const CutOptions& options = {}, CutStats* stats = nullptr);

}  // namespace ht
