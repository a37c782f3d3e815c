#include "runtime/builder.hpp"

#include "nodes/mesh_leaf.hpp"
#include "nodes/operators.hpp"
#include "nodes/primitives.hpp"
#include "nodes/warps.hpp"

#include <glm/geometric.hpp>

#include <cmath>
#include <vector>

namespace ht {
namespace {

void require_finite(const std::string& key, double v) {
  if (!std::isfinite(v)) throw BuildError(key, "must be a finite number");
}
void require_finite(const std::string& key, const glm::dvec3& v) {
  if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z))
    throw BuildError(key, "must hold finite numbers");
}
void require_positive(const std::string& key, double v) {
  require_finite(key, v);
  if (!(v > 0.0)) throw BuildError(key, "must be > 0");
}
void push3(std::vector<double>& out, const glm::dvec3& v) {
  out.push_back(v.x);
  out.push_back(v.y);
  out.push_back(v.z);
}
glm::dvec3 unit_normal(const std::string& key, const glm::dvec3& n) {
  require_finite(key, n);
  const double len = glm::length(n);
  if (!(len > 0.0)) throw BuildError(key, "must be a non-zero vector");
  return n / len;
}
void check_falloff(const Falloff& f) {
  require_positive("radius", f.radius);
  require_finite("strength", f.strength);
  if (f.strength == 0.0) throw BuildError("strength", "must be non-zero");
}
void check_box(const glm::dvec3& lo, const glm::dvec3& hi) {
  require_finite("min", lo);
  require_finite("max", hi);
  if (!(lo.x < hi.x && lo.y < hi.y && lo.z < hi.z))
    throw BuildError("max", "must be greater than min on every axis");
}

}  // namespace

Builder::Builder(double threshold) : threshold_(threshold), cache_(std::make_unique<MeshCache>()) {
  require_positive("threshold", threshold);
}
Builder::~Builder() = default;

NodeId Builder::add(NodeKind kind, std::span<const double> params, std::span<const NodeId> children,
                    BooleanMode mode) {
  Graph& g = graph_;
  const auto id = static_cast<NodeId>(g.size());
  g.kind.push_back(kind);
  g.boolean.push_back(mode);
  g.mesher.push_back(MesherHint::Auto);
  g.param_begin.push_back(static_cast<std::uint32_t>(g.params.size()));
  g.param_count.push_back(static_cast<std::uint32_t>(params.size()));
  g.params.insert(g.params.end(), params.begin(), params.end());
  g.child_begin.push_back(static_cast<std::uint32_t>(g.children.size()));
  g.child_count.push_back(static_cast<std::uint32_t>(children.size()));
  g.children.insert(g.children.end(), children.begin(), children.end());
  g.derived_begin.push_back(0);
  g.derived_count.push_back(0);
  g.mesh.push_back(kNone);
  g.name.push_back(kNone);
  g.support_alone.emplace_back();
  g.support_blended.emplace_back();
  g.nonnegative.push_back(0);
  return id;
}

void Builder::check_children(std::span<const NodeId> children, std::size_t min_count) {
  if (children.size() < min_count)
    throw BuildError("children", "must hold at least " + std::to_string(min_count) + " node" +
                                     (min_count == 1 ? "" : "s"));
  for (std::size_t i = 0; i < children.size(); ++i)
    if (children[i] >= graph_.size())
      throw BuildError("children[" + std::to_string(i) + "]", "is not a node of this builder");
}

NodeId Builder::add_primitive(NodeKind kind, std::span<const double> skeleton, Falloff f) {
  check_falloff(f);
  std::vector<double> p{f.radius, f.strength};
  p.insert(p.end(), skeleton.begin(), skeleton.end());
  return add(kind, p, {});
}

NodeId Builder::point(glm::dvec3 c, Falloff f) {
  require_finite("center", c);
  const double s[] = {c.x, c.y, c.z};
  return add_primitive(NodeKind::Point, s, f);
}

NodeId Builder::segment(glm::dvec3 a, glm::dvec3 b, Falloff f) {
  require_finite("a", a);
  require_finite("b", b);
  const double s[] = {a.x, a.y, a.z, b.x, b.y, b.z};
  return add_primitive(NodeKind::Segment, s, f);
}

