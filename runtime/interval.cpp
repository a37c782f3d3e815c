// Interval analysis: a conservative range of a node's field over a box. Every rule follows the
// monotonicity of a formula in SCENE_FORMAT.md; the tape compiler prunes on these ranges, and
// tests/test_tape.cpp checks them against sampled values.
#include "nodes/mesh_leaf.hpp"
#include "nodes/operators.hpp"
#include "nodes/primitives.hpp"
#include "nodes/warps.hpp"
#include "runtime/interval.hpp"
#include "runtime/node_params.hpp"
#include "runtime/tape.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

namespace ht {
namespace {

Interval hull(double a, double b) { return {std::min(a, b), std::max(a, b)}; }
Interval hull(const Interval& a, const Interval& b) { return {std::min(a.lo, b.lo), std::max(a.hi, b.hi)}; }

double box_gap(const Aabb& a, const Aabb& b) {
  const glm::dvec3 gap = glm::max(glm::max(a.lo - b.hi, b.lo - a.hi), glm::dvec3(0.0));
  return glm::length(gap);
}

// g over a distance range [dmin, dmax]: g decreases with d for F > 0.
Interval falloff_range(double dmin, double dmax, double R, double F) {
  return hull(falloff(dmin, R, F), falloff(dmax, R, F));
}

Interval either_sign(double F) { return {std::min(0.0, F), std::max(0.0, F)}; }

Interval primitive_interval(const Graph& g, NodeId n, const Aabb& box) {
  const auto p = g.params_of(n);
  const double R = p[kPrimR], F = p[kPrimF];
  if (ht::intersect(box, g.support_alone[n]).empty()) return {};
  if (!box.finite()) return either_sign(F);
  const double half = 0.5 * glm::length(box.size());
  const double at_centre = skeleton_distance(g.kind[n], g.skeleton_of(n), box.center());
  // Distance to a set is 1-Lipschitz; the skeleton's box gives a second lower bound.
  const double dmin = std::max({0.0, at_centre - half, box_gap(box, skeleton_bounds(g.kind[n], g.skeleton_of(n)))});
  return falloff_range(dmin, at_centre + half, R, F);
}

Interval mesh_interval(const Graph& g, NodeId n, double T, const Aabb& box) {
  const MeshFieldParams mp = params::mesh_field(g, n, T);
  const double F = mp.F, kernel = mp.kernel_radius, r0 = mp.r0, reach = mp.query_radius;
  if (ht::intersect(box, g.support_alone[n]).empty()) return {};
  if (!box.finite()) return either_sign(F);
  const MeshLeaf& mesh = *g.meshes[g.mesh[n]];
  const double half = 0.5 * glm::length(box.size());
  const MeshLeaf::Closest c = mesh.query(box.center(), half + reach);
  // A closed leaf's box away from the surface is all on the centre's side. A winding leaf's
  // 1/2 level set may cross it far from any triangle (across a hole): its side is certified
  // over the whole box (WindingTree::box_side) or both sides are allowed.
  const int side = mesh.inside_mode() == MeshInside::Winding ? mesh.box_side(box) : (c.inside ? 1 : 0);
  if (!std::isfinite(c.distance)) return side == 1 ? Interval{F, F} : side == 0 ? Interval{} : hull(F, 0.0);
  if (c.distance <= half) return either_sign(F);  // the surface crosses the box
  // Pseudo-distance ranges follow dM +- half on each side the box may be on.
  const double dlo = c.distance - half, dhi = c.distance + half;
  auto field_at = [&](double pseudo) { return falloff(pseudo, kernel, F); };
  (void)T;
  const Interval in = hull(field_at(std::max(0.0, r0 - dhi)), field_at(std::max(0.0, r0 - dlo)));
  const Interval out = hull(field_at(dlo + r0), field_at(dhi + r0));
  return side == 1 ? in : side == 0 ? out : hull(in, out);
}

// The region of a warp's child: where the child is asked, w^-1(box).
bool child_region(const Graph& g, NodeId n, const Aabb& box, Aabb& out) {
  const auto p = g.params_of(n);
  switch (g.kind[n]) {
    case NodeKind::Affine: out = warp_bounds(NodeKind::Affine, p.data() + 12, box); return true;
    case NodeKind::Twist: {
      double q[kTwistParams];
      std::copy(p.begin(), p.end(), q);
      q[4] = -q[4];
      out = warp_bounds(NodeKind::Twist, q, box);
      return true;
    }
    case NodeKind::Taper: {
      double q[kTaperParams];
      std::copy(p.begin(), p.end(), q);
      q[6] = 1.0 / p[6];
      q[7] = 1.0 / p[7];
      out = warp_bounds(NodeKind::Taper, q, box);
      return true;
    }
    default: return false;  // bend: no bound of its inverse yet, so no pruning below it
  }
}

}  // namespace

namespace interval {

Interval leaf(const Graph& g, NodeId n, double T, const Aabb& box) {
  if (g.kind[n] == NodeKind::Mesh) return mesh_interval(g, n, T, box);
  if (g.kind[n] == NodeKind::Ffd) return g.mesh[n] != kNone ? mesh_interval(g, n, T, box) : either_sign(params::ffd(g, n).F);
  return primitive_interval(g, n, box);
}

bool warp_child_region(const Graph& g, NodeId n, const Aabb& box, Aabb& out) { return child_region(g, n, box, out); }

Interval crop(const Graph& g, NodeId n, double T, const Aabb& box, Interval v) {
  if (!box.finite()) return {std::max(0.0, std::min(v.lo, 0.0)), std::max(0.0, v.hi)};
  const double half = 0.5 * glm::length(box.size());
  const double h = crop_box_field(g.params_of(n).data(), T, box.center());
  const double slope = T / crop_reach(g.params_of(n).data());  // h is slope-Lipschitz
  return {std::max(0.0, std::min(v.lo, h - slope * half)), std::max(0.0, std::min(v.hi, h + slope * half))};
}

Interval add(Interval a, Interval b) { return {a.lo + b.lo, a.hi + b.hi}; }

// Union and intersection rise with both operands, difference rises with A, falls with B.
Interval unite(Interval a, Interval b, double T, bool rf) {
  return {union_field(a.lo, b.lo, T, rf), union_field(a.hi, b.hi, T, rf)};
}
Interval intersect(Interval a, Interval b, double T, bool rf) {
  return {intersection_field(a.lo, b.lo, T, rf), intersection_field(a.hi, b.hi, T, rf)};
}
Interval subtract(Interval a, Interval b, double T, bool rf) {
  return {difference_field(a.lo, b.hi, T, rf), difference_field(a.hi, b.lo, T, rf)};
}

Interval local_blend(Interval a, Interval b, Interval r, double T, bool rf) {
  const Interval sum = add(a, b), uni = unite(a, b, T, rf);
  const double wlo = std::clamp(r.lo, 0.0, 1.0), whi = std::clamp(r.hi, 0.0, 1.0);
  // f = U + w (S - U), linear in w: its range is the hull at both ends of w.
  const Interval diff{sum.lo - uni.hi, sum.hi - uni.lo};
  return {uni.lo + std::min(wlo * diff.lo, whi * diff.lo), uni.hi + std::max(wlo * diff.hi, whi * diff.hi)};
}

}  // namespace interval

Interval field_interval(const Graph& g, NodeId n, double T, const Aabb& box, bool under_blend) {
  const auto c = g.children_of(n);
  const bool rf = use_rfunction(g.boolean[n], under_blend);
  auto child = [&](std::size_t i, bool blended) { return field_interval(g, c[i], T, box, blended); };
  switch (kind_family(g.kind[n])) {
    case Family::Primitive:
    case Family::Mesh: return interval::leaf(g, n, T, box);
    case Family::Warp: {
      if (g.kind[n] == NodeKind::Ffd) return interval::leaf(g, n, T, box);
      Aabb local;
      if (!child_region(g, n, box, local)) local = Aabb::everything();
      return field_interval(g, c[0], T, local, under_blend);
    }
    case Family::Operator: break;
  }
  switch (g.kind[n]) {
    case NodeKind::Blend: {
      // A leaf whose support misses the box adds exactly 0 (as leaf() would find): skipped
      // without the call, which on a blend of hundreds of primitives is most of the work.
      Interval sum;
      for (std::size_t i = 0; i < c.size(); ++i) {
        const Family f = kind_family(g.kind[c[i]]);
        if ((f == Family::Primitive || f == Family::Mesh) && ht::intersect(box, g.support_alone[c[i]]).empty()) continue;
        sum = interval::add(sum, child(i, true));
      }
      return sum;
    }
    case NodeKind::Union:
    case NodeKind::Intersection:
    case NodeKind::Difference: {
      Interval acc = child(0, under_blend);
      for (std::size_t i = 1; i < c.size(); ++i) {
        const Interval b = child(i, under_blend);
        acc = g.kind[n] == NodeKind::Union          ? interval::unite(acc, b, T, rf)
              : g.kind[n] == NodeKind::Intersection ? interval::intersect(acc, b, T, rf)
                                                    : interval::subtract(acc, b, T, rf);
      }
      return acc;
    }
    case NodeKind::LocalBlend: return interval::local_blend(child(0, true), child(1, true), child(2, true), T, rf);
    default: return interval::crop(g, n, T, box, child(0, under_blend));
  }
}


}  // namespace ht

