// A HybridTree ready for queries: an immutable graph, a root and the threshold T.
//
// field() and gradient() here run the reference evaluator (runtime/tree_eval.hpp): double
// precision, recursive, obviously right. It is the oracle every faster evaluator is tested
// against.
#pragma once

#include "runtime/graph.hpp"

#include <glm/vec3.hpp>

#include <memory>
#include <span>

namespace ht {

class Tree {
 public:
  Tree(std::shared_ptr<const Graph> graph, NodeId root, double threshold, MesherSettings settings = {});

  /// The field at p.
  double field(const glm::dvec3& p) const;
  /// The field at every point (TBB over points). values.size() must equal points.size().
  void field(std::span<const glm::dvec3> points, std::span<double> values) const;
  /// The gradient at p (central differences of the reference field).
  glm::dvec3 gradient(const glm::dvec3& p) const;
  void gradient(std::span<const glm::dvec3> points, std::span<glm::dvec3> gradients) const;

  /// The same graph rooted at another node (each node is a tree of its own).
  Tree subtree(NodeId node) const { return Tree(graph_, node, threshold_, settings_); }

  const Graph& graph() const { return *graph_; }
  std::shared_ptr<const Graph> graph_ptr() const { return graph_; }
  NodeId root() const { return root_; }
  double threshold() const { return threshold_; }
  const MesherSettings& mesher_settings() const { return settings_; }

 private:
  std::shared_ptr<const Graph> graph_;
  NodeId root_;
  double threshold_;
  MesherSettings settings_;
};

}  // namespace ht
