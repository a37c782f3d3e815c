// The HybridTree as a flat, immutable node arena (structure of arrays).
//
// Node ids are indices; a node's children always have smaller ids than the node, so a forward
// walk over ids is a valid post-order for any subset of the graph. Parameters are doubles in one
// pool, laid out per kind (nodes/primitives.hpp, nodes/warps.hpp, runtime/graph.hpp below);
// children are ranges of one index array. Nothing here is a pointer, so a Graph is cheap to copy,
// to hash and to ship, and every node can be the root of its own query.
#pragma once

#include "nodes/kinds.hpp"
#include "runtime/aabb.hpp"

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace ht {

class MeshLeaf;

using NodeId = std::uint32_t;
inline constexpr std::uint32_t kNone = ~0u;

/// How a node asks to be meshed (SCENE_FORMAT.md, `mesher` on operators and warps).
enum class MesherHint : std::uint8_t { Auto, Global, Local };

/// Parameter layouts of the kinds not described in nodes/:
///   mesh         R F kernel_radius r0 query_radius     (nodes/mesh_leaf.hpp, MeshFieldParams)
///   ffd          see nodes/warps.hpp; once prepared (meshers/ffd.hpp), `mesh` names its deformed
///                mesh and its field is that mesh's pseudo-distance field with its R and F
///   crop         min(3) max(3)
///   operators    none (children only; local_blend's children are a, b, region)
inline constexpr int kMeshParams = 5;

/// Deepest nesting of nodes any walk accepts (scene loading, compilation): keeps every recursive
/// walk far from the end of the stack.
inline constexpr int kMaxTreeDepth = 1000;

struct Graph {
  // One entry per node.
  std::vector<NodeKind> kind;
  std::vector<BooleanMode> boolean;      ///< Booleans and local blend; Auto elsewhere
  std::vector<MesherHint> mesher;
  std::vector<std::uint32_t> param_begin, param_count;
  std::vector<std::uint32_t> child_begin, child_count;
  std::vector<std::uint32_t> mesh;       ///< index into meshes (mesh leaves), else kNone
  std::vector<std::uint32_t> name;       ///< index into names, else kNone
  /// Where the node's field may be non-zero, when the node is a root on its own (`auto` picks
  /// min/max at the node) and when something above it blends (`auto` picks R-functions).
  std::vector<Aabb> support_alone, support_blended;
  /// The field is >= 0 everywhere (no negative strength reaches it).
  std::vector<std::uint8_t> nonnegative;

  /// Evaluation data derived from the parameters (a curve's sampled polyline), kept apart from
  /// the model so that bytes() measures the model as the paper does.
  std::vector<std::uint32_t> derived_begin, derived_count;

  // Pools.
  std::vector<double> params;
  std::vector<double> derived;
  std::vector<NodeId> children;
  std::vector<std::string> names;
  std::vector<std::shared_ptr<const MeshLeaf>> meshes;

  std::size_t size() const { return kind.size(); }
  std::span<const double> params_of(NodeId n) const { return {params.data() + param_begin[n], param_count[n]}; }
  std::span<const NodeId> children_of(NodeId n) const {
    return {children.data() + child_begin[n], child_count[n]};
  }
  /// What skeleton_distance() reads for a primitive: its skeleton parameters, or for a curve
  /// its polyline block [n, x0 y0 z0, ...].
  const double* skeleton_of(NodeId n) const {
    return derived_count[n] ? derived.data() + derived_begin[n] : params.data() + param_begin[n] + 2;
  }
  const Aabb& support(NodeId n, bool under_blend) const {
    return under_blend ? support_blended[n] : support_alone[n];
  }
  /// "name" if the node has one, else "type #id".
  std::string label(NodeId n) const;
  /// Bytes of the model itself: kinds, parameters, children, names (what the paper measures),
  /// not the meshes it names nor anything derived from it.
  std::size_t bytes() const;
  /// Bytes of what is derived from the model to evaluate it: supports, signs, curve polylines.
  std::size_t derived_bytes() const;
};

/// Fills support_alone, support_blended and nonnegative for every node, bottom-up (the builder
/// calls it; so does anything that changes a node's meshes, such as ffd preparation).
void compute_supports(Graph& graph);

/// The top-level settings of a scene.
struct MesherSettings {
  double precision = 0.0;  ///< target edge length; 0 = choose from the scene's size
  MesherHint strategy = MesherHint::Auto;
  double blend_overlap = 0.5;  ///< the paper's rho threshold
};

}  // namespace ht
