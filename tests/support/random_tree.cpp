#include "tests/support/random_tree.hpp"

#include "nodes/mesh_leaf.hpp"

#include <glm/gtc/matrix_transform.hpp>

namespace ht::test {
namespace {

double uniform(Rng& rng, double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }
int pick(Rng& rng, int n) { return std::uniform_int_distribution<int>(0, n - 1)(rng); }
glm::dvec3 vec(Rng& rng, double e) { return {uniform(rng, -e, e), uniform(rng, -e, e), uniform(rng, -e, e)}; }

Falloff falloff(Rng& rng) {
  // Mostly positive, sometimes carving.
  const double strength = pick(rng, 6) == 0 ? -uniform(rng, 0.3, 1.0) : uniform(rng, 0.7, 1.5);
  return {uniform(rng, 0.4, 1.2), strength};
}

NodeId primitive(Builder& b, Rng& rng, const RandomTreeOptions& o) {
  const int kinds = o.meshes.empty() ? 9 : 10;
  switch (pick(rng, kinds)) {
    case 0: return b.point(vec(rng, 1), falloff(rng));
    case 1: return b.segment(vec(rng, 1), vec(rng, 1), falloff(rng));
    case 2: return b.circle(vec(rng, 1), vec(rng, 1) + glm::dvec3(0, 0, 1.5), uniform(rng, 0.2, 0.8), falloff(rng));
    case 3: return b.disc(vec(rng, 1), vec(rng, 1) + glm::dvec3(0, 1.5, 0), uniform(rng, 0.2, 0.8), falloff(rng));
    case 4: return b.triangle(vec(rng, 1), vec(rng, 1), vec(rng, 1), falloff(rng));
    case 5: {
      std::vector<glm::dvec3> pts;
      const int n = 2 + pick(rng, 4);
      for (int i = 0; i < n; ++i) pts.push_back(vec(rng, 1));
      return b.curve(pts, falloff(rng));
    }
    case 6: {
      const glm::dvec3 lo = vec(rng, 1);
      return b.box(lo, lo + glm::dvec3(uniform(rng, 0.1, 1), uniform(rng, 0.1, 1), uniform(rng, 0.1, 1)), falloff(rng));
    }
    case 7: {
      const glm::dvec3 a = vec(rng, 1);
      return b.cylinder(a, a + vec(rng, 1) + glm::dvec3(0.3, 0, 0), uniform(rng, 0.1, 0.5), falloff(rng));
    }
    case 8: return b.cone_sphere(vec(rng, 1), vec(rng, 1), uniform(rng, 0.1, 0.6), uniform(rng, 0.1, 0.6), falloff(rng));
    default: {
      const auto& m = o.meshes[std::size_t(pick(rng, int(o.meshes.size())))];
      const double strength = pick(rng, 4) == 0 ? -uniform(rng, 0.8, 1.5) : uniform(rng, 0.8, 1.5);
      return b.mesh(m, {uniform(rng, 0.1, 0.5), strength});
    }
  }
}

BooleanMode mode(Rng& rng) { return static_cast<BooleanMode>(pick(rng, 3)); }
Axis axis(Rng& rng) { return static_cast<Axis>(pick(rng, 3)); }

}  // namespace

glm::dvec3 random_point(Rng& rng, double e) { return vec(rng, e); }

const std::vector<std::shared_ptr<const MeshLeaf>>& small_meshes() {
  static const auto meshes = [] {
    std::vector<std::shared_ptr<const MeshLeaf>> m;
    m.push_back(MeshLeaf::load(cgal_mesh("eight.off")));
    m.push_back(MeshLeaf::load(cgal_mesh("sphere.off")));
    return m;
  }();
  return meshes;
}

NodeId random_tree(Builder& b, Rng& rng, const RandomTreeOptions& o, int depth) {
  if (depth >= o.max_depth || pick(rng, 4) == 0) return primitive(b, rng, o);
  auto kids = [&](int min) {
    std::vector<NodeId> c;
    const int n = min + pick(rng, std::max(1, o.max_children - min + 1));
    for (int i = 0; i < n; ++i) c.push_back(random_tree(b, rng, o, depth + 1));
    return c;
  };
  auto one = [&] { return random_tree(b, rng, o, depth + 1); };
  switch (pick(rng, 10)) {
    case 0: return b.blend(kids(1));
    case 1: return b.unite(kids(1), mode(rng));
    case 2: return b.intersect(kids(1), mode(rng));
    case 3: return b.subtract(kids(1), mode(rng));
    case 4: {
      const NodeId a = one(), c = one(), r = one();
      return b.local_blend(a, c, r, mode(rng));
    }
    case 5: {
      const glm::dvec3 lo = vec(rng, 1);
      return b.crop(one(), lo, lo + glm::dvec3(uniform(rng, 0.3, 2), uniform(rng, 0.3, 2), uniform(rng, 0.3, 2)));
    }
    case 6: {
      glm::dmat4 m = glm::translate(glm::dmat4(1.0), vec(rng, 0.5));
      m = glm::rotate(m, uniform(rng, -3, 3), glm::normalize(vec(rng, 1) + glm::dvec3(0, 0, 2)));
      m = glm::scale(m, glm::dvec3(uniform(rng, 0.5, 1.5), uniform(rng, 0.5, 1.5), uniform(rng, 0.5, 1.5)));
      return b.affine(one(), m);
    }
    case 7: return b.twist(one(), axis(rng), vec(rng, 0.5), uniform(rng, -1.5, 1.5));
    case 8: {
      const double h0 = uniform(rng, -1, 0);
      return b.taper(one(), axis(rng), vec(rng, 0.5), h0, h0 + uniform(rng, 0.2, 2), uniform(rng, 0.4, 1.6),
                     uniform(rng, 0.4, 1.6));
    }
    default: {
      const double h0 = uniform(rng, -1, 0);
      return b.bend(one(), axis(rng), vec(rng, 0.5), h0, h0 + uniform(rng, 0.2, 2), uniform(rng, -0.4, 0.4));
    }
  }
}

}  // namespace ht::test
