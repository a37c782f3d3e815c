#include "runtime/tree_eval.hpp"

#include "nodes/mesh_leaf.hpp"
#include "nodes/operators.hpp"
#include "nodes/primitives.hpp"
#include "nodes/warps.hpp"
#include "runtime/tape.hpp"
#include "runtime/tape_eval.hpp"
#include "runtime/tree.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <mutex>

namespace ht {

double reference_field(const Graph& g, NodeId n, double T, const glm::dvec3& p, bool under_blend) {
  const NodeKind k = g.kind[n];
  const auto prm = g.params_of(n);
  const auto c = g.children_of(n);
  const bool rf = use_rfunction(g.boolean[n], under_blend);
  auto child = [&](std::size_t i, const glm::dvec3& q, bool blended) {
    return reference_field(g, c[i], T, q, blended);
  };
  switch (k) {
    case NodeKind::Mesh: {
      MeshFieldParams m;
      m.R = prm[0];
      m.F = prm[1];
      m.T = T;
      m.kernel_radius = prm[2];
      m.r0 = prm[3];
      m.query_radius = prm[4];
      return mesh_field(*g.meshes[g.mesh[n]], m, p);
    }
    case NodeKind::Blend: {
      double sum = 0.0;
      for (std::size_t i = 0; i < c.size(); ++i) sum += child(i, p, true);
      return sum;
    }
    case NodeKind::Union:
    case NodeKind::Intersection:
    case NodeKind::Difference: {
      double f = child(0, p, under_blend);
      for (std::size_t i = 1; i < c.size(); ++i) {
        const double fb = child(i, p, under_blend);
        f = k == NodeKind::Union          ? union_field(f, fb, T, rf)
            : k == NodeKind::Intersection ? intersection_field(f, fb, T, rf)
                                          : difference_field(f, fb, T, rf);
      }
      return f;
    }
    case NodeKind::LocalBlend:
      return local_blend_field(child(0, p, true), child(1, p, true), child(2, p, true), T, rf);
    case NodeKind::Crop:
      return std::max(0.0, std::min(child(0, p, under_blend), crop_box_field(prm.data(), T, p)));
    case NodeKind::Affine:
    case NodeKind::Twist:
    case NodeKind::Taper:
    case NodeKind::Bend:
      return child(0, warp_inverse(k, prm.data(), p), under_blend);
    case NodeKind::Ffd:
      if (g.mesh[n] == kNone)
        throw EvalError("ffd node " + g.label(n) +
                        ": its field is the distance to its deformed mesh, which needs meshing first (meshers/ffd.hpp)");
      return mesh_field(*g.meshes[g.mesh[n]], mesh_field_params(prm[9], prm[10], T), p);
    default:  // skeletal primitives
      return falloff(skeleton_distance(k, g.skeleton_of(n), p), prm[kPrimR], prm[kPrimF]);
  }
}

glm::dvec3 reference_gradient(const Graph& g, NodeId n, double T, const glm::dvec3& p, bool under_blend) {
  const double scale = std::max({1.0, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
  const double h = 1e-6 * scale;
  glm::dvec3 grad;
  for (int axis = 0; axis < 3; ++axis) {
    glm::dvec3 a = p, b = p;
    a[axis] += h;
    b[axis] -= h;
    grad[axis] = (reference_field(g, n, T, a, under_blend) - reference_field(g, n, T, b, under_blend)) / (2.0 * h);
  }
  return grad;
}

struct Tree::Compiled {
  std::once_flag once;
  std::unique_ptr<TapeEvaluator> evaluator;
  std::exception_ptr error;
};

Tree::Tree(std::shared_ptr<const Graph> graph, NodeId root, double threshold, MesherSettings settings)
    : graph_(std::move(graph)), root_(root), threshold_(threshold), settings_(settings),
      compiled_(std::make_shared<Compiled>()) {}

const TapeEvaluator& Tree::evaluator() const {
  std::call_once(compiled_->once, [&] {
    try {
      compiled_->evaluator =
          std::make_unique<TapeEvaluator>(std::make_shared<const Tape>(compile_tape(graph_, root_, threshold_)));
    } catch (...) {
      compiled_->error = std::current_exception();
    }
  });
  if (compiled_->error) std::rethrow_exception(compiled_->error);
  return *compiled_->evaluator;
}

double Tree::field(const glm::dvec3& p) const { return evaluator().field(p); }

void Tree::field(std::span<const glm::dvec3> points, std::span<double> values) const {
  evaluator().field(points, values);
}

glm::dvec3 Tree::gradient(const glm::dvec3& p) const {
  glm::dvec3 g;
  evaluator().gradient(std::span<const glm::dvec3>(&p, 1), {}, std::span<glm::dvec3>(&g, 1));
  return g;
}

void Tree::gradient(std::span<const glm::dvec3> points, std::span<glm::dvec3> gradients) const {
  evaluator().gradient(points, {}, gradients);
}

double Tree::reference(const glm::dvec3& p) const { return reference_field(*graph_, root_, threshold_, p); }

void Tree::reference(std::span<const glm::dvec3> points, std::span<double> values) const {
  if (values.size() != points.size()) throw std::invalid_argument("Tree::reference: values.size() != points.size()");
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 256), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) values[i] = reference(points[i]);
  });
}

glm::dvec3 Tree::reference_gradient(const glm::dvec3& p) const {
  return ht::reference_gradient(*graph_, root_, threshold_, p);
}

void Tree::reference_gradient(std::span<const glm::dvec3> points, std::span<glm::dvec3> gradients) const {
  if (gradients.size() != points.size())
    throw std::invalid_argument("Tree::reference_gradient: gradients.size() != points.size()");
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 64), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) gradients[i] = reference_gradient(points[i]);
  });
}

}  // namespace ht
