// Free-form deformation nodes (Sederberg & Parry 1986; the paper, section 3.3.2). An ffd has no
// closed-form inverse, so, as in the paper, its field goes through a mesh: the child is meshed at
// the current precision, every vertex is moved by the trivariate Bernstein map of the lattice,
// and the ffd's field is the pseudo-distance field of that deformed mesh (a mesh leaf with the
// ffd's radius and strength). prepare_ffd() does this for every ffd under a root, innermost
// first, and returns a graph in which they compile and evaluate like mesh leaves.
#pragma once

#include "runtime/graph.hpp"
#include "runtime/tree.hpp"

namespace ht {

/// True when some ffd node under `root` still waits for its deformed mesh.
bool needs_ffd_preparation(const Graph& graph, NodeId root);

/// A copy of the graph whose ffd nodes under `root` carry their deformed meshes (node ids are
/// unchanged). Children are meshed with the global polygonizer at `precision`. Throws
/// PolygonizeError when a child's surface is empty or cannot be meshed.
std::shared_ptr<const Graph> prepare_ffd(std::shared_ptr<const Graph> graph, NodeId root, double threshold,
                                         double precision);

/// The same for a Tree (returns the tree itself when nothing needs preparing).
Tree prepare_ffd(const Tree& tree, double precision);

}  // namespace ht
