#include "meshers/mesh_node.hpp"

#include "meshers/sweep.hpp"
#include "meshers/warp_mesh.hpp"
#include "nodes/mesh_leaf.hpp"
#include "runtime/tape.hpp"
#include "runtime/tape_eval.hpp"

#include <chrono>

namespace ht {
namespace {

double since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::shared_ptr<const TriangleMesh> global(const Tree& tree, NodeId node, double precision, const PolygonizeOptions* base) {
  PolygonizeOptions o = base ? *base : PolygonizeOptions{};
  o.precision = precision;
  return std::make_shared<const TriangleMesh>(polygonize(tree.graph_ptr(), node, tree.threshold(), o));
}

}  // namespace

std::shared_ptr<const TriangleMesh> mesh_node(const Tree& tree, NodeId node, double precision, MeshStrategy strategy,
                                              std::vector<MeshLogEntry>* log, const PolygonizeOptions* options) {
  const Graph& g = tree.graph();
  const auto t0 = std::chrono::steady_clock::now();
  // The node's own hint wins over the request.
  if (g.mesher[node] == MesherHint::Global) strategy = MeshStrategy::Global;
  if (g.mesher[node] == MesherHint::Local) strategy = MeshStrategy::Local;
  std::shared_ptr<const TriangleMesh> mesh;
  std::string used;
  const NodeKind kind = g.kind[node];
  if (strategy == MeshStrategy::Global) {
    mesh = global(tree, node, precision, options);
    used = "global";
  } else if (kind == NodeKind::Mesh || (kind == NodeKind::Ffd && g.mesh[node] != kNone)) {
    mesh = g.meshes[g.mesh[node]]->surface();
    used = kind == NodeKind::Mesh ? "shared leaf mesh" : "deformed child mesh (ffd)";
  } else if (kind_family(kind) == Family::Primitive) {
    mesh = std::make_shared<const TriangleMesh>(sweep_mesh(g, node, tree.threshold(), precision));
    used = "sweep";
  } else if (kind_family(kind) == Family::Warp && kind != NodeKind::Ffd) {
    const NodeId child = g.children_of(node)[0];
    const auto child_mesh = mesh_node(tree, child, precision, strategy, log, options);
    const TapeEvaluator child_field(std::make_shared<const Tape>(compile_tape(tree.graph_ptr(), child, tree.threshold())));
    WarpRemeshStats ws;
    mesh = std::make_shared<const TriangleMesh>(
        warp_mesh(*child_mesh, forward_map(g, node), child_field, tree.threshold(), 1.5 * precision, &ws));
    used = "warped child (" + std::to_string(ws.edges_split) + " edges split)";
  } else {
    mesh = global(tree, node, precision, options);
    used = kind == NodeKind::Ffd ? "global (ffd not prepared)" : "global (operators mesh globally for now)";
  }
  if (log) log->push_back({node, used, mesh->triangles.size(), since(t0)});
  return mesh;
}

}  // namespace ht