NodeId Builder::circle(glm::dvec3 c, glm::dvec3 n, double r, Falloff f) {
  require_finite("center", c);
  const glm::dvec3 u = unit_normal("normal", n);
  require_positive("circle_radius", r);
  const double s[] = {c.x, c.y, c.z, u.x, u.y, u.z, r};
  return add_primitive(NodeKind::Circle, s, f);
}

NodeId Builder::disc(glm::dvec3 c, glm::dvec3 n, double r, Falloff f) {
  require_finite("center", c);
  const glm::dvec3 u = unit_normal("normal", n);
  require_positive("disc_radius", r);
  const double s[] = {c.x, c.y, c.z, u.x, u.y, u.z, r};
  return add_primitive(NodeKind::Disc, s, f);
}

NodeId Builder::triangle(glm::dvec3 a, glm::dvec3 b, glm::dvec3 c, Falloff f) {
  require_finite("a", a);
  require_finite("b", b);
  require_finite("c", c);
  const double s[] = {a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z};
  return add_primitive(NodeKind::Triangle, s, f);
}

NodeId Builder::curve(std::span<const glm::dvec3> points, Falloff f) {
  if (points.size() < 2) throw BuildError("points", "must hold at least 2 points");
  for (std::size_t i = 0; i < points.size(); ++i) require_finite("points[" + std::to_string(i) + "]", points[i]);
  check_falloff(f);
  std::vector<double> s{static_cast<double>(points.size())};
  for (const auto& q : points) push3(s, q);
  const NodeId id = add_primitive(NodeKind::Curve, s, f);
  const std::vector<glm::dvec3> poly = curve_polyline(points, kCurveTolerance * f.radius);
  graph_.derived_begin[id] = static_cast<std::uint32_t>(graph_.derived.size());
  graph_.derived_count[id] = static_cast<std::uint32_t>(1 + 3 * poly.size());
  graph_.derived.push_back(static_cast<double>(poly.size()));
  for (const auto& q : poly) push3(graph_.derived, q);
  return id;
}

NodeId Builder::box(glm::dvec3 lo, glm::dvec3 hi, Falloff f) {
  check_box(lo, hi);
  const double s[] = {lo.x, lo.y, lo.z, hi.x, hi.y, hi.z};
  return add_primitive(NodeKind::Box, s, f);
}

NodeId Builder::cylinder(glm::dvec3 a, glm::dvec3 b, double r, Falloff f) {
  require_finite("a", a);
  require_finite("b", b);
  if (!(glm::length(b - a) > 0.0)) throw BuildError("b", "must differ from a");
  require_positive("cylinder_radius", r);
  const double s[] = {a.x, a.y, a.z, b.x, b.y, b.z, r};
  return add_primitive(NodeKind::Cylinder, s, f);
}

NodeId Builder::cone_sphere(glm::dvec3 a, glm::dvec3 b, double ra, double rb, Falloff f) {
  require_finite("a", a);
  require_finite("b", b);
  require_positive("radius_a", ra);
  require_positive("radius_b", rb);
  const double s[] = {a.x, a.y, a.z, b.x, b.y, b.z, ra, rb};
  return add_primitive(NodeKind::ConeSphere, s, f);
}

NodeId Builder::mesh(const std::filesystem::path& file, Falloff f, bool repair, MeshInside inside) {
  check_falloff(f);
  if (!(std::abs(f.strength) > threshold_))
    throw BuildError("strength", "|strength| must be > threshold (" + std::to_string(threshold_) + ")");
  const std::filesystem::path full = file.is_absolute() || base_dir_.empty() ? file : base_dir_ / file;
  std::shared_ptr<const MeshLeaf> leaf;
  try {
    leaf = cache_->get(full, repair, inside);
  } catch (const MeshError& e) {
    throw BuildError("file", e.what());
  }
  return mesh(std::move(leaf), f);
}

