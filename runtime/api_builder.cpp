// The embedding API's builder (runtime/api.hpp): each call forwards to ht::Builder
// (runtime/builder.hpp), whose BuildError becomes an InputError naming the key.
#include "runtime/api.hpp"

#include "runtime/api_impl.hpp"
#include "runtime/optimize.hpp"
#include "runtime/builder.hpp"

#include <glm/mat4x4.hpp>

#include <chrono>

namespace hybridtree {

struct Builder::Impl {
  explicit Impl(double threshold) : b(threshold) {}
  ht::Builder b;
};

namespace {

glm::dvec3 v(const Vec3& a) { return {a[0], a[1], a[2]}; }
ht::Falloff fall(const Falloff& f) { return {f.radius, f.strength}; }
ht::Axis ax(Axis a) { return static_cast<ht::Axis>(static_cast<int>(a)); }
ht::BooleanMode mode_of(BooleanMode m) {
  return m == BooleanMode::MinMax ? ht::BooleanMode::MinMax
         : m == BooleanMode::RFunction ? ht::BooleanMode::RFunction
                                       : ht::BooleanMode::Auto;
}
std::vector<glm::dvec3> xyz(std::span<const double> points) {
  if (points.size() % 3 != 0)
    throw InputError("points: expected an (n, 3) array, got " + std::to_string(points.size()) + " numbers", {},
                     "points");
  std::vector<glm::dvec3> p(points.size() / 3);
  for (std::size_t i = 0; i < p.size(); ++i) p[i] = {points[3 * i], points[3 * i + 1], points[3 * i + 2]};
  return p;
}

// Builder calls are argument checks and arena appends: their errors are InputErrors.
template <class F>
Node call(F&& f) {
  return guarded({}, std::forward<F>(f));
}

}  // namespace

Builder::Builder(double threshold) {
  guarded({}, [&] { impl_ = std::make_unique<Impl>(threshold); });
}
Builder::~Builder() = default;

Node Builder::point(Vec3 c, Falloff f) {
  return call([&] { return impl_->b.point(v(c), fall(f)); });
}
Node Builder::segment(Vec3 a, Vec3 b, Falloff f) {
  return call([&] { return impl_->b.segment(v(a), v(b), fall(f)); });
}
Node Builder::circle(Vec3 c, Vec3 n, double r, Falloff f) {
  return call([&] { return impl_->b.circle(v(c), v(n), r, fall(f)); });
}
Node Builder::disc(Vec3 c, Vec3 n, double r, Falloff f) {
  return call([&] { return impl_->b.disc(v(c), v(n), r, fall(f)); });
}
Node Builder::triangle(Vec3 a, Vec3 b, Vec3 c, Falloff f) {
  return call([&] { return impl_->b.triangle(v(a), v(b), v(c), fall(f)); });
}
Node Builder::curve(std::span<const double> points, Falloff f) {
  const std::vector<glm::dvec3> p = xyz(points);
  return call([&] { return impl_->b.curve(p, fall(f)); });
}
Node Builder::box(Vec3 lo, Vec3 hi, Falloff f) {
  return call([&] { return impl_->b.box(v(lo), v(hi), fall(f)); });
}
Node Builder::cylinder(Vec3 a, Vec3 b, double r, Falloff f) {
  return call([&] { return impl_->b.cylinder(v(a), v(b), r, fall(f)); });
}
Node Builder::cone_sphere(Vec3 a, Vec3 b, double ra, double rb, Falloff f) {
  return call([&] { return impl_->b.cone_sphere(v(a), v(b), ra, rb, fall(f)); });
}
Node Builder::mesh(const std::string& file, Falloff f, bool repair, bool winding) {
  return call([&] {
    return impl_->b.mesh(file, fall(f), repair, winding ? ht::MeshInside::Winding : ht::MeshInside::Closed);
  });
}

Node Builder::blend(std::span<const Node> c) {
  return call([&] { return impl_->b.blend(c); });
}
Node Builder::unite(std::span<const Node> c, BooleanMode m) {
  return call([&] { return impl_->b.unite(c, mode_of(m)); });
}
Node Builder::intersect(std::span<const Node> c, BooleanMode m) {
  return call([&] { return impl_->b.intersect(c, mode_of(m)); });
}
Node Builder::subtract(std::span<const Node> c, BooleanMode m) {
  return call([&] { return impl_->b.subtract(c, mode_of(m)); });
}
Node Builder::local_blend(Node a, Node b, Node region, BooleanMode m) {
  return call([&] { return impl_->b.local_blend(a, b, region, mode_of(m)); });
}
Node Builder::crop(Node child, Vec3 lo, Vec3 hi) {
  return call([&] { return impl_->b.crop(child, v(lo), v(hi)); });
}

Node Builder::affine(Node child, const std::array<double, 16>& forward) {
  glm::dmat4 m;  // glm is column-major: m[column][row]
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m[c][r] = forward[std::size_t(4 * r + c)];
  return call([&] { return impl_->b.affine(child, m); });
}
Node Builder::twist(Node child, Axis axis, Vec3 center, double rate) {
  return call([&] { return impl_->b.twist(child, ax(axis), v(center), rate); });
}
Node Builder::taper(Node child, Axis axis, Vec3 center, double h0, double h1, double s0, double s1) {
  return call([&] { return impl_->b.taper(child, ax(axis), v(center), h0, h1, s0, s1); });
}
Node Builder::bend(Node child, Axis axis, Vec3 center, double h0, double h1, double rate) {
  return call([&] { return impl_->b.bend(child, ax(axis), v(center), h0, h1, rate); });
}

Node Builder::ffd(Node child, Vec3 lo, Vec3 hi, std::array<int, 3> dims, std::span<const double> points, Falloff f) {
  const std::vector<glm::dvec3> p = xyz(points);
  return call([&] { return impl_->b.ffd(child, v(lo), v(hi), {dims[0], dims[1], dims[2]}, p, fall(f)); });
}

void Builder::set_name(Node node, const std::string& name) {
  call([&] {
    if (node >= impl_->b.size()) throw ht::BuildError("node", "is not a node of this builder");
    impl_->b.set_name(node, name);
    return node;
  });
}

void Builder::set_mesher(Node node, MesherHint hint) {
  call([&] {
    if (node >= impl_->b.size()) throw ht::BuildError("node", "is not a node of this builder");
    impl_->b.set_mesher(node, hint == MesherHint::Global ? ht::MesherHint::Global
                              : hint == MesherHint::Local ? ht::MesherHint::Local
                                                          : ht::MesherHint::Auto);
    return node;
  });
}

Tree Builder::build(Node root) {
  return guarded({}, [&] {
    const auto t0 = std::chrono::steady_clock::now();
    ht::Tree tree = ht::optimize(impl_->b.build(root));
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return Tree(std::make_shared<const Tree::Impl>(std::move(tree), "<builder>", s));
  });
}

}  // namespace hybridtree
