#include "tools/scenes.hpp"

#include "nodes/mesh_leaf.hpp"

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

namespace ht::scenes {
namespace {

struct CurveSpec {
  std::vector<glm::dvec3> points;
  double radius;
};

// The body: pieces of a sinuous spine, each a 4-point curve overlapping its neighbours so the
// blend is smooth; radius tapers toward the tail. The rest of the primitives are fins: short
// curves standing on the back.
std::vector<CurveSpec> snake_specs(int count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(-1.0, 1.0);
  const int body = std::max(1, (count * 4) / 5);
  const int fins = count - body;
  const double length = 12.0;
  auto spine = [&](double s) {
    const double t = s / length;
    return glm::dvec3(s, 1.2 * std::sin(2.0 * std::numbers::pi * 1.5 * t) * (0.3 + t),
                      0.5 * std::sin(2.0 * std::numbers::pi * 0.75 * t) + 0.8 * (1.0 - t) * (1.0 - t));
  };
  auto thickness = [&](double s) { return 0.22 + 0.38 * (1.0 - s / length) + 0.1 * std::exp(-s * s); };
  std::vector<CurveSpec> out;
  const double step = length / body;
  for (int i = 0; i < body; ++i) {
    const double s0 = i * step;
    CurveSpec c;
    for (int k = 0; k < 4; ++k) c.points.push_back(spine(s0 + (k - 0.5) * step * 0.9));
    c.radius = thickness(s0) * (1.0 + 0.05 * jitter(rng)) + 0.35;
    out.push_back(c);
  }
  for (int i = 0; i < fins; ++i) {
    const double s = length * (0.1 + 0.8 * (i + 0.5) / fins);
    const glm::dvec3 base = spine(s);
    const double h = 0.35 + 0.15 * jitter(rng);
    CurveSpec c;
    c.points = {base, base + glm::dvec3(0.1, 0.0, 0.6 * h), base + glm::dvec3(0.25, 0.05 * jitter(rng), h)};
    c.radius = 0.3;
    out.push_back(c);
  }
  return out;
}

}  // namespace

NodeId snake(Builder& b, int count, std::uint64_t seed) {
  std::vector<NodeId> parts;
  for (const CurveSpec& c : snake_specs(count, seed)) parts.push_back(b.curve(c.points, {c.radius, 1.0}));
  return b.blend(parts);
}

std::string snake_json(int count, std::uint64_t seed) {
  std::string out = "{\n  \"hybridtree\": 1,\n  \"threshold\": 0.5,\n  \"root\": {\"type\": \"blend\", \"name\": \"snake\", \"children\": [\n";
  const auto specs = snake_specs(count, seed);
  char buf[256];
  for (std::size_t i = 0; i < specs.size(); ++i) {
    out += "    {\"type\": \"curve\", \"radius\": ";
    std::snprintf(buf, sizeof buf, "%.17g", specs[i].radius);
    out += buf;
    out += ", \"points\": [";
    for (std::size_t k = 0; k < specs[i].points.size(); ++k) {
      const auto& p = specs[i].points[k];
      std::snprintf(buf, sizeof buf, "%s[%.17g, %.17g, %.17g]", k ? ", " : "", p.x, p.y, p.z);
      out += buf;
    }
    out += i + 1 < specs.size() ? "]},\n" : "]}\n";
  }
  out += "  ]}\n}\n";
  return out;
}

NodeId every_kind(Builder& b, std::shared_ptr<const MeshLeaf> mesh) {
  const Falloff f{0.4, 1.0};
  const NodeId prims[] = {
      b.point({0, 0, 0}, f),
      b.segment({-0.5, 0.3, 0}, {0.5, 0.3, 0.1}, f),
      b.circle({0.3, -0.3, 0.2}, {0, 0.3, 1}, 0.4, {0.25, 1.0}),
      b.disc({-0.4, -0.4, -0.2}, {1, 0, 0.2}, 0.3, {0.25, 1.0}),
      b.triangle({0, 0.5, 0.5}, {0.5, 0.8, 0.4}, {0.2, 0.4, 0.9}, {0.3, 1.0}),
      b.box({0.6, 0.6, -0.3}, {0.9, 0.9, 0.1}, {0.3, 1.0}),
      b.cylinder({-0.8, 0.2, -0.5}, {-0.6, 0.5, 0.2}, 0.1, {0.3, 1.0}),
      b.cone_sphere({0.2, -0.8, 0}, {0.7, -0.6, 0.3}, 0.15, 0.05, {0.3, 1.0}),
  };
  const std::vector<glm::dvec3> spline = {{-0.9, -0.9, 0.5}, {-0.5, -0.6, 0.7}, {0, -0.8, 0.9}, {0.5, -0.5, 0.6}};
  const NodeId curve = b.curve(spline, {0.3, 1.0});
  const NodeId leaf = b.mesh(std::move(mesh), {0.1, 1.0});
  const NodeId body = b.blend({prims[0], prims[1], curve});
  const NodeId u = b.unite({prims[2], prims[3]}, BooleanMode::MinMax);
  const NodeId i = b.intersect({prims[4], b.point({0.25, 0.6, 0.6}, {0.5, 1.0})}, BooleanMode::RFunction);
  const NodeId d = b.subtract({prims[5], b.point({0.9, 0.9, 0.1}, {0.3, 1.5})});
  const NodeId lb = b.local_blend(prims[6], prims[7], b.box({-0.2, -0.5, -0.5}, {0.2, 0.5, 0.5}, {0.3, 1.0}));
  const NodeId crop = b.crop(leaf, {-1, -1, -0.2}, {1, 1, 1});
  const NodeId warped = b.affine(b.twist(b.taper(b.bend(body, Axis::X, {0, 0, 0}, -0.5, 0.5, 0.4), Axis::Z, {0, 0, 0}, -0.5,
                                                 0.5, 1.0, 0.6),
                                         Axis::Y, {0, 0, 0}, 0.8),
                                 glm::dmat4(1.0));
  return b.blend({warped, u, i, d, lb, crop});
}

NodeId mesh_with_primitives(Builder& b, std::shared_ptr<const MeshLeaf> mesh) {
  const Aabb box = mesh->bounds();
  const double size = glm::length(box.size());
  const glm::dvec3 c = box.center(), h = 0.5 * box.size();
  const NodeId leaf = b.mesh(std::move(mesh), {0.03 * size, 1.0});
  const NodeId perch = b.segment(c + glm::dvec3(-h.x, -h.y, -h.z), c + glm::dvec3(h.x, -h.y, -h.z), {0.15 * size, 1.0});
  const NodeId nest = b.point(c + glm::dvec3(0, 0.2 * h.y, 0.6 * h.z), {0.12 * size, -1.5});
  const NodeId ring = b.circle(c + glm::dvec3(0, 0, 1.1 * h.z), {0, 0, 1}, 0.5 * h.x, {0.06 * size, 1.0});
  return b.blend({leaf, perch, nest, ring});
}

NodeId scatter(Builder& b, int count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double side = 1.6 * std::cbrt(static_cast<double>(count));
  auto where = [&] { return glm::dvec3(unit(rng), unit(rng), unit(rng)) * side; };
  auto offset = [&](double r) { return glm::dvec3(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5) * (2.0 * r); };
  NodeId chain = kNone;
  for (int i = 0; i < count; ++i) {
    const glm::dvec3 c = where();
    const Falloff f{0.5 + 0.4 * unit(rng), 1.0};
    NodeId p;
    switch (i % 8) {
      case 0: p = b.point(c, f); break;
      case 1: p = b.segment(c, c + offset(0.6), f); break;
      case 2: p = b.circle(c, offset(1.0) + glm::dvec3(0, 0, 0.1), 0.3, {0.3, 1.0}); break;
      case 3: p = b.disc(c, offset(1.0) + glm::dvec3(0.1, 0, 0), 0.3, {0.3, 1.0}); break;
      case 4: p = b.triangle(c, c + offset(0.5), c + offset(0.5), {0.35, 1.0}); break;
      case 5: p = b.box(c, c + glm::dvec3(0.3, 0.4, 0.2), {0.3, 1.0}); break;
      case 6: p = b.cylinder(c, c + offset(0.5) + glm::dvec3(0, 0.05, 0), 0.15, {0.3, 1.0}); break;
      default: {
        const std::vector<glm::dvec3> pts = {c, c + offset(0.4), c + offset(0.8)};
        p = b.curve(pts, {0.35, 1.0});
      }
    }
    if (i % 10 == 9) {  // built at the origin, put in place by a similarity
      const glm::dmat4 turn = glm::rotate(glm::dmat4(1.0), 2.0 * std::numbers::pi * unit(rng), glm::normalize(offset(1.0) + glm::dvec3(0, 0, 0.01)));
      p = b.affine(b.affine(p, glm::translate(glm::dmat4(1.0), -c)), glm::translate(glm::dmat4(1.0), c) * turn * glm::scale(glm::dmat4(1.0), glm::dvec3(0.9)));
    }
    chain = chain == kNone ? p : b.blend({chain, p});
  }
  return chain;
}

NodeId point_grid(Builder& b, int count) {
  const int side = static_cast<int>(std::ceil(std::cbrt(static_cast<double>(count))));
  std::vector<NodeId> parts;
  for (int i = 0; i < count; ++i)
    parts.push_back(b.point({i % side, (i / side) % side, i / (side * side)}, {0.6, 1.0}));
  return b.blend(parts);
}

}  // namespace ht::scenes