NodeId Builder::mesh(std::shared_ptr<const MeshLeaf> leaf, Falloff f) {
  check_falloff(f);
  if (!(std::abs(f.strength) > threshold_))
    throw BuildError("strength", "|strength| must be > threshold (" + std::to_string(threshold_) + ")");
  const MeshFieldParams m = mesh_field_params(f.radius, f.strength, threshold_);
  const double p[] = {m.R, m.F, m.kernel_radius, m.r0, m.query_radius};
  const NodeId id = add(NodeKind::Mesh, p, {});
  std::uint32_t index = kNone;
  for (std::size_t i = 0; i < graph_.meshes.size(); ++i)
    if (graph_.meshes[i] == leaf) index = static_cast<std::uint32_t>(i);
  if (index == kNone) {
    index = static_cast<std::uint32_t>(graph_.meshes.size());
    graph_.meshes.push_back(std::move(leaf));
  }
  graph_.mesh[id] = index;
  return id;
}

NodeId Builder::blend(std::span<const NodeId> c) {
  check_children(c, 1);
  return add(NodeKind::Blend, {}, c);
}
NodeId Builder::unite(std::span<const NodeId> c, BooleanMode mode) {
  check_children(c, 1);
  return add(NodeKind::Union, {}, c, mode);
}
NodeId Builder::intersect(std::span<const NodeId> c, BooleanMode mode) {
  check_children(c, 1);
  return add(NodeKind::Intersection, {}, c, mode);
}
NodeId Builder::subtract(std::span<const NodeId> c, BooleanMode mode) {
  check_children(c, 1);
  return add(NodeKind::Difference, {}, c, mode);
}

NodeId Builder::local_blend(NodeId a, NodeId b, NodeId region, BooleanMode mode) {
  const NodeId c[] = {a, b, region};
  for (int i = 0; i < 3; ++i)
    if (c[i] >= graph_.size())
      throw BuildError(i == 0 ? "a" : i == 1 ? "b" : "region", "is not a node of this builder");
  return add(NodeKind::LocalBlend, {}, c, mode);
}

NodeId Builder::crop(NodeId child, glm::dvec3 lo, glm::dvec3 hi) {
  if (child >= graph_.size()) throw BuildError("child", "is not a node of this builder");
  check_box(lo, hi);
  const double p[] = {lo.x, lo.y, lo.z, hi.x, hi.y, hi.z};
  const NodeId c[] = {child};
  return add(NodeKind::Crop, p, c);
}

NodeId Builder::affine(NodeId child, const glm::dmat4& m) {
  if (child >= graph_.size()) throw BuildError("child", "is not a node of this builder");
  double fwd[12];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) {
      fwd[4 * r + c] = m[c][r];  // glm is column-major
      require_finite("matrix", fwd[4 * r + c]);
    }
  if (m[0][3] != 0.0 || m[1][3] != 0.0 || m[2][3] != 0.0 || m[3][3] != 1.0)
    throw BuildError("matrix", "last row must be [0, 0, 0, 1]");
  double p[kAffineParams];
  if (!affine_from_matrix(fwd, p)) throw BuildError("matrix", "is singular (not invertible)");
  const NodeId c[] = {child};
  return add(NodeKind::Affine, p, c);
}

NodeId Builder::twist(NodeId child, Axis axis, glm::dvec3 center, double rate) {
  if (child >= graph_.size()) throw BuildError("child", "is not a node of this builder");
  require_finite("center", center);
  require_finite("rate", rate);
  const double p[] = {static_cast<double>(axis), center.x, center.y, center.z, rate};
  const NodeId c[] = {child};
  return add(NodeKind::Twist, p, c);
}

NodeId Builder::taper(NodeId child, Axis axis, glm::dvec3 center, double h0, double h1, double s0, double s1) {
  if (child >= graph_.size()) throw BuildError("child", "is not a node of this builder");
  require_finite("center", center);
  require_finite("range", h0);
  require_finite("range", h1);
  if (!(h0 < h1)) throw BuildError("range", "must be [h0, h1] with h0 < h1");
  require_positive("scale", s0);
  require_positive("scale", s1);
  const double p[] = {static_cast<double>(axis), center.x, center.y, center.z, h0, h1, s0, s1};
  const NodeId c[] = {child};
  return add(NodeKind::Taper, p, c);
}

