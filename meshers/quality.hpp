// The quality pass: well-shaped triangles on the surface, the topology untouched.
//
// Marching tetrahedra puts every vertex on a grid edge, so the triangles inherit the grid's
// accidents: needles where the surface passes near a grid point (two vertices almost on top of
// each other) and caps where it cuts a tetrahedron's corner off (one angle near 180 degrees).
// The local strategies leave thin fans beside their exact seams. The pass removes both, on an
// OpenMesh halfedge mesh with its validity checks:
//   collapse  first a vertex of valence 3 at the corner of a needle, a cap or a speck (nearer
//             than kShortNeedleEdge cells to a neighbour): its three neighbours' triangle stays;
//             it is the third common neighbour that makes the link check refuse the needles
//             beside it. Then the shortest edge of a needle, when
//             is_collapse_ok allows it, no triangle around it turns over, and the smallest angle
//             around it gets better;
//   flip      an edge whose two triangles are nearly coplanar, when is_flip_ok allows it and
//             the smaller of their smallest angles gets better (max-min angle, so flips end);
//   split     an edge longer than twice the precision, at its midpoint put on the surface;
//   relax     every free vertex toward the area-weighted centroid of its ring, in its tangent
//             plane, then back onto f = T by Newton steps along its normal on the field's values
//             (from the polygonizer, the bricks' own tapes: meshers/surface_field.hpp);
//             a move that turns a triangle over or worsens its smallest angle much is undone.
// Locked vertices (crease points, corners, exact seams, a mesh's boundary, triangles kept from
// the user's meshes) neither move nor go away, and no edge between two of them is flipped or
// collapsed, so creases stay sharp and open patches keep their rims. Vertices beside a crease
// (kNearCrease below) are the pass's too, but a face there may straddle the crease, so their
// steps are measured (meshers/off_surface.hpp): a collapse or flip that leaves a face's middle
// further off the surface than the faces it replaces were (or 0.05 cells), or a move that does
// (or 0.02), is not made, and no long edge there splits. A component less than two precisions across on
// every axis is locked whole: so few triangles fold into each other when collapsed or relaxed,
// and there is nothing to gain.
//
// The mesh is cut into slabs across its longest axis, kSlabCells precisions thick, at fixed
// places in space (multiples of the slab's thickness from the origin); the slabs are worked on in
// parallel with their rims locked, then the bands between them (three rings wide), in parallel
// too, each connected band on its own. Deterministic: the slabs and bands depend on the mesh
// alone, never on the thread count; in a slab the topological steps visit the mesh in a fixed
// order and the relaxation is a Jacobi step (every vertex moves from the previous positions).
// Because slabs sit at fixed places, an edit of the surface changes the input of the slabs and
// bands it touches only, and with a PieceCache (QualityReuse) the others are not worked on again.
#pragma once

#include "meshers/batch_field.hpp"
#include "meshers/triangle_mesh.hpp"
#include "runtime/aabb.hpp"

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>

