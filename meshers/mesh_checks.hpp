// Mesh checks: what the tests and `hybridtree mesh --stats-json` assert about every mesh.
//   topology  closed (no boundary edge), edge- and vertex-manifold, consistently oriented,
//             components, Euler characteristic and genus per component
//   geometry  degenerate triangles, area, enclosed volume, minimum-angle distribution
//   surface   |f - T| / |grad f| at vertices and face centres, inverted faces, through a tape
#pragma once

#include "meshers/triangle_mesh.hpp"
#include "runtime/graph.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace ht {

class SurfaceField;
class TapeEvaluator;

struct MeshChecks {
  std::size_t vertices = 0, triangles = 0, edges = 0;
  std::size_t boundary_edges = 0;       ///< used by one triangle
  std::size_t nonmanifold_edges = 0;    ///< used by three or more
  std::size_t misoriented_edges = 0;    ///< two triangles traverse it the same way
  std::size_t nonmanifold_vertices = 0; ///< whose triangles form more than one fan
  std::size_t degenerate_triangles = 0; ///< zero area (relative to the mesh's size)
  std::size_t nonfinite_vertices = 0;   ///< a coordinate NaN or infinite
  std::size_t unused_vertices = 0;
  std::size_t components = 0;
  long euler = 0;                       ///< V - E + F over the used vertices
  long genus = 0;                       ///< sum over components of (2 - chi) / 2 (closed meshes)
  double area = 0, volume = 0;          ///< volume by the divergence theorem (closed meshes)
  double min_angle = 0;                 ///< degrees, over all triangles
  double min_angle_p1 = 0;              ///< degrees: the first percentile of the triangles' smallest angles
  std::array<std::size_t, 6> min_angle_histogram{};  ///< triangles by min angle: [0,10) ... [50,60]
  // Surface error, filled by measure_surface_error(): distance to the isosurface estimated as
  // |f - T| / |grad f|, at vertices and at face centres. A face centre's is capped by its
  // distance to a corner plus that corner's: a bound on the true distance that holds where
  // grad f vanishes (a small primitive's centre) and the quotient does not (it read 1e300 there).
  double vertex_error_max = 0, vertex_error_mean = 0, face_error_max = 0, face_error_mean = 0;
  /// Triangles whose normal points inward (against -grad f at their centre): folds, or slivers
  /// too thin for their orientation to matter (their area tells which).
  std::size_t inverted_faces = 0;
  double inverted_area = 0;
  /// Of those, triangles folded over onto their neighbours (meshers/unfold.hpp
  /// folded_triangles): against the vertex normals around them, and along the surface at none of
  /// their corners (not merely across a sharp crease). Every mesher's output should have none.
  std::size_t folded_triangles = 0;
  // Where the small angles are, filled by measure_surface_error() too. Kept triangles are a mesh
  // leaf's own (all three corners are its vertices, bit for bit): their shapes are the input's.
  // The made ones are HybridTree's; of those, crease triangles are within one ring of a triangle
  // across which grad f turns by more than kCreaseTurnDegrees (corners and centre compared), and
  // the rest are smooth. Angles in degrees; p1 is the first percentile; 0 when there are none.
  std::size_t kept_triangles = 0, crease_triangles = 0, smooth_triangles = 0;
  double made_min_angle = 0, made_min_angle_p1 = 0;
  double smooth_min_angle = 0, smooth_min_angle_p1 = 0;
  /// Pairs of triangles that intersect beyond their shared vertices or edge: crossings, touching
  /// at a point they do not share, folds (see meshers/self_intersections.hpp). Exact.
  std::size_t self_intersecting_pairs = 0;

  bool closed() const { return boundary_edges == 0; }
  bool manifold() const { return nonmanifold_edges == 0 && nonmanifold_vertices == 0; }
  bool oriented() const { return misoriented_edges == 0; }
  /// Closed, manifold, oriented, finite, no degenerate triangle: what every mesher must return.
  bool watertight() const {
    return closed() && manifold() && oriented() && degenerate_triangles == 0 && nonfinite_vertices == 0;
  }
  /// No self-intersecting pair. Separate from watertight(), which is about topology.
  bool intersection_free() const { return self_intersecting_pairs == 0; }
};

/// Topology and geometry checks. Linear time, except the self-intersection count: O(n log n) plus
/// an exact test per pair of triangles whose boxes overlap, in parallel (see
/// find_self_intersections()). No allocation beyond a few arrays of the mesh's size and the
/// candidate pairs.
MeshChecks check_mesh(const TriangleMesh& mesh, bool self_intersections = true);

/// Only what watertight() reads (edges by use and direction, vertex fans, degenerate triangles)
/// and the counts of vertices, triangles and unused vertices; the other fields stay 0. What the
/// mesh plan asks of every strategy's result, at a fraction of check_mesh()'s cost.
MeshChecks check_watertight(const TriangleMesh& mesh);

/// What keeps `c` from watertight() and intersection_free(), as "462 boundary edges, 3
/// self-intersecting triangle pairs"; empty when nothing does.
std::string describe_defects(const MeshChecks& c);

/// How far grad f turns across a triangle that MeshChecks counts as a crease triangle.
inline constexpr double kCreaseTurnDegrees = 30.0;

/// Fills the surface-error and angle-census fields of `checks` by evaluating f and grad f with
/// the tape at T. `kept` is empty or holds one flag per triangle (kept_leaf_triangles()).
void measure_surface_error(const TriangleMesh& mesh, const TapeEvaluator& tape, double threshold, MeshChecks& checks,
                           std::span<const std::uint8_t> kept = {});
/// The same with the field's tapes specialized to bricks (meshers/surface_field.hpp): the same
/// figures to float rounding, at a fraction of the cost on a big tree.
void measure_surface_error(const TriangleMesh& mesh, SurfaceField& field, MeshChecks& checks,
                           std::span<const std::uint8_t> kept = {});

/// One flag per triangle of `mesh`: its three corners are among `corners`, bit for bit.
std::vector<std::uint8_t> kept_leaf_triangles(const TriangleMesh& mesh, std::vector<glm::dvec3> corners);
/// The same with the corners of the mesh leaves (and prepared ffds) under `root`, moved by the
/// affine nodes above each, as the mesh plan moves them: the triangles kept from the user's
/// meshes. O((V + C) log C) for C corners; a leaf under a twist, taper or bend keeps none.
std::vector<std::uint8_t> kept_leaf_triangles(const TriangleMesh& mesh, const Graph& graph, NodeId root);

}  // namespace ht
