// The graph writer (runtime/graph_writer.hpp) and the support rules every writer applies.
#include "runtime/graph_writer.hpp"

#include "nodes/mesh_leaf.hpp"
#include "nodes/operators.hpp"
#include "nodes/primitives.hpp"
#include "nodes/warps.hpp"
#include "runtime/node_params.hpp"

#include <cstring>
#include <stdexcept>
#include <string>

namespace ht {

GraphWriter::GraphWriter(Graph start, bool merge) : graph_(std::move(start)), merge_(merge) {}

std::uint32_t GraphWriter::mesh_index(std::shared_ptr<const MeshLeaf> leaf) {
  for (std::size_t i = 0; i < graph_.meshes.size(); ++i)
    if (graph_.meshes[i] == leaf) return static_cast<std::uint32_t>(i);
  graph_.meshes.push_back(std::move(leaf));
  return static_cast<std::uint32_t>(graph_.meshes.size() - 1);
}

std::string GraphWriter::key(NodeKind kind, std::span<const double> params, std::span<const NodeId> children,
                             BooleanMode mode, MesherHint hint, std::uint32_t mesh, const std::string& name) const {
  std::string k;
  k.reserve(16 + 8 * params.size() + 4 * children.size() + name.size());
  const std::uint8_t head[3] = {static_cast<std::uint8_t>(kind), static_cast<std::uint8_t>(mode),
                                static_cast<std::uint8_t>(hint)};
  k.append(reinterpret_cast<const char*>(head), sizeof head);
  const std::uint32_t counts[3] = {static_cast<std::uint32_t>(params.size()), static_cast<std::uint32_t>(children.size()), mesh};
  k.append(reinterpret_cast<const char*>(counts), sizeof counts);
  k.append(reinterpret_cast<const char*>(params.data()), params.size_bytes());
  k.append(reinterpret_cast<const char*>(children.data()), children.size_bytes());
  k.append(name);
  return k;
}

NodeId GraphWriter::append(NodeKind kind, std::span<const double> params, std::span<const NodeId> children,
                           BooleanMode mode, MesherHint hint, std::uint32_t mesh, std::string name) {
  std::string k;
  if (merge_) {
    k = key(kind, params, children, mode, hint, mesh, name);
    if (auto it = seen_.find(k); it != seen_.end()) {
      ++merged_;
      return it->second;
    }
  }
  Graph& g = graph_;
  const auto id = static_cast<NodeId>(g.size());
  g.kind.push_back(kind);
  g.boolean.push_back(mode);
  g.mesher.push_back(hint);
  g.param_begin.push_back(static_cast<std::uint32_t>(g.params.size()));
  g.param_count.push_back(static_cast<std::uint32_t>(params.size()));
  g.params.insert(g.params.end(), params.begin(), params.end());
  g.child_begin.push_back(static_cast<std::uint32_t>(g.children.size()));
  g.child_count.push_back(static_cast<std::uint32_t>(children.size()));
  g.children.insert(g.children.end(), children.begin(), children.end());
  g.derived_begin.push_back(static_cast<std::uint32_t>(g.derived.size()));
  g.derived_count.push_back(0);
  g.mesh.push_back(mesh);
  g.name.push_back(kNone);
  g.support_alone.emplace_back();
  g.support_blended.emplace_back();
  g.nonnegative.push_back(0);
  if (kind == NodeKind::Curve) {  // the polyline the evaluators read (nodes/primitives.hpp)
    const auto count = static_cast<std::size_t>(params[kPrimSkeleton]);
    std::vector<glm::dvec3> points(count);
    for (std::size_t i = 0; i < count; ++i)
      points[i] = {params[kPrimSkeleton + 1 + 3 * i], params[kPrimSkeleton + 2 + 3 * i], params[kPrimSkeleton + 3 + 3 * i]};
    const std::vector<glm::dvec3> poly = curve_polyline(points, kCurveTolerance * params[kPrimR]);
    g.derived.push_back(static_cast<double>(poly.size()));
    for (const auto& q : poly) g.derived.insert(g.derived.end(), {q.x, q.y, q.z});
    g.derived_count[id] = static_cast<std::uint32_t>(1 + 3 * poly.size());
  }
  if (!name.empty()) set_name(id, std::move(name));
  compute_support(g, id);
  if (merge_) seen_.emplace(std::move(k), id);
  return id;
}

NodeId GraphWriter::add(NodeKind kind, std::span<const double> params, std::span<const NodeId> children,
                        BooleanMode mode, MesherHint hint, std::string name) {
  return append(kind, params, children, mode, hint, kNone, std::move(name));
}

NodeId GraphWriter::add_mesh(std::shared_ptr<const MeshLeaf> leaf, std::span<const double> params, std::string name) {
  const std::uint32_t index = mesh_index(std::move(leaf));
  return append(NodeKind::Mesh, params, {}, BooleanMode::Auto, MesherHint::Auto, index, std::move(name));
}

NodeId GraphWriter::copy(const Graph& from, NodeId n, std::span<const NodeId> children) {
  std::string name = from.name[n] != kNone ? from.names[from.name[n]] : std::string();
  const std::uint32_t mesh = from.mesh[n] != kNone ? mesh_index(from.meshes[from.mesh[n]]) : kNone;
  return append(from.kind[n], from.params_of(n), children, from.boolean[n], from.mesher[n], mesh, std::move(name));
}

void GraphWriter::attach_mesh(NodeId n, std::shared_ptr<const MeshLeaf> leaf) {
  graph_.mesh.at(n) = mesh_index(std::move(leaf));
  compute_supports(graph_);  // the ffd's support changes, and with it its ancestors'
}

void GraphWriter::empty_ffd(NodeId n) {
  if (graph_.kind.at(n) != NodeKind::Ffd) throw std::invalid_argument("empty_ffd: node " + std::to_string(n) + " is no ffd");
  graph_.params.at(graph_.param_begin.at(n) + kFfdHeader - 1) = 0.0;
  compute_supports(graph_);
}

void GraphWriter::set_name(NodeId n, std::string name) {
  graph_.name.at(n) = static_cast<std::uint32_t>(graph_.names.size());
  graph_.names.push_back(std::move(name));
}

void GraphWriter::set_boolean(NodeId n, BooleanMode mode) {
  graph_.boolean.at(n) = mode;
  compute_support(graph_, n);
}

Graph GraphWriter::take() {
  Graph out = std::move(graph_);
  graph_ = Graph{};
  seen_.clear();
  return out;
}

// Supports and signs, bottom-up (children have smaller ids). The rules follow from the
// formulas in nodes/operators.hpp: where every child is 0, a blend, a union of either kind and
// an R-function intersection are 0; a min/max intersection of non-negative fields is 0 where
// either is; a min/max difference is 0 where A is; an R-function difference is not 0 anywhere
// (it tends to 2T/(2+sqrt 2) far from both), so its support is everything.
void compute_support(Graph& g, NodeId n) {
  {
    const NodeKind k = g.kind[n];
    const auto p = g.params_of(n);
    const auto c = g.children_of(n);
    auto sup = [&](NodeId child, bool blended) { return g.support(child, blended); };
    bool all_children_nonneg = true;
    for (NodeId child : c) all_children_nonneg = all_children_nonneg && g.nonnegative[child];
    bool nonneg_both = true;  // the sign must hold in both contexts
    for (int blended = 0; blended < 2; ++blended) {
      bool nonneg = all_children_nonneg;
      // Children of a blend or local blend see a blend above them.
      const bool below = blended || k == NodeKind::Blend || k == NodeKind::LocalBlend;
      Aabb box;
      switch (kind_family(k)) {
        case Family::Primitive: {
          const params::Primitive prim = params::primitive(g, n);
          box = skeleton_bounds(k, g.skeleton_of(n)).expanded(prim.R);
          nonneg = prim.F > 0.0;
          break;
        }
        case Family::Mesh: {
          const params::MeshLeafParams m = params::mesh_leaf(g, n);
          box = g.meshes[g.mesh[n]]->bounds().expanded(m.R);
          nonneg = m.F > 0.0;
          break;
        }
        case Family::Warp:
          if (k == NodeKind::Ffd) {  // its field lives on its deformed mesh, once meshed
            const params::Ffd f = params::ffd(g, n);
            box = g.mesh[n] != kNone ? g.meshes[g.mesh[n]]->bounds().expanded(f.R)
                  : f.F == 0.0       ? Aabb{}  // prepared, empty: 0 everywhere
                                     : Aabb::everything();
            nonneg = f.F > 0.0;
          } else {
            box = warp_bounds(k, p.data(), sup(c[0], below));
          }
          break;
        case Family::Operator: {
          const bool rf = use_rfunction(g.boolean[n], blended);
          for (NodeId child : c) box = merge(box, sup(child, below));
          if (k == NodeKind::Intersection && !rf) {
            if (all_children_nonneg) {
              box = Aabb::everything();
              for (NodeId child : c) box = ht::intersect(box, sup(child, below));
            }
          } else if (k == NodeKind::Difference) {
            box = rf && c.size() > 1 ? Aabb::everything() : sup(c[0], below);
            nonneg = c.size() > 1 || all_children_nonneg;  // one child: the child itself
          } else if (k == NodeKind::Union && !rf) {
            nonneg = false;
            for (NodeId child : c) nonneg = nonneg || g.nonnegative[child];
          } else if (k == NodeKind::LocalBlend) {
            box = merge(sup(c[0], below), sup(c[1], below));
            nonneg = g.nonnegative[c[0]] && g.nonnegative[c[1]];
          } else if (k == NodeKind::Crop) {
            const params::Crop crop = params::crop(g, n);
            box = ht::intersect(sup(c[0], below), crop.box.expanded(crop_reach(crop.box6)));
            nonneg = true;
          }
          break;
        }
      }
      if (box.empty()) box = Aabb{};
      (blended ? g.support_blended : g.support_alone)[n] = box;
      nonneg_both = nonneg_both && nonneg;
    }
    g.nonnegative[n] = nonneg_both ? 1 : 0;
  }
}

void compute_supports(Graph& g) {
  for (NodeId n = 0; n < g.size(); ++n) compute_support(g, n);
}

}  // namespace ht
