// The reference evaluator: walks the graph recursively in double precision, one point at a
// time, straight from the formulas of SCENE_FORMAT.md. Slow on purpose and small on purpose:
// it is the oracle the tape evaluator is held to.
#pragma once

#include "runtime/graph.hpp"

#include <glm/vec3.hpp>

#include <stdexcept>

namespace ht {

/// Thrown for a query the reference evaluator cannot answer (an ffd before its mesh exists).
struct EvalError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// f at p of node `node`; `under_blend` is whether a blend or local blend is above it (it picks
/// the `auto` Boolean rule).
double reference_field(const Graph& graph, NodeId node, double threshold, const glm::dvec3& p,
                       bool under_blend = false);

/// The gradient of reference_field by the chain rule through the tree: mesh leaves exactly
/// (mesh_field_gradient: on a mesh, the one-sided limit from outside along the inward
/// pseudo-normal, never zero), warps through the central-difference Jacobian of w^-1,
/// primitives and the crop box by central differences, operators by their partial derivatives
/// in value space; steps relative to |p| so that it stays accurate far from the origin.
glm::dvec3 reference_gradient(const Graph& graph, NodeId node, double threshold, const glm::dvec3& p,
                              bool under_blend = false);

}  // namespace ht
