#include "meshers/ffd.hpp"

#include "meshers/polygonize.hpp"
#include "nodes/mesh_leaf.hpp"
#include "nodes/warps.hpp"

#include <vector>

namespace ht {
namespace {

void collect(const Graph& g, NodeId n, std::vector<std::uint8_t>& seen) {
  if (seen[n]) return;
  seen[n] = 1;
  for (NodeId c : g.children_of(n)) collect(g, c, seen);
}

}  // namespace

bool needs_ffd_preparation(const Graph& g, NodeId root) {
  std::vector<std::uint8_t> seen(g.size(), 0);
  collect(g, root, seen);
  for (NodeId n = 0; n < g.size(); ++n)
    if (seen[n] && g.kind[n] == NodeKind::Ffd && g.mesh[n] == kNone) return true;
  return false;
}

std::shared_ptr<const Graph> prepare_ffd(std::shared_ptr<const Graph> graph, NodeId root, double T, double precision) {
  if (!needs_ffd_preparation(*graph, root)) return graph;
  std::vector<std::uint8_t> seen(graph->size(), 0);
  collect(*graph, root, seen);
  // Children have smaller ids: walking ids upward prepares inner ffds before outer ones.
  auto current = std::make_shared<Graph>(*graph);
  for (NodeId n = 0; n < current->size(); ++n) {
    if (!seen[n] || current->kind[n] != NodeKind::Ffd || current->mesh[n] != kNone) continue;
    const NodeId child = current->children_of(n)[0];
    PolygonizeOptions options;
    options.precision = precision;
    TriangleMesh mesh = polygonize(current, child, T, options);
    if (mesh.triangles.empty())
      throw PolygonizeError("ffd node " + current->label(n) + ": its child's surface is empty, there is nothing to deform");
    const double* params = current->params_of(n).data();
    for (glm::dvec3& v : mesh.positions) v = warp_forward(NodeKind::Ffd, params, v);
    std::shared_ptr<const MeshLeaf> leaf;
    try {
      leaf = MeshLeaf::from_triangles(std::move(mesh.positions), std::move(mesh.triangles),
                                      "deformed mesh of ffd node " + current->label(n));
    } catch (const MeshError& e) {
      throw PolygonizeError(e.what());
    }
    auto next = std::make_shared<Graph>(*current);
    next->mesh[n] = static_cast<std::uint32_t>(next->meshes.size());
    next->meshes.push_back(std::move(leaf));
    compute_supports(*next);
    current = std::move(next);
  }
  return current;
}

Tree prepare_ffd(const Tree& tree, double precision) {
  if (!needs_ffd_preparation(tree.graph(), tree.root())) return tree;
  return Tree(prepare_ffd(tree.graph_ptr(), tree.root(), tree.threshold(), precision), tree.root(), tree.threshold(),
              tree.mesher_settings());
}

}  // namespace ht
