#include "runtime/tree_eval.hpp"

#include "nodes/mesh_leaf.hpp"
#include "nodes/operators.hpp"
#include "nodes/primitives.hpp"
#include "nodes/warps.hpp"
#include "runtime/node_params.hpp"
#include "runtime/tape.hpp"
#include "runtime/tape_eval.hpp"
#include "runtime/tree.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <mutex>
#include <span>

namespace ht {

namespace {
}  // namespace

double reference_field(const Graph& g, NodeId n, double T, const glm::dvec3& p, bool under_blend) {
  const NodeKind k = g.kind[n];
  const auto prm = g.params_of(n);
  const auto c = g.children_of(n);
  const bool rf = use_rfunction(g.boolean[n], under_blend);
  auto child = [&](std::size_t i, const glm::dvec3& q, bool blended) {
    return reference_field(g, c[i], T, q, blended);
  };
  switch (k) {
    case NodeKind::Mesh: return mesh_field(*g.meshes[g.mesh[n]], params::mesh_field(g, n, T), p);
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
      if (params::ffd_empty(g, n)) return 0.0;
      if (g.mesh[n] == kNone)
        throw EvalError("ffd node " + g.label(n) +
                        ": its field is the distance to its deformed mesh, which needs meshing first (meshers/ffd.hpp)");
      return mesh_field(*g.meshes[g.mesh[n]], params::mesh_field(g, n, T), p);
    default:  // skeletal primitives
      return falloff(skeleton_distance(k, g.skeleton_of(n), p), prm[kPrimR], prm[kPrimF]);
  }
}

namespace {

struct ValueGradient {
  double v = 0;
  glm::dvec3 g{0.0};
};

double step_at(const glm::dvec3& p) { return 1e-6 * std::max({1.0, std::abs(p.x), std::abs(p.y), std::abs(p.z)}); }

// Central differences of a smooth function of space (a primitive's field, the crop box field).
template <class Fn>
glm::dvec3 central_gradient(const glm::dvec3& p, Fn&& f) {
  const double h = step_at(p);
  glm::dvec3 grad;
  for (int axis = 0; axis < 3; ++axis) {
    glm::dvec3 a = p, b = p;
    a[axis] += h;
    b[axis] -= h;
    grad[axis] = (f(a) - f(b)) / (2.0 * h);
  }
  return grad;
}

// The partial derivative of an operator's combination h(x[0..n)) in x[i], by central
// differences in value space (max, min and clamps pick their branch as the tape does, away
// from ties).
template <class Fn, std::size_t N>
double partial(Fn&& h, std::array<double, N> x, std::size_t i) {
  const double e = 1e-7 * std::max(1.0, std::abs(x[i])), xi = x[i];
  x[i] = xi + e;
  const double up = h(x);
  x[i] = xi - e;
  return (up - h(x)) / (2.0 * e);
}

template <class Fn, std::size_t N>
ValueGradient combine(Fn&& h, const std::array<ValueGradient, N>& in) {
  std::array<double, N> x;
  for (std::size_t i = 0; i < N; ++i) x[i] = in[i].v;
  ValueGradient out{h(x), glm::dvec3(0.0)};
  for (std::size_t i = 0; i < N; ++i)
    if (in[i].g != glm::dvec3(0.0)) out.g += partial(h, x, i) * in[i].g;
  return out;
}

ValueGradient value_gradient(const Graph& g, NodeId n, double T, const glm::dvec3& p, bool under_blend);

ValueGradient boolean_value_gradient(const Graph& g, NodeId n, double T, const glm::dvec3& p, bool under_blend) {
  const NodeKind k = g.kind[n];
  const auto c = g.children_of(n);
  const bool rf = use_rfunction(g.boolean[n], under_blend);
  auto op = [&](const std::array<double, 2>& x) {
    return k == NodeKind::Union          ? union_field(x[0], x[1], T, rf)
           : k == NodeKind::Intersection ? intersection_field(x[0], x[1], T, rf)
                                         : difference_field(x[0], x[1], T, rf);
  };
  ValueGradient f = value_gradient(g, c[0], T, p, under_blend);
  for (std::size_t i = 1; i < c.size(); ++i) f = combine(op, std::array{f, value_gradient(g, c[i], T, p, under_blend)});
  return f;
}

// The chain rule through the tree in double: mesh leaves analytic (mesh_field_gradient), warps
// by the central-difference Jacobian of w^-1, primitives by central differences, operators by
// their partial derivatives.
ValueGradient value_gradient(const Graph& g, NodeId n, double T, const glm::dvec3& p, bool under_blend) {
  const NodeKind k = g.kind[n];
  const auto prm = g.params_of(n);
  const auto c = g.children_of(n);
  auto child = [&](std::size_t i, const glm::dvec3& q, bool blended) { return value_gradient(g, c[i], T, q, blended); };
  switch (k) {
    case NodeKind::Mesh: {
      const MeshFieldSample s = mesh_field_gradient(*g.meshes[g.mesh[n]], params::mesh_field(g, n, T), p);
      return {s.value, s.gradient};
    }
    case NodeKind::Ffd: {
      if (g.mesh[n] == kNone) return {reference_field(g, n, T, p, under_blend), glm::dvec3(0.0)};  // 0, or throws
      const MeshFieldSample s = mesh_field_gradient(*g.meshes[g.mesh[n]], params::mesh_field(g, n, T), p);
      return {s.value, s.gradient};
    }
    case NodeKind::Blend: {
      ValueGradient sum;
      for (std::size_t i = 0; i < c.size(); ++i) {
        const ValueGradient f = child(i, p, true);
        sum.v += f.v;
        sum.g += f.g;
      }
      return sum;
    }
    case NodeKind::Union:
    case NodeKind::Intersection:
    case NodeKind::Difference: return boolean_value_gradient(g, n, T, p, under_blend);
    case NodeKind::LocalBlend: {
      const bool rf = use_rfunction(g.boolean[n], under_blend);
      auto op = [&](const std::array<double, 3>& x) { return local_blend_field(x[0], x[1], x[2], T, rf); };
      return combine(op, std::array{child(0, p, true), child(1, p, true), child(2, p, true)});
    }
    case NodeKind::Crop: {
      auto box = [&](const glm::dvec3& q) { return crop_box_field(prm.data(), T, q); };
      const ValueGradient h{box(p), central_gradient(p, box)};
      auto op = [](const std::array<double, 2>& x) { return std::max(0.0, std::min(x[0], x[1])); };
      return combine(op, std::array{child(0, p, under_blend), h});
    }
    case NodeKind::Affine:
    case NodeKind::Twist:
    case NodeKind::Taper:
    case NodeKind::Bend: {
      const ValueGradient f = child(0, warp_inverse(k, prm.data(), p), under_blend);
      if (f.g == glm::dvec3(0.0)) return f;
      // grad (f o w^-1)(p) = J^T grad f, J the Jacobian of w^-1 at p: the gradient of the
      // linear function q -> grad f . w^-1(q).
      return {f.v, central_gradient(p, [&](const glm::dvec3& q) { return glm::dot(warp_inverse(k, prm.data(), q), f.g); })};
    }
    default: {  // skeletal primitives
      auto field = [&](const glm::dvec3& q) { return falloff(skeleton_distance(k, g.skeleton_of(n), q), prm[kPrimR], prm[kPrimF]); };
      return {field(p), central_gradient(p, field)};
    }
  }
}

}  // namespace

glm::dvec3 reference_gradient(const Graph& g, NodeId n, double T, const glm::dvec3& p, bool under_blend) {
  return value_gradient(g, n, T, p, under_blend).g;
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