NodeId Builder::bend(NodeId child, Axis axis, glm::dvec3 center, double h0, double h1, double rate) {
  if (child >= graph_.size()) throw BuildError("child", "is not a node of this builder");
  require_finite("center", center);
  require_finite("range", h0);
  require_finite("range", h1);
  if (!(h0 <= h1)) throw BuildError("range", "must be [h0, h1] with h0 <= h1");
  require_finite("rate", rate);
  const double p[] = {static_cast<double>(axis), center.x, center.y, center.z, h0, h1, rate};
  const NodeId c[] = {child};
  return add(NodeKind::Bend, p, c);
}

NodeId Builder::ffd(NodeId child, glm::dvec3 lo, glm::dvec3 hi, glm::ivec3 dims,
                    std::span<const glm::dvec3> points, Falloff f) {
  if (child >= graph_.size()) throw BuildError("child", "is not a node of this builder");
  check_box(lo, hi);
  if (dims.x < 1 || dims.y < 1 || dims.z < 1 || dims.x > 64 || dims.y > 64 || dims.z > 64)
    throw BuildError("dims", "must be three whole numbers from 1 to 64");
  const std::size_t expected = std::size_t(dims.x + 1) * std::size_t(dims.y + 1) * std::size_t(dims.z + 1);
  if (points.size() != expected)
    throw BuildError("points", "must hold (l+1)(m+1)(n+1) = " + std::to_string(expected) +
                                   " control points, not " + std::to_string(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i) require_finite("points[" + std::to_string(i) + "]", points[i]);
  check_falloff(f);
  if (!(std::abs(f.strength) > threshold_))
    throw BuildError("strength", "|strength| must be > threshold (" + std::to_string(threshold_) + ")");
  std::vector<double> p{lo.x, lo.y, lo.z, hi.x, hi.y, hi.z, double(dims.x), double(dims.y), double(dims.z),
                        f.radius, f.strength};
  for (const auto& q : points) push3(p, q);
  const NodeId c[] = {child};
  return add(NodeKind::Ffd, p, c);
}

void Builder::set_name(NodeId node, std::string name) {
  graph_.name.at(node) = static_cast<std::uint32_t>(graph_.names.size());
  graph_.names.push_back(std::move(name));
}

void Builder::set_mesher(NodeId node, MesherHint hint) { graph_.mesher.at(node) = hint; }

// Supports and signs, bottom-up (children have smaller ids). The rules follow from the
// formulas in nodes/operators.hpp: where every child is 0, a blend, a union of either kind and
// an R-function intersection are 0; a min/max intersection of non-negative fields is 0 where
// either is; a min/max difference is 0 where A is; an R-function difference is not 0 anywhere
// (it tends to 2T/(2+sqrt 2) far from both), so its support is everything.
void compute_supports(Graph& g) {
  for (NodeId n = 0; n < g.size(); ++n) {
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
        case Family::Primitive:
          box = skeleton_bounds(k, g.skeleton_of(n)).expanded(p[kPrimR]);
          nonneg = p[kPrimF] > 0.0;
          break;
        case Family::Mesh:
          box = g.meshes[g.mesh[n]]->bounds().expanded(p[0]);
          nonneg = p[1] > 0.0;
          break;
        case Family::Warp:
          if (k == NodeKind::Ffd) {  // its field lives on its deformed mesh, once meshed
            box = g.mesh[n] != kNone ? g.meshes[g.mesh[n]]->bounds().expanded(p[9]) : Aabb::everything();
            nonneg = p[10] > 0.0;
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
            box = ht::intersect(sup(c[0], below), Aabb{{p[0], p[1], p[2]}, {p[3], p[4], p[5]}}.expanded(crop_reach(p.data())));
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

Tree Builder::build(NodeId root) {
  if (root >= graph_.size()) throw BuildError("root", "is not a node of this builder");
  compute_supports(graph_);
  return Tree(std::make_shared<const Graph>(graph_), root, threshold_, settings_);
}

}  // namespace ht