namespace ht {

/// What the pass holds at its peak per vertex of the mesh, for memory budgets: the OpenMesh
/// halfedge mesh (a vertex, three edges of two halfedges and two faces with their handles, status
/// and double positions: about 160 bytes, as much again while its arrays grow) and the pass's own
/// per-vertex arrays.
inline constexpr double kQualityBytesPerVertex = 400.0;

struct QualityOptions {
  bool enabled = true;  ///< false: meshers return what they extracted
  int iterations = 3;   ///< rounds of collapse, flip and relax
  int newton_steps = 1; ///< projection steps per relaxation
  /// Beside a crease a collapse or flip may take a face's middle this many precisions off the
  /// surface, or as far as the faces it replaces were (at 0.02 the polygonizer's slivers there
  /// stayed; a trimmed Boolean's seam, whose operands' faces are exact, takes 0.02).
  double off_step_cells = 0.05;
};

/// Slabs are this many precisions thick.
inline constexpr double kSlabCells = 24.0;

class PieceCache;

/// What the pass may take from earlier runs (incremental re-meshing, meshers/piece_cache.hpp).
/// The field is seen as parts of space (the polygonizer's bricks), each with a content key (its
/// tape's hash). A slab or band is kept under a hash of its input and `context`, with the parts
/// its work evaluated the field in and their keys; it is taken again when its input is the same
/// and each of those parts still has the same key, since the work then evaluates the same field
/// at the same points and makes the same result.
struct QualityReuse {
  PieceCache* cache = nullptr;  ///< not owned; null: nothing is reused or kept
  /// Mixed into every key: what fixes the parts' places (the polygonizer's grid).
  std::uint64_t context = 0;
  /// The part a point's value comes from, or kNoPart when nothing can be said of it (then the
  /// piece is not kept). Called from several threads at once.
  std::function<std::uint64_t(const glm::dvec3&)> part_of;
  /// The content key of a part now. Called from several threads at once.
  std::function<std::uint64_t(std::uint64_t part)> part_key;
  static constexpr std::uint64_t kNoPart = ~std::uint64_t(0);
};

struct QualityStats {
  std::size_t collapses = 0, flips = 0, splits = 0;
  std::size_t moved = 0;     ///< vertex moves kept over all relaxations
  std::size_t reverted = 0;  ///< vertex moves undone
  std::size_t pieces = 0, pieces_reused = 0;  ///< slabs and bands worked on, and of those taken from a QualityReuse
  std::size_t retries = 0;   ///< runs again from the extracted mesh with the vertices around folds kept (meshers/polygonize.hpp)
  bool skipped = false;      ///< the mesh was not a manifold OpenMesh accepts; left as it was
  double seconds = 0.0;

  QualityStats& operator+=(const QualityStats& o) {
    collapses += o.collapses, flips += o.flips, splits += o.splits, moved += o.moved, reverted += o.reverted;
    pieces += o.pieces, pieces_reused += o.pieces_reused, retries += o.retries;
    skipped |= o.skipped;
    seconds += o.seconds;
    return *this;
  }
};

/// A `locked` value: the vertex lies beside a crease (the polygonizer's two rings around its
/// crease points). It is not locked, but every step that moves it, takes it away or flips an
/// edge near it is held to the surface (above); a needle's edge shorter than kShortNeedleEdge
/// precisions may collapse it even into a crease point's neighbour. Any other nonzero value
/// locks the vertex outright.
inline constexpr std::uint8_t kNearCrease = 2;
/// A `locked` value: the vertex stays even where it is a crease point (no merging, no sliding
/// along its chain) and its neighbours stay as a rim's do. The polygonizer's second run around
/// folds keeps the vertices in their boxes so.
inline constexpr std::uint8_t kPinned = 3;
inline constexpr double kShortNeedleEdge = 0.15;

/// Improves the triangles of `mesh` in place. `locked` and `crease` hold one flag per vertex (or
/// are empty): locked vertices stay (but see kNearCrease), and crease vertices (points on a crease
/// line, locked too) that are almost together merge into one. `field` is the surface's field,
/// {field = threshold} the surface, the solid where it is larger; it is called from several threads at once (the
/// pass works on slabs of the mesh in parallel, then on the bands between them). `h` is the
/// precision (world units). Vertex indices change; with `crease_after`, receives the crease flags
/// renumbered with them.
/// With `reuse`, slabs and bands whose input and field were seen before are taken from its cache
/// (the result is the same, bit for bit) and the others are stored there with the parts of the
/// field they read.
void improve_quality(TriangleMesh& mesh, std::span<const std::uint8_t> locked, std::span<const std::uint8_t> crease,
                     const BatchField& field, double threshold, double h, const QualityOptions& options = {},
                     QualityStats* stats = nullptr, std::vector<std::uint8_t>* crease_after = nullptr,
                     const QualityReuse* reuse = nullptr);

}  // namespace ht
