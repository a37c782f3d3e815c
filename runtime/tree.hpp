// A HybridTree ready for queries: an immutable graph, a root and the threshold T.
//
// field() and gradient() run the compiled tape (runtime/tape.hpp, float, SIMD blocks, TBB),
// compiled on first use and shared by copies of the Tree. reference() and
// reference_gradient() run the reference evaluator (runtime/tree_eval.hpp): double precision,
// recursive, obviously right; it is the oracle the tape is tested against.
#pragma once

#include "runtime/graph.hpp"

#include <glm/vec3.hpp>

#include <memory>
#include <span>

namespace ht {

class TapeEvaluator;

class Tree {
 public:
  Tree(std::shared_ptr<const Graph> graph, NodeId root, double threshold, MesherSettings settings = {});

  /// The field at p (tape; prefer the batch form).
  double field(const glm::dvec3& p) const;
  /// The field at every point (tape, TBB over blocks). values.size() must equal points.size().
  void field(std::span<const glm::dvec3> points, std::span<double> values) const;
  /// The gradient at p (tape, forward-mode differentiation).
  glm::dvec3 gradient(const glm::dvec3& p) const;
  void gradient(std::span<const glm::dvec3> points, std::span<glm::dvec3> gradients) const;

  /// The reference evaluator: double precision, recursive, one point at a time.
  double reference(const glm::dvec3& p) const;
  /// The reference evaluator over many points (TBB over points).
  void reference(std::span<const glm::dvec3> points, std::span<double> values) const;
  /// Central-difference gradient of the reference field.
  glm::dvec3 reference_gradient(const glm::dvec3& p) const;
  void reference_gradient(std::span<const glm::dvec3> points, std::span<glm::dvec3> gradients) const;

  /// The compiled tape's evaluator (compiled on first call; throws CompileError for an ffd).
  const TapeEvaluator& evaluator() const;

  /// The same graph rooted at another node (each node is a tree of its own).
  Tree subtree(NodeId node) const { return Tree(graph_, node, threshold_, settings_); }

  const Graph& graph() const { return *graph_; }
  std::shared_ptr<const Graph> graph_ptr() const { return graph_; }
  NodeId root() const { return root_; }
  double threshold() const { return threshold_; }
  const MesherSettings& mesher_settings() const { return settings_; }

 private:
  struct Compiled;
  std::shared_ptr<const Graph> graph_;
  NodeId root_;
  double threshold_;
  MesherSettings settings_;
  std::shared_ptr<Compiled> compiled_;  // the tape, compiled once, shared by copies
};

}  // namespace ht
