// The global polygonizer: a closed, oriented 2-manifold of any node's surface {f = T} at a
// precision (the paper's Marching Cubes path, section 3.2.1).
//
// The domain (the node's solid bounds) is cut into bricks of 8^3 cells of side `precision`. An
// octree descent with interval analysis (runtime/tape.hpp) keeps only the bricks the surface may
// cross, so the cost follows the surface's area, not the domain's volume. Each active brick
// compiles a tape specialized to its box, samples its 9^3 grid points in one batch, and cuts each
// cell into the six tetrahedra of Kuhn's triangulation (all sharing the cell's main diagonal,
// so neighbouring cells' faces match). Marching tetrahedra on that conforming mesh, with one
// inside/outside label per grid point (shared points take their owner brick's label), gives a
// closed, oriented 2-manifold by construction. Vertices sit on grid edges, keyed by edge so they
// are shared exactly, and are refined onto the surface by false position along their edge.
// Edges that cross a crease or a corner are split at a point on it (meshers/features.hpp), so
// min/max Booleans and crops stay sharp.
//
// Deterministic: the same node and precision give the same mesh at any thread count.
#pragma once

#include "meshers/features.hpp"
#include "meshers/quality.hpp"
#include "meshers/snap.hpp"
#include "meshers/unfold.hpp"
#include "meshers/triangle_mesh.hpp"
#include "runtime/aabb.hpp"
#include "runtime/graph.hpp"
#include "runtime/memory_budget.hpp"

#include <atomic>
#include <cstddef>
#include <functional>
#include <memory>
#include <stdexcept>
#include <vector>

