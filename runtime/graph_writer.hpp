// The one way to write a Graph: the builder, ffd preparation and the optimizer append nodes
// through a GraphWriter, which keeps every per-node array in step, derives what a kind needs (a
// curve's polyline), fills the node's support and sign as soon as it is added (so a writer can
// ask about what it has written), and, when asked to, merges identical nodes.
//
// Not thread-safe: one writer, one thread. Node ids are dense and children always precede
// their parents, as Graph requires.
#pragma once

#include "runtime/graph.hpp"

#include <span>
#include <string>
#include <unordered_map>

namespace ht {

class GraphWriter {
 public:
  /// merge: a node equal to one already written (kind, Boolean mode, mesher hint, parameters
  /// bit for bit, children, mesh, name) is not written again; add() returns the earlier id.
  explicit GraphWriter(bool merge = false) : merge_(merge) {}
  /// Continues an existing graph (its supports must be computed).
  explicit GraphWriter(Graph start, bool merge = false);

  /// Appends a node of any kind but mesh; children must be ids of this graph. A curve's
  /// polyline is derived here from its points and R.
  NodeId add(NodeKind kind, std::span<const double> params, std::span<const NodeId> children,
             BooleanMode mode = BooleanMode::Auto, MesherHint hint = MesherHint::Auto, std::string name = {});
  /// Appends a mesh leaf (params: R F kernel_radius r0 query_radius); the mesh joins the pool
  /// once however many leaves name it.
  NodeId add_mesh(std::shared_ptr<const MeshLeaf> leaf, std::span<const double> params, std::string name = {});
  /// Copies node n of `from` with new children (ids of this graph, as many as n has).
  NodeId copy(const Graph& from, NodeId n, std::span<const NodeId> children);
  /// Gives node n (a prepared ffd) its deformed mesh, and updates its support.
  void attach_mesh(NodeId n, std::shared_ptr<const MeshLeaf> leaf);
  /// Marks node n (an ffd whose child's solid is empty) as prepared with an empty deformed mesh:
  /// its field is 0 everywhere (params::ffd_empty), and its support empty.
  void empty_ffd(NodeId n);

  void set_name(NodeId n, std::string name);
  void set_mesher(NodeId n, MesherHint hint) { graph_.mesher.at(n) = hint; }
  /// Changes a Boolean's mode; n's support follows, its parents' do not: call it before any
  /// parent of n is written.
  void set_boolean(NodeId n, BooleanMode mode);

  const Graph& graph() const { return graph_; }
  std::size_t size() const { return graph_.size(); }
  /// How many add() calls returned an earlier node (merge on).
  std::size_t merged() const { return merged_; }
  /// Hands the graph over (supports up to date); the writer is empty afterwards.
  Graph take();

 private:
  std::uint32_t mesh_index(std::shared_ptr<const MeshLeaf> leaf);
  NodeId append(NodeKind kind, std::span<const double> params, std::span<const NodeId> children, BooleanMode mode,
                MesherHint hint, std::uint32_t mesh, std::string name);
  std::string key(NodeKind kind, std::span<const double> params, std::span<const NodeId> children, BooleanMode mode,
                  MesherHint hint, std::uint32_t mesh, const std::string& name) const;

  Graph graph_;
  bool merge_;
  std::size_t merged_ = 0;
  std::unordered_map<std::string, NodeId> seen_;
};

/// Fills support_alone, support_blended and nonnegative of node n from its children's.
void compute_support(Graph& graph, NodeId n);

}  // namespace ht
