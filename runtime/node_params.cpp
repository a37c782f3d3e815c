#include "runtime/node_params.hpp"

#include "nodes/mesh_leaf.hpp"

namespace ht::params {

MeshFieldParams mesh_field(const Graph& g, NodeId n, double T) {
  if (g.kind[n] == NodeKind::Ffd) {
    const Ffd f = ffd(g, n);
    return mesh_field_params(f.R, f.F, T);
  }
  const MeshLeafParams m = mesh_leaf(g, n);
  return MeshFieldParams{m.R, m.F, T, m.kernel_radius, m.r0, m.query_radius};
}

}  // namespace ht::params