namespace ht {

class PieceCache;

struct PolygonizeOptions {
  double precision = 0.0;                        ///< cell size (about the edge length); > 0
  std::size_t memory_budget = std::size_t(4) << 30;  ///< bytes the polygonizer may use (when `budget` is null)
  /// The run's budget, shared with its other stages (runtime/memory_budget.hpp); not owned. When
  /// set it replaces memory_budget. The polygonizer takes its brick table and active bricks
  /// (5 bytes a brick, 12 KiB an active brick, 15 with region_operands) and its quality pass
  /// (kQualityBytesPerVertex) before allocating them, gives them back when done, and throws
  /// MemoryBudgetError when they do not fit.
  MemoryBudget* budget = nullptr;
  int refine_steps = 24;                         ///< at most this many false-position steps per vertex (Illinois)
  /// A vertex is done when |f - T| is below this fraction of f's change along its edge, or its
  /// bracket below this fraction of the edge.
  double refine_tolerance = 1e-3;
  bool sharp_features = true;                    ///< split edges along creases (meshers/features.hpp)
  bool snap = true;                              ///< merge the vertices a hair from a grid point into one (meshers/snap.hpp)
  FeatureOptions features;
  /// The quality pass over the extracted mesh (meshers/quality.hpp); on by default.
  QualityOptions quality;
  /// Called from the calling thread with the fraction done, at most about 100 times.
  std::function<void(double)> progress;
  /// When set, only the bricks it accepts are meshed, and in them only the octants it names: the
  /// result is the part of the surface there, open where they end (the local strategies mesh a
  /// patch this way and cut it, meshers/local_ops.hpp). Called with each brick's box, from any
  /// thread; returns one bit per octant of the brick (namespace octants), 0 for none. Grid
  /// points outside the named octants are not evaluated, and the triangles of their cells and of
  /// the cells that read them are left out (so a patch is also open within a cell of them).
  std::function<std::uint8_t(const Aabb&)> brick_filter;
  /// With brick_filter, for a blend's patch: the root is a blend of these nodes (its field their
  /// sum, each taken as a blend's operand), sampled one by one; a cell with no corner where two
  /// of them act (are nonzero) is not meshed: the patch's cut would take its triangles away
  /// (meshers/local_blends.cpp, meshers/brick_region.hpp). Vertices are placed on the root's
  /// field. Fewer than two operands: ignored.
  std::vector<NodeId> region_operands;
  /// When not empty, only the part of the domain inside this box is gridded (with the filter, a
  /// patch costs what its region costs, not what the node's whole solid would).
  Aabb clip;
  /// Polled between bricks; when it reads true the polygonizer throws MeshCancelled.
  const std::atomic<bool>* cancel = nullptr;
  /// Parts of earlier runs (not owned; meshers/piece_cache.hpp): bricks whose extraction and
  /// quality-pass slabs and bands whose work was done before with the same inputs and field are
  /// taken from it, the others stored in it (meshers/polygonize_reuse.hpp). The mesh is the same,
  /// byte for byte, with or without it. Not used with a brick_filter or a clip.
  PieceCache* pieces = nullptr;
};

/// A brick's octants for PolygonizeOptions::brick_filter: bit i + 2 j + 4 k is the octant on the
/// upper half of the x axis when i is 1, of y when j is, of z when k is.
namespace octants {
inline constexpr std::uint8_t kAll = 0xff;
/// Octant `k`'s box in `box` (k as the bits above).
Aabb of(const Aabb& box, int k);
}  // namespace octants

struct PolygonizeStats {
  std::size_t bricks_total = 0, bricks_active = 0;
  std::size_t bricks_reused = 0;  ///< active bricks taken from PolygonizeOptions::pieces
  std::size_t points_evaluated = 0;
  /// Field values the vertices' placement took (false position along the crossing edges, from a
  /// cubic's guess where a brick holds four values on the edge's line); bricks taken from
  /// `pieces` add none.
  std::size_t refine_evaluations = 0;
  std::size_t crease_edges = 0, corner_vertices = 0;  ///< sharp features (meshers/features.hpp)
  std::size_t crease_candidates = 0, crease_spread = 0;  ///< CreaseStats::candidate_edges, spread_edges
  std::size_t crease_intersections = 0;  ///< intersecting pairs left where the crease step ran (after unfolding)
  std::size_t quality_intersections = 0; ///< of those, pairs the quality pass made (then unfolded)
  UnfoldStats unfold;                                 ///< folds the crease step left, collapsed (meshers/unfold.hpp)
  /// Triangles folded over onto their neighbours without crossing them, mended after the crease
  /// step and after the quality pass (meshers/unfold.hpp unfold_folded): pairs_before counts
  /// those found by both, pairs_after those left at the end.
  UnfoldStats folds;
  SnapStats snap;                                     ///< vertices merged at grid points (meshers/snap.hpp)
  QualityStats quality;                               ///< the quality pass (meshers/quality.hpp)
  double seconds_classify = 0, seconds_sample = 0, seconds_extract = 0, seconds_merge = 0, seconds_features = 0;
  Aabb domain;
};

/// Thrown when the request cannot be met: an unbounded solid, a grid past 2e6 bricks a side, an
/// ffd before meshing exists. A precision that would exceed the memory budget throws
/// MemoryBudgetError (runtime/memory_budget.hpp), whose message says how much it would need.
struct PolygonizeError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// A cell must hold at least this many steps of doubles at the solid's farthest coordinate: a
/// finer precision cannot place the grid's points apart (a point translated by 1e17, where doubles
/// step by 16, sent the brick classification into endless subdivision at h = 0.03; a unit ball at
/// 1e9, 2.9e5 steps a cell, came out of the global polygonizer with 1,038 boundary edges).
inline constexpr double kCoordinateSteps = 1e6;

/// The message for a precision below what doubles resolve where `solid` lies, or empty when
/// they resolve it: precision >= kCoordinateSteps times the spacing of doubles at its farthest
/// coordinate.
std::string unresolvable_precision(const Aabb& solid, double precision);

/// How far from the origin a solid may reach: the exact checks (meshers/self_intersections.hpp)
/// multiply three coordinates, which past about 1e102 overflow doubles (a tapered cylinder of
/// radius 1e150 spent minutes in those checks on infinite products).
inline constexpr double kMaxCoordinate = 1e100;

/// The message for a solid that reaches farther than kMaxCoordinate from the origin, or empty.
std::string unmeshable_extent(const Aabb& solid);

/// Thrown when a run is cancelled through its cancellation flag.
struct MeshCancelled : PolygonizeError {
  using PolygonizeError::PolygonizeError;
};

/// Meshes node `root` of `graph` at threshold T. An empty surface gives an empty mesh.
TriangleMesh polygonize(std::shared_ptr<const Graph> graph, NodeId root, double threshold,
                        const PolygonizeOptions& options, PolygonizeStats* stats = nullptr);

}  // namespace ht
