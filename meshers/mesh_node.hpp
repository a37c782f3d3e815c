// Per-node meshing: every node answers "what is your mesh at this precision?" with the strategy
// that fits it (the paper, sections 3.1-3.3):
//   mesh leaf        its own mesh, shared, never copied
//   primitive        the sweep mesh of its skeleton at r0 (meshers/sweep.hpp)
//   warp             its child's mesh, warped, with local remeshing of stretched edges
//                    (meshers/warp_mesh.hpp); a prepared ffd answers its deformed mesh
//   operator         the global polygonizer on its subtree (meshers/polygonize.hpp); the
//                    paper's local strategies for blends and Booleans come later
// MeshStrategy::Global polygonizes the node whatever it is; a node's own `mesher` hint in the
// scene overrides the requested strategy for that node. The log says which strategy each node
// used and why.
#pragma once

#include "meshers/polygonize.hpp"
#include "meshers/triangle_mesh.hpp"
#include "runtime/tree.hpp"

#include <memory>
#include <string>
#include <vector>

namespace ht {

enum class MeshStrategy { Auto, Global, Local };

struct MeshLogEntry {
  NodeId node;
  std::string strategy;  ///< "shared leaf mesh", "sweep", "warped child", "global", ...
  std::size_t triangles;
  double seconds;
};

/// The mesh of node `node` of `tree` (whose ffd nodes must be prepared, meshers/ffd.hpp) at
/// `precision`. Throws PolygonizeError for what cannot be meshed.
std::shared_ptr<const TriangleMesh> mesh_node(const Tree& tree, NodeId node, double precision, MeshStrategy strategy,
                                              std::vector<MeshLogEntry>* log = nullptr,
                                              const PolygonizeOptions* global_options = nullptr);

}  // namespace ht
