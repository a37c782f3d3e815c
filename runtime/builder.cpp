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
  // Scaled by its largest component first: the squares of 1e155 pass doubles (NaN vertices), and
  // those of 1e-170 vanish.
  const double big = std::max({std::abs(n.x), std::abs(n.y), std::abs(n.z)});
  if (!(big > 0.0)) throw BuildError(key, "must be a non-zero vector");
  const glm::dvec3 m = n / big;
  return m / glm::length(m);
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
  return writer_.add(kind, params, children, mode);
}

void Builder::check_children(std::span<const NodeId> children, std::size_t min_count) {
  if (children.size() < min_count)
    throw BuildError("children", "must hold at least " + std::to_string(min_count) + " node" +
                                     (min_count == 1 ? "" : "s"));
  for (std::size_t i = 0; i < children.size(); ++i)
    if (children[i] >= writer_.size())
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
  return add_primitive(NodeKind::Curve, s, f);  // the writer derives its polyline
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

void Builder::prefetch_meshes(std::span<const MeshFileRequest> files) {
  std::vector<MeshFileRequest> full(files.begin(), files.end());
  for (MeshFileRequest& r : full)
    if (!r.file.is_absolute() && !base_dir_.empty()) r.file = base_dir_ / r.file;
  cache_->prefetch(full);
}

NodeId Builder::mesh(std::shared_ptr<const MeshLeaf> leaf, Falloff f) {
  check_falloff(f);
  if (!(std::abs(f.strength) > threshold_))
    throw BuildError("strength", "|strength| must be > threshold (" + std::to_string(threshold_) + ")");
  const MeshFieldParams m = mesh_field_params(f.radius, f.strength, threshold_);
  const double p[] = {m.R, m.F, m.kernel_radius, m.r0, m.query_radius};
  return writer_.add_mesh(std::move(leaf), p);
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
    if (c[i] >= writer_.size())
      throw BuildError(i == 0 ? "a" : i == 1 ? "b" : "region", "is not a node of this builder");
  return add(NodeKind::LocalBlend, {}, c, mode);
}

NodeId Builder::crop(NodeId child, glm::dvec3 lo, glm::dvec3 hi) {
  if (child >= writer_.size()) throw BuildError("child", "is not a node of this builder");
  check_box(lo, hi);
  const double p[] = {lo.x, lo.y, lo.z, hi.x, hi.y, hi.z};
  const NodeId c[] = {child};
  return add(NodeKind::Crop, p, c);
}

NodeId Builder::affine(NodeId child, const glm::dmat4& m) {
  if (child >= writer_.size()) throw BuildError("child", "is not a node of this builder");
  double fwd[12];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) {
      fwd[4 * r + c] = m[c][r];  // glm is column-major
      require_finite("matrix", fwd[4 * r + c]);
    }
  if (m[0][3] != 0.0 || m[1][3] != 0.0 || m[2][3] != 0.0 || m[3][3] != 1.0)
    throw BuildError("matrix", "last row must be [0, 0, 0, 1]");
  double p[kAffineParams];
  if (!affine_from_matrix(fwd, p))
    throw BuildError("matrix", "is singular, or too near it to invert in double precision (condition past 1e12)");
  const NodeId c[] = {child};
  return add(NodeKind::Affine, p, c);
}

NodeId Builder::twist(NodeId child, Axis axis, glm::dvec3 center, double rate) {
  if (child >= writer_.size()) throw BuildError("child", "is not a node of this builder");
  require_finite("center", center);
  require_finite("rate", rate);
  const double p[] = {static_cast<double>(axis), center.x, center.y, center.z, rate};
  const NodeId c[] = {child};
  return add(NodeKind::Twist, p, c);
}

NodeId Builder::taper(NodeId child, Axis axis, glm::dvec3 center, double h0, double h1, double s0, double s1) {
  if (child >= writer_.size()) throw BuildError("child", "is not a node of this builder");
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
  if (child >= writer_.size()) throw BuildError("child", "is not a node of this builder");
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
  if (child >= writer_.size()) throw BuildError("child", "is not a node of this builder");
  check_box(lo, hi);
  if (dims.x < 1 || dims.y < 1 || dims.z < 1 || dims.x > kFfdMaxDim || dims.y > kFfdMaxDim || dims.z > kFfdMaxDim)
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
  writer_.set_name(node, std::move(name));
}

void Builder::set_mesher(NodeId node, MesherHint hint) { writer_.set_mesher(node, hint); }

Tree Builder::build(NodeId root) {
  if (root >= writer_.size()) throw BuildError("root", "is not a node of this builder");
  return Tree(std::make_shared<const Graph>(writer_.graph()), root, threshold_, settings_);
}

}  // namespace ht