namespace ht {

namespace {
bool reaches_unprepared_ffd(const Graph& g, NodeId n) {
  if (params::ffd_unprepared(g, n)) return true;
  const auto c = g.children_of(n);
  return std::any_of(c.begin(), c.end(), [&](NodeId child) { return reaches_unprepared_ffd(g, child); });
}
}  // namespace

Aabb solid_bounds(const Graph& g, NodeId n, double T, bool under_blend) {
  const auto c = g.children_of(n);
  const Aabb& support = g.support(n, under_blend);
  auto child = [&](std::size_t i, bool blended) { return solid_bounds(g, c[i], T, blended); };
  // Where a child's support is bounded it bounds everything; otherwise its solid does.
  auto part = [&](std::size_t i, bool blended) {
    const Aabb& s = g.support(c[i], blended);
    return s.finite() || s.empty() ? s : child(i, blended);
  };
  switch (g.kind[n]) {
    case NodeKind::Blend:
    case NodeKind::LocalBlend: {
      // A part of unbounded support (an R-function difference, about 0.586 T everywhere) is
      // bounded by its solid only while it is the one such part: two sum past T far from both
      // solids (a review's blend of two such differences lost a sphere elsewhere in the tree).
      // An unprepared ffd's support is a placeholder (everything) though its field, the distance
      // to its deformed mesh, is compact: such a part is bounded by its solid, as before.
      const std::size_t count = g.kind[n] == NodeKind::Blend ? c.size() : 2;
      std::size_t unbounded = 0;
      for (std::size_t i = 0; i < count; ++i) {
        const Aabb& s = g.support(c[i], true);
        unbounded += !(s.finite() || s.empty()) && !reaches_unprepared_ffd(g, c[i]);
      }
      if (unbounded >= 2) return support;
      Aabb box;
      for (std::size_t i = 0; i < count; ++i) box = merge(box, part(i, true));
      return box;
    }
    case NodeKind::Union: {
      Aabb box;
      for (std::size_t i = 0; i < c.size(); ++i) box = merge(box, child(i, under_blend));
      return box;
    }
    case NodeKind::Intersection: {
      Aabb box = child(0, under_blend);
      for (std::size_t i = 1; i < c.size(); ++i) box = ht::intersect(box, child(i, under_blend));
      return box.empty() ? Aabb{} : box;
    }
    case NodeKind::Difference: return child(0, under_blend);  // f >= T needs f_A >= T
    case NodeKind::Crop: {
      const Aabb box = ht::intersect(child(0, under_blend), params::crop(g, n).box);
      return box.empty() ? Aabb{} : box;
    }
    case NodeKind::Affine:
    case NodeKind::Twist:
    case NodeKind::Taper:
    case NodeKind::Bend: return warp_bounds(g.kind[n], g.params_of(n).data(), child(0, under_blend));
    case NodeKind::Ffd: {
      if (g.mesh[n] != kNone || params::ffd_empty(g, n)) return support;
      // Inside the lattice, points move within the control points' box; outside, not at all.
      const auto p = g.params_of(n);
      Aabb box = child(0, under_blend);
      for (std::size_t i = kFfdHeader; i + 2 < p.size(); i += 3) box.grow({p[i], p[i + 1], p[i + 2]});
      return box;
    }
    default: return support;
  }
}

bool solid_empty(const Graph& g, NodeId n, double T) {
  if (solid_bounds(g, n, T).empty()) return true;
  const auto c = g.children_of(n);
  // Both Boolean modes: with a = fA - T < 0 and b = fB - T < 0 everywhere, the R-functions'
  // a + b +- sqrt(a^2 + b^2) is negative too (nodes/operators.hpp), as max and min are.
  switch (g.kind[n]) {
    case NodeKind::Union:
      return std::all_of(c.begin(), c.end(), [&](NodeId child) { return solid_empty(g, child, T); });
    case NodeKind::Intersection:
      return std::any_of(c.begin(), c.end(), [&](NodeId child) { return solid_empty(g, child, T); });
    case NodeKind::Difference:
    case NodeKind::Crop:
    case NodeKind::Affine:
    case NodeKind::Twist:
    case NodeKind::Taper:
    case NodeKind::Bend: return solid_empty(g, c[0], T);
    case NodeKind::Ffd: return g.mesh[n] == kNone && solid_empty(g, c[0], T);  // nothing to deform
    case NodeKind::Blend:
    case NodeKind::LocalBlend: return false;  // weak operands may sum past T
    default: {
      // A leaf's field is at most its strength F (on its skeleton, or inside its mesh).
      const double F = kind_family(g.kind[n]) == Family::Mesh ? params::mesh_field(g, n, T).F : params::primitive(g, n).F;
      return F < T;
    }
  }
}

}  // namespace ht
