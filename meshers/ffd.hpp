// Free-form deformation nodes (Sederberg & Parry 1986; the paper, section 3.3.2). An ffd has no
// closed-form inverse, so, as in the paper, its field goes through a mesh: the child is meshed at
// the current precision (by the mesh plan, meshers/mesh_plan.hpp, with the child's own
// strategy), every vertex is moved by the trivariate Bernstein map of the lattice, and the ffd's
// field is the pseudo-distance field of that deformed mesh (a mesh leaf with the ffd's radius and
// strength). Once its mesh is attached, an ffd compiles and evaluates like a mesh leaf.
#pragma once

#include "meshers/triangle_mesh.hpp"
#include "runtime/graph.hpp"
#include "runtime/memory_budget.hpp"
#include "runtime/tree.hpp"

#include <memory>

namespace ht {

/// True when some ffd node under `root` still waits for its deformed mesh.
bool needs_ffd_preparation(const Graph& graph, NodeId root);

/// The mesh leaf of ffd node `ffd`: `child_mesh` (the child's mesh, in the child's space) moved
/// by the lattice. With max_edge > 0, edges the lattice stretches past max_edge are split first,
/// their new vertices put on the child's surface {f = threshold} (meshers/warp_mesh.hpp).
/// Throws PolygonizeError when the child's mesh is empty or the deformed mesh is not a valid
/// closed mesh. `crossing` (optional) receives the intersecting triangle pairs the deformed mesh
/// still has after its folds were unfolded (a lattice whose outer control points are moved tears
/// the child where it leaves the lattice box, and the torn band can cross itself). Such a leaf
/// takes its inside from the winding number (MeshInside::Winding), so its field is still defined,
/// but its mesh is no output. With `budget`, the refinement makes no more triangles than what
/// the budget has left holds at kDeformedBytesPerTriangle, and throws MemoryBudgetError (naming
/// the node) where it would: a lattice stretching its child a million times along an axis asked
/// for billions of triangles and filled memory. The budget is not kept taken.
std::shared_ptr<const MeshLeaf> deform_child_mesh(const std::shared_ptr<const Graph>& graph, NodeId ffd,
                                                  const TriangleMesh& child_mesh, double max_edge = 0.0,
                                                  double threshold = 0.0, std::size_t* crossing = nullptr,
                                                  MemoryBudget* budget = nullptr);

/// What a deformed mesh holds a triangle while it is refined and made a mesh leaf: the pass's
/// two meshes (about 48 bytes) and the leaf (about 180: arrays, normals, Embree's hierarchy).
inline constexpr double kDeformedBytesPerTriangle = 256.0;

/// A copy of `graph` in which ffd node `ffd` carries `leaf` (node ids unchanged, supports
/// recomputed).
std::shared_ptr<const Graph> attach_ffd_mesh(const Graph& graph, NodeId ffd, std::shared_ptr<const MeshLeaf> leaf);
/// The same for an ffd whose child's solid is empty: nothing to deform, so its deformed mesh is
/// empty and its field 0 everywhere (params::ffd_empty); an operand of a bigger tree, it adds
/// nothing.
std::shared_ptr<const Graph> attach_empty_ffd(const Graph& graph, NodeId ffd);

/// The tree with every ffd under its root prepared at `precision`, each child meshed with the
/// automatic strategy (runs the mesh plan's field jobs; returns the tree itself when nothing
/// needs preparing).
Tree prepare_ffd(const Tree& tree, double precision);

}  // namespace ht
