// Typed views of the parameters each kind keeps in the graph's pool (layouts: nodes/primitives.hpp,
// nodes/warps.hpp, runtime/graph.hpp), so that the compiler, the interval rules, the reference
// evaluator, the supports, the optimizer and the scene writer read fields by name, not offset.
// Views point into the graph: valid while it lives, read-only.
#pragma once

#include "nodes/primitives.hpp"
#include "nodes/warps.hpp"
#include "runtime/graph.hpp"

#include <glm/vec3.hpp>

#include <span>

namespace ht {
struct MeshFieldParams;
}

namespace ht::params {

/// The pseudo-distance field parameters of a mesh leaf (as stored) or of a prepared ffd (from
/// its R and F): what every evaluator of its field reads.
MeshFieldParams mesh_field(const Graph& g, NodeId n, double T);

struct Primitive {
  double R, F;
  const double* skeleton;  ///< the skeleton's own layout (a curve: its control points block)
};
inline Primitive primitive(const Graph& g, NodeId n) {
  const auto p = g.params_of(n);
  return {p[kPrimR], p[kPrimF], p.data() + kPrimSkeleton};
}

/// A mesh leaf's stored falloff: R, F, then what mesh_field_params derived from them.
struct MeshLeafParams {
  double R, F, kernel_radius, r0, query_radius;
};
inline MeshLeafParams mesh_leaf(const Graph& g, NodeId n) {
  const auto p = g.params_of(n);
  return {p[0], p[1], p[2], p[3], p[4]};
}

struct Crop {
  Aabb box;
  const double* box6;  ///< lo(3) hi(3), as nodes/operators.hpp crop_box_field reads it
};
inline Crop crop(const Graph& g, NodeId n) {
  const double* p = g.params_of(n).data();
  return {Aabb{{p[0], p[1], p[2]}, {p[3], p[4], p[5]}}, p};
}

struct Ffd {
  Aabb lattice;
  int l, m, n;
  double R, F;
  std::span<const double> points;  ///< (l+1)(m+1)(n+1) control points, x fastest
};
inline Ffd ffd(const Graph& g, NodeId node) {
  const auto p = g.params_of(node);
  return {Aabb{{p[0], p[1], p[2]}, {p[3], p[4], p[5]}}, int(p[6]), int(p[7]), int(p[8]), p[9], p[10],
          p.subspan(kFfdHeader)};
}
/// An ffd whose child's solid is empty: its deformed mesh is empty and its field 0 everywhere.
/// The mesh plan marks it by a strength of 0 (GraphWriter::empty_ffd), which no scene may say.
inline bool ffd_empty(const Graph& g, NodeId n) {
  return g.kind[n] == NodeKind::Ffd && g.mesh[n] == kNone && g.params_of(n)[kFfdHeader - 1] == 0.0;
}
/// An ffd that still waits for its deformed mesh (meshers/ffd.hpp).
inline bool ffd_unprepared(const Graph& g, NodeId n) {
  return g.kind[n] == NodeKind::Ffd && g.mesh[n] == kNone && !ffd_empty(g, n);
}

/// Twist, taper and bend share axis and centre; then twist: rate; taper: h0 h1 s0 s1;
/// bend: h0 h1 rate.
struct Barr {
  int axis;
  glm::dvec3 center;
  double rate;            ///< twist and bend
  double h0, h1, s0, s1;  ///< taper (h0 h1 for bend too)
};
inline Barr barr(NodeKind k, std::span<const double> p) {
  Barr b{int(p[0]), {p[1], p[2], p[3]}, 0.0, 0.0, 0.0, 1.0, 1.0};
  switch (k) {
    case NodeKind::Twist: b.rate = p[4]; break;
    case NodeKind::Taper: b.h0 = p[4], b.h1 = p[5], b.s0 = p[6], b.s1 = p[7]; break;
    default: b.h0 = p[4], b.h1 = p[5], b.rate = p[6]; break;
  }
  return b;
}
inline Barr barr(const Graph& g, NodeId n) { return barr(g.kind[n], g.params_of(n)); }

/// Whether a twist, taper or bend leaves every point where it is.
inline bool barr_is_identity(NodeKind k, const Barr& b) {
  return k == NodeKind::Taper ? b.s0 == 1.0 && b.s1 == 1.0 : b.rate == 0.0;
}

}  // namespace ht::params
