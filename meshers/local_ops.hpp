// The paper's local strategies for operators (sections 3.2.1-3.2.3): mesh the operands, trim
// their meshes where the operation changes the surface, mesh only the new part, and stitch.
//
//   blend     every operand's mesh M_i is cut along {g_i = eps}, g_i = sum over the other
//             operands of |f_j| (so the kept part is where nothing else acts: there the blend's
//             surface is M_i's, to within eps / |grad f_i|); the blend's own surface is
//             polygonized only in bricks where two operands' supports meet, and that patch is
//             cut to where every g_i >= eps. A negative operand has no mesh: it only trims.
//   Booleans  (union, intersection, difference of up to 16 operands, as a left fold of binary
//             steps; min/max or R-functions: the surface is the same) at each step both meshes
//             are cut along the other's surface {f_other = T},
//             by root finding on the other's tape, so both cuts lie on the intersection curve
//             and the crease stays sharp. No new surface is needed.
//   crop      the child's mesh is cut by the box exactly; each opening is closed by a planar
//             cap (meshers/caps.hpp).
//   local blend  as a union outside the region's reach, as a blend inside it.
// The pieces are joined by meshers/stitch.hpp. Each function throws LocalFailure (or
// StitchError / PolygonizeError) when it cannot build its mesh; the mesh plan
// (meshers/mesh_plan.hpp) then falls back to global polygonization and reports why.
#pragma once

#include "meshers/bridge.hpp"
#include "meshers/polygonize.hpp"
#include "meshers/remesh.hpp"
#include "meshers/stitch.hpp"
#include "meshers/triangle_mesh.hpp"
#include "runtime/graph.hpp"

#include <memory>
#include <span>
#include <stdexcept>

namespace ht {

struct LocalFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// What a local strategy is given: the node (in a graph whose ffd nodes under it are prepared),
/// its children's meshes in child order, and the polygonizer's settings for the patch.
struct LocalInput {
  std::shared_ptr<const Graph> graph;
  NodeId node = kNone;
  double threshold = 0.5;
  double precision = 0.0;
  std::span<const std::shared_ptr<const TriangleMesh>> child_meshes;
  PolygonizeOptions polygonize;  ///< precision, brick_filter and progress are set by the strategy
  /// Remesh what a strategy made (patches, bands) to the precision (meshers/remesh.hpp).
  bool remesh_seams = true;
};

struct LocalStats {
  std::size_t operand_triangles = 0;  ///< in the children's meshes
  std::size_t kept_triangles = 0;     ///< of those, kept (whole or clipped)
  std::size_t patch_triangles = 0;    ///< new surface from the polygonizer, after its cut
  bool patched = false;               ///< the polygonizer ran on part of the node
  double patch_precision = 0;         ///< its cell size: the operands' own edge length there
  PolygonizeStats patch;
  /// Self-intersecting triangle pairs left where the strategy changed the mesh (the plan
  /// rejects a result with any).
  std::size_t self_intersections = 0;
  StitchStats stitch;                 ///< Booleans: the exact seams
  BridgeStats bridge;                 ///< blends: the bands between operands and patch
  RemeshStats remesh;                 ///< blends: the remeshing of patch and bands
};

/// The paper's overlap ratio of a blend: rho = V(B_A and B_B) / V(B_A or B_B) of the operands'
/// support boxes, the largest over pairs of operands (0 for one operand).
double blend_overlap(const Graph& graph, NodeId blend);

/// Operands a local blend handles at most (each kept part is tested against all the others).
inline constexpr std::size_t kMaxLocalBlendOperands = 8;
/// Operands a local Boolean folds at most (each step cuts the result so far again).
inline constexpr std::size_t kMaxLocalBooleanOperands = 16;

TriangleMesh trim_blend(const LocalInput& in, LocalStats* stats = nullptr);
TriangleMesh trim_boolean(const LocalInput& in, LocalStats* stats = nullptr);
TriangleMesh trim_crop(const LocalInput& in, LocalStats* stats = nullptr);
/// Local blend (section 3.2.2): the operands trimmed where the other reaches them or the region
/// acts, their union's crease welded, the blended part polygonized where the region acts and
/// joined by bands. Children: a, b, region; `child_meshes` holds a's and b's.
TriangleMesh trim_local_blend(const LocalInput& in, LocalStats* stats = nullptr);

}  // namespace ht
