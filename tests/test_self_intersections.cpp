// Self-intersections: closed surfaces have none, overlapping ones do and the examples name one
// triangle of each, folds count, the rules for triangles sharing a vertex or an edge hold, exact
// touching on a tilted lattice is found where double arithmetic alone would guess, the answer
// does not depend on corner order, flat regular grids (exactly coplanar neighbours) have none
// until a vertex is pushed through a neighbour, and the Embree candidates lose nothing against
// a brute-force run of the same exact test over all pairs.
#include "meshers/mesh_checks.hpp"
#include "meshers/self_intersections.hpp"
#include "tests/support/test_support.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

namespace ht {
namespace {

using glm::dvec3;
using test::Rng;

using test::seeded;
using test::icosphere;

// ---- Meshes ------------------------------------------------------------------------------------

/// Poles at centre +- (0, 0, radius) exactly.
TriangleMesh uv_sphere(unsigned rings, unsigned segments, double radius = 1.0, dvec3 centre = dvec3(0.0)) {
  TriangleMesh m;
  m.positions.push_back(centre + dvec3(0, 0, radius));
  for (unsigned r = 1; r < rings; ++r)
    for (unsigned s = 0; s < segments; ++s) {
      const double th = std::numbers::pi * r / rings, ph = 2 * std::numbers::pi * s / segments;
      const dvec3 dir(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
      m.positions.push_back(centre + radius * dir);
    }
  m.positions.push_back(centre + dvec3(0, 0, -radius));
  const unsigned south = static_cast<unsigned>(m.positions.size() - 1);
  auto at = [&](unsigned r, unsigned s) { return 1 + (r - 1) * segments + s % segments; };
  for (unsigned s = 0; s < segments; ++s) {
    m.triangles.push_back({0, at(1, s), at(1, s + 1)});
    m.triangles.push_back({south, at(rings - 1, s + 1), at(rings - 1, s)});
    for (unsigned r = 1; r + 1 < rings; ++r) {
      m.triangles.push_back({at(r, s), at(r + 1, s), at(r + 1, s + 1)});
      m.triangles.push_back({at(r, s), at(r + 1, s + 1), at(r, s + 1)});
    }
  }
  return m;
}

/// b's triangles after a's, on their own vertices: one soup.
TriangleMesh soup(const TriangleMesh& a, const TriangleMesh& b) {
  TriangleMesh m = a;
  append(m, b);
  return m;
}

/// An n x n grid of unit-spaced quads scaled by `step`, two triangles each (the diagonal
/// alternating like a checkerboard), in the plane z = 0, counter-clockwise seen from +z.
TriangleMesh flat_grid(unsigned n, double step) {
  TriangleMesh m;
  for (unsigned j = 0; j <= n; ++j)
    for (unsigned i = 0; i <= n; ++i) m.positions.push_back({i * step, j * step, 0});
  auto at = [&](unsigned i, unsigned j) { return j * (n + 1) + i; };
  for (unsigned j = 0; j < n; ++j)
    for (unsigned i = 0; i < n; ++i) {
      const unsigned a = at(i, j), b = at(i + 1, j), c = at(i + 1, j + 1), d = at(i, j + 1);
      if ((i + j) % 2 == 0)
        m.triangles.insert(m.triangles.end(), {{a, b, c}, {a, c, d}});
      else
        m.triangles.insert(m.triangles.end(), {{a, b, d}, {b, c, d}});
    }
  return m;
}

/// The closed cube [0, 1]^3 with an n x n grid on each face, welded along the cube's edges,
/// faces outward.
TriangleMesh grid_cube(unsigned n) {
  TriangleMesh m;
  std::map<std::array<double, 3>, unsigned> index;
  auto vertex = [&](dvec3 p) {
    auto [it, fresh] = index.try_emplace({p.x, p.y, p.z}, static_cast<unsigned>(m.positions.size()));
    if (fresh) m.positions.push_back(p);
    return it->second;
  };
  const TriangleMesh face = flat_grid(n, 1.0 / n);
  for (int axis = 0; axis < 3; ++axis)
    for (double level : {0.0, 1.0}) {
      // The grid's x and y become the two axes after `axis`, cyclically, so its +z normal
      // becomes +axis; the face at 0 is flipped to point outward.
      std::vector<unsigned> map;
      for (const dvec3& q : face.positions) {
        dvec3 p;
        p[axis] = level, p[(axis + 1) % 3] = q.x, p[(axis + 2) % 3] = q.y;
        map.push_back(vertex(p));
      }
      for (const auto& t : face.triangles)
        m.triangles.push_back(level == 0 ? glm::uvec3(map[t[0]], map[t[2]], map[t[1]])
                                          : glm::uvec3(map[t[0]], map[t[1]], map[t[2]]));
    }
  return m;
}

/// Two triangles on their own six vertices.
TriangleMesh pair_mesh(dvec3 a0, dvec3 a1, dvec3 a2, dvec3 b0, dvec3 b1, dvec3 b2) {
  return {{a0, a1, a2, b0, b1, b2}, {{0, 1, 2}, {3, 4, 5}}};
}

std::size_t count(const TriangleMesh& m) { return find_self_intersections(m).pairs; }

/// The same exact test over all pairs: the reference for the candidate search.
std::vector<std::array<std::uint32_t, 2>> brute_force(const TriangleMesh& m) {
  std::vector<std::array<std::uint32_t, 2>> r;
  for (std::uint32_t i = 0; i < m.triangles.size(); ++i)
    for (std::uint32_t j = i + 1; j < m.triangles.size(); ++j)
      if (triangles_intersect(m, i, j)) r.push_back({i, j});
  return r;
}

void expect_matches_brute_force(const TriangleMesh& m, const std::string& what) {
  const auto ref = brute_force(m);
  const SelfIntersections s = find_self_intersections(m, 16);
  EXPECT_EQ(s.pairs, ref.size()) << what;
  const auto end = ref.begin() + std::ptrdiff_t(std::min<std::size_t>(16, ref.size()));
  const std::vector<std::array<std::uint32_t, 2>> first(ref.begin(), end);
  EXPECT_EQ(s.examples, first) << what;
}

struct Off {
  TriangleMesh mesh;
  bool found = false;
};
Off read_off(const std::string& name) {
  const auto file = std::filesystem::path(HYBRIDTREE_SOURCE_DIR) / "data" / "meshes" / name;
  Off r;
  if (!std::filesystem::exists(file)) return r;
  std::ifstream in(file);
  std::string magic;
  std::size_t nv = 0, nf = 0, ne = 0;
  in >> magic >> nv >> nf >> ne;
  r.mesh.positions.resize(nv);
  for (auto& p : r.mesh.positions) in >> p.x >> p.y >> p.z;
  for (std::size_t f = 0; f < nf; ++f) {
    std::size_t n = 0;
    in >> n;
    std::vector<unsigned> idx(n);
    for (auto& i : idx) in >> i;
    for (std::size_t i = 1; i + 1 < n; ++i) r.mesh.triangles.push_back({idx[0], idx[i], idx[i + 1]});
  }
  r.found = in.good() || in.eof();
  return r;
}

// ---- Closed surfaces ---------------------------------------------------------------------------

TEST(SelfIntersections, ClosedSpheresHaveNone) {
  for (int l = 0; l <= 4; ++l) {
    const TriangleMesh m = icosphere(l);
    EXPECT_EQ(count(m), 0u) << "icosphere level " << l;
    const MeshChecks c = check_mesh(m);
    EXPECT_TRUE(c.watertight());
    EXPECT_TRUE(c.intersection_free()) << c.self_intersecting_pairs;
  }
  for (unsigned r : {3u, 8u, 40u})
    for (unsigned s : {3u, 7u, 64u}) EXPECT_EQ(count(uv_sphere(r, s)), 0u) << r << " x " << s;
  // Far from the origin, where float boxes are coarse and double differences round.
  EXPECT_EQ(count(icosphere(3, 1e-3, dvec3(1e4, -2e4, 3e4))), 0u);
  EXPECT_EQ(check_mesh(TriangleMesh{}).self_intersecting_pairs, 0u);
}

TEST(SelfIntersections, OverlappingSpheresCrossEachOther) {
  const TriangleMesh a = icosphere(3), b = icosphere(3, 0.8, dvec3(1.0, 0.1, 0.05));
  const TriangleMesh m = soup(a, b);
  const SelfIntersections s = find_self_intersections(m, 16);
  EXPECT_GT(s.pairs, 0u);
  ASSERT_EQ(s.examples.size(), std::min<std::size_t>(16, s.pairs));
  const auto na = static_cast<std::uint32_t>(a.triangles.size());
  for (const auto& e : s.examples) {
    EXPECT_LT(e[0], na) << "first of a pair from the first sphere";
    EXPECT_GE(e[1], na) << "second of a pair from the second sphere";
  }
  EXPECT_TRUE(std::is_sorted(s.examples.begin(), s.examples.end()));
  EXPECT_EQ(check_mesh(m).self_intersecting_pairs, s.pairs);
  // Deterministic, and the count does not depend on how many examples are asked for.
  const SelfIntersections again = find_self_intersections(m, 16);
  EXPECT_EQ(again.pairs, s.pairs);
  EXPECT_EQ(again.examples, s.examples);
  EXPECT_EQ(find_self_intersections(m, 0).pairs, s.pairs);
  EXPECT_TRUE(find_self_intersections(m, 0).examples.empty());
  expect_matches_brute_force(soup(icosphere(2), icosphere(2, 0.7, dvec3(0.9, 0.2, 0.0))), "level 2 spheres");
}

TEST(SelfIntersections, DisjointSpheresAndSpheresTouchingAtASharedPosition) {
  EXPECT_EQ(count(soup(icosphere(3), icosphere(3, 1.0, dvec3(2.001, 0, 0)))), 0u);
  // The north pole of the lower sphere and the south pole of the upper one are the same point
  // at different indices: shared, so touching there is no intersection.
  const TriangleMesh lower = uv_sphere(12, 16), upper = uv_sphere(12, 16, 1.0, dvec3(0, 0, 2));
  ASSERT_EQ(lower.positions.front(), upper.positions.back());
  EXPECT_EQ(count(soup(lower, upper)), 0u);
  // One step closer, the poles poke into each other.
  const TriangleMesh closer = uv_sphere(12, 16, 1.0, dvec3(0, 0, std::nextafter(2.0, 0.0)));
  EXPECT_GT(count(soup(lower, closer)), 0u);
}

TEST(SelfIntersections, AVertexPushedThroughTheOppositeSideFolds) {
  TriangleMesh m = icosphere(2);
  ASSERT_EQ(count(m), 0u);
  m.positions[5] *= -1.3;
  const SelfIntersections s = find_self_intersections(m);
  EXPECT_GT(s.pairs, 0u);
  EXPECT_TRUE(check_mesh(m).watertight()) << "topology is unchanged";
  EXPECT_FALSE(check_mesh(m).intersection_free());
  // A dent that stays on its side is no fold.
  TriangleMesh dent = icosphere(2);
  dent.positions[5] *= 0.9;
  EXPECT_EQ(count(dent), 0u);
}

// ---- The pair rules ----------------------------------------------------------------------------

const dvec3 O(0, 0, 0), X(1, 0, 0), Y(0, 1, 0);

/// Two triangles on an edge O X: by index (four vertices) and by position only (six).
std::size_t on_edge(dvec3 a, dvec3 b) {
  const TriangleMesh shared{{O, X, a, b}, {{0, 1, 2}, {1, 0, 3}}};
  const std::size_t by_index = count(shared);
  EXPECT_EQ(count(pair_mesh(O, X, a, X, O, b)), by_index) << "position sharing differs from index sharing";
  return by_index;
}

TEST(SelfIntersections, TrianglesOnASharedEdge) {
  EXPECT_EQ(on_edge(Y, dvec3(0.5, 0.5, 0)), 1u) << "folded flat onto each other";
  EXPECT_EQ(on_edge(Y, dvec3(0.3, 2, 0)), 1u) << "folded flat, sticking out";
  EXPECT_EQ(on_edge(Y, dvec3(0.5, -1, 0)), 0u) << "flat, opposite sides";
  EXPECT_EQ(on_edge(Y, dvec3(0.5, 0.5, 1)), 0u) << "at a dihedral angle";
  EXPECT_EQ(on_edge(Y, dvec3(0.5, 0.5, 1e-12)), 0u) << "almost folded: meets only on the edge";
  EXPECT_EQ(on_edge(Y, dvec3(0.5, -0.5, -1e-30)), 0u);
  const TriangleMesh duplicate{{O, X, Y}, {{0, 1, 2}, {2, 1, 0}}};
  EXPECT_EQ(count(duplicate), 1u) << "a duplicate face";
}

TEST(SelfIntersections, TrianglesOnASharedVertex) {
  auto at_vertex = [](dvec3 b1, dvec3 b2) {
    const TriangleMesh m{{O, X, Y, b1, b2}, {{0, 1, 2}, {0, 3, 4}}};
    EXPECT_EQ(count(pair_mesh(O, X, Y, O, b1, b2)), count(m));
    return count(m);
  };
  EXPECT_EQ(at_vertex(dvec3(0.2, 0.2, -1), dvec3(0.2, 0.2, 1)), 1u) << "crossing through the face";
  EXPECT_EQ(at_vertex(dvec3(1, 1, -1), dvec3(1, 1, 1)), 1u) << "crossing through the opposite edge";
  EXPECT_EQ(at_vertex(dvec3(-1, 0, 1), dvec3(-1, 1, 1)), 0u) << "apart";
  EXPECT_EQ(at_vertex(dvec3(-1, 0, 0), dvec3(0, -1, 0)), 0u) << "coplanar, apart";
  EXPECT_EQ(at_vertex(dvec3(1, 1, 0), dvec3(0.5, 1, 0)), 1u) << "coplanar, overlapping";
  EXPECT_EQ(at_vertex(dvec3(0.2, 0.1, 0), dvec3(0.1, 0.2, 0)), 1u) << "coplanar, inside";
  EXPECT_EQ(at_vertex(dvec3(0.5, 0, 0), dvec3(0.5, -1, 0)), 1u) << "coplanar, along an edge";
  EXPECT_EQ(at_vertex(dvec3(0.5, 0, 1), dvec3(0, 0.5, 1)), 0u) << "above, over the face";
  EXPECT_EQ(at_vertex(dvec3(0.2, 0.2, 0), dvec3(0.2, 0.2, 1)), 1u) << "standing on the face along a segment";
}

TEST(SelfIntersections, TrianglesSharingNothing) {
  EXPECT_EQ(count(pair_mesh(O, X, Y, {0.2, 0.2, 0}, {1, 1, 1}, {0, 1, 1})), 1u) << "a corner on the face";
  EXPECT_EQ(count(pair_mesh(O, X, Y, {0.5, 0, 0}, {1, 1, 1}, {0, 1, 1})), 1u) << "a T-junction";
  EXPECT_EQ(count(pair_mesh(O, X, Y, {0.2, 0.2, 1e-9}, {1, 1, 1}, {0, 1, 1})), 0u) << "just above";
  EXPECT_EQ(count(pair_mesh(O, X, Y, {0.2, -1, -1}, {0.2, 2, -1}, {0.2, 0.5, 1})), 1u) << "piercing";
  EXPECT_EQ(count(pair_mesh(O, X, Y, {0.2, 0.2, 0}, {0.3, 0.2, 0}, {0.25, 0.25, 1})), 1u) << "an edge on the face";
  EXPECT_EQ(count(pair_mesh(O, X, Y, {1, 1, 0}, {2, 1, 0}, {1.5, 1.5, 1})), 0u) << "an edge in the plane, off the face";
  EXPECT_EQ(count(pair_mesh(O, X, Y, {0.1, 0.1, 0}, {0.3, 0.1, 0}, {0.1, 0.3, 0})), 1u) << "coplanar, inside";
  EXPECT_EQ(count(pair_mesh(O, X, Y, {0.6, 0.6, 0}, {2, 0.6, 0}, {0.6, 2, 0})), 0u) << "coplanar, apart";
  EXPECT_EQ(count(pair_mesh(O, X, Y, {0.5, 0.5, 0}, {2, 0.5, 0}, {0.5, 2, 0})), 1u) << "coplanar, touching";
  // Degenerate triangles take part in nothing.
  EXPECT_EQ(count(pair_mesh(O, X, Y, {0.2, 0.2, -1}, {0.2, 0.2, 1}, {0.2, 0.2, 0})), 0u);
  EXPECT_EQ(count(pair_mesh(O, X, Y, {0.2, 0.2, -1}, {0.2, 0.2, 1}, {0.2, 0.2, 1})), 0u);
}

// ---- Exactness ---------------------------------------------------------------------------------

// A tilted lattice far from the origin: points o + i u + j v + k w, integer steps of 2^-20 around
// 2^25, so products of coordinate differences need more than 53 bits. Integer determinants tell
// the truth.
struct Lattice {
  std::int64_t u[3], v[3];
  dvec3 origin;
  dvec3 at(std::int64_t i, std::int64_t j, const std::int64_t* w = nullptr) const {
    dvec3 p = origin;
    for (int c = 0; c < 3; ++c) p[c] += std::ldexp(double(i * u[c] + j * v[c] + (w ? w[c] : 0)), -20);
    return p;
  }
  std::int64_t side(const std::int64_t* w) const {  // det(u, v, w)
    return w[0] * (u[1] * v[2] - u[2] * v[1]) + w[1] * (u[2] * v[0] - u[0] * v[2]) + w[2] * (u[0] * v[1] - u[1] * v[0]);
  }
};

Lattice random_lattice(Rng& rng) {
  std::uniform_int_distribution<std::int64_t> d(-(1 << 18), 1 << 18);
  std::uniform_int_distribution<int> off(-3, 3);
  Lattice l{};
  for (;;) {
    for (int c = 0; c < 3; ++c) l.u[c] = d(rng), l.v[c] = d(rng);
    const std::int64_t n[3] = {l.u[1] * l.v[2] - l.u[2] * l.v[1], l.u[2] * l.v[0] - l.u[0] * l.v[2],
                               l.u[0] * l.v[1] - l.u[1] * l.v[0]};
    if (std::abs(n[0]) + std::abs(n[1]) + std::abs(n[2]) > (std::int64_t(1) << 34)) break;  // not too flat
  }
  for (int c = 0; c < 3; ++c) l.origin[c] = std::ldexp(1.0 + 0.25 * off(rng), 25);
  return l;
}

/// A lattice step w far off the plane, on the positive side when `positive`.
void off_plane(Rng& rng, const Lattice& l, bool positive, std::int64_t* w) {
  std::uniform_int_distribution<std::int64_t> d(-(1 << 18), 1 << 18);
  for (;;) {
    for (int c = 0; c < 3; ++c) w[c] = d(rng);
    const std::int64_t s = l.side(w);
    if ((positive ? s : -s) > (std::int64_t(1) << 50)) return;
  }
}

TEST(SelfIntersections, ExactTouchingOnATiltedLattice) {
  Rng rng = seeded();
  std::uniform_int_distribution<std::int64_t> unit(-1, 1);
  for (int trial = 0; trial < 300; ++trial) {
    const Lattice l = random_lattice(rng);
    const dvec3 a0 = l.at(0, 0), a1 = l.at(6, 0), a2 = l.at(0, 6);
    std::int64_t w1[3], w2[3], s[3];
    off_plane(rng, l, true, w1);
    off_plane(rng, l, true, w2);
    // A corner exactly on the face's interior, and exactly on an edge.
    EXPECT_EQ(count(pair_mesh(a0, a1, a2, l.at(2, 2), l.at(2, 2, w1), l.at(2, 2, w2))), 1u) << trial;
    EXPECT_EQ(count(pair_mesh(a0, a1, a2, l.at(3, 0), l.at(3, 0, w1), l.at(3, 0, w2))), 1u) << trial;
    // One step off the plane: above stays clear, below goes through.
    do
      for (auto& c : s) c = unit(rng);
    while (l.side(s) == 0);
    const std::size_t expected = l.side(s) > 0 ? 0u : 1u;
    EXPECT_EQ(count(pair_mesh(a0, a1, a2, l.at(2, 2, s), l.at(2, 2, w1), l.at(2, 2, w2))), expected) << trial;
    // Coplanar, by lattice steps: overlapping, sharing a corner only, apart, folded on an edge,
    // flat across an edge.
    EXPECT_EQ(count(pair_mesh(a0, a1, a2, l.at(4, 0), l.at(10, 0), l.at(4, 6))), 1u) << trial;
    EXPECT_EQ(count(pair_mesh(a0, a1, a2, l.at(6, 0), l.at(12, 0), l.at(6, 6))), 0u) << trial;
    EXPECT_EQ(count(pair_mesh(a0, a1, a2, l.at(6, 1), l.at(12, 1), l.at(6, 7))), 0u) << trial;
    EXPECT_EQ(count(pair_mesh(a0, a1, a2, l.at(6, 0), l.at(0, 6), l.at(2, 2))), 1u) << trial;
    EXPECT_EQ(count(pair_mesh(a0, a1, a2, l.at(6, 0), l.at(0, 6), l.at(6, 6))), 0u) << trial;
  }
}

// Coplanar triangles, one corner of the second a few ulps from an edge of the first, at full
// double precision: differences round, so only exact orientation tests get the side right.
// Coordinates in [2^-8, 1] in magnitude are multiples of 2^-60, so 128-bit integers tell the
// truth.
__extension__ using Int128 = __int128;
Int128 fixed(double x) { return static_cast<Int128>(std::ldexp(x, 60)); }
int side(dvec3 a, dvec3 b, dvec3 c) {
  const Int128 l = (fixed(b.x) - fixed(a.x)) * (fixed(c.y) - fixed(a.y));
  const Int128 r = (fixed(b.y) - fixed(a.y)) * (fixed(c.x) - fixed(a.x));
  return l > r ? 1 : l < r ? -1 : 0;
}

TEST(SelfIntersections, ExactNearCollinearCornerInAPlane) {
  Rng rng = seeded();
  std::uniform_real_distribution<double> d(-1, 1), t(0.2, 0.8);
  std::uniform_int_distribution<int> ulps(-3, 3);
  auto representable = [](dvec3 p) {
    for (int c = 0; c < 2; ++c)
      if (std::abs(p[c]) < std::ldexp(1.0, -8) || std::abs(p[c]) > 2) return false;
    return true;
  };
  int tested = 0, touching = 0, apart = 0;
  while (tested < 2000) {
    const dvec3 b(d(rng), d(rng), 0), c(d(rng), d(rng), 0), e = c - b, n(-e.y, e.x, 0);
    dvec3 q = b + t(rng) * e;
    for (int k = ulps(rng); k != 0; k += k > 0 ? -1 : 1) q.x = std::nextafter(q.x, k > 0 ? 2.0 : -2.0);
    for (int k = ulps(rng); k != 0; k += k > 0 ? -1 : 1) q.y = std::nextafter(q.y, k > 0 ? 2.0 : -2.0);
    const dvec3 a = b + 0.5 * e + 0.5 * n, e1 = q - 0.5 * n + 0.1 * e, e2 = q - 0.5 * n - 0.1 * e;
    if (!representable(a) || !representable(b) || !representable(c) || !representable(q) || !representable(e1) ||
        !representable(e2))
      continue;
    const int sa = side(b, c, a), sq = side(b, c, q);
    if (sa == 0 || side(b, c, e1) != -sa || side(b, c, e2) != -sa) continue;
    ++tested;
    const std::size_t expected = (sq == 0 || sq == sa) ? 1u : 0u;
    touching += sq == 0 ? 1 : 0;
    apart += expected == 0 ? 1 : 0;
    EXPECT_EQ(count(pair_mesh(b, c, a, q, e1, e2)), expected) << tested;
    // The same in the tilted plane z = x: coplanar exactly, and the 2D tests drop x or z.
    auto lift = [](dvec3 p) { return dvec3(p.x, p.y, p.x); };
    EXPECT_EQ(count(pair_mesh(lift(b), lift(c), lift(a), lift(q), lift(e1), lift(e2))), expected) << tested;
  }
  EXPECT_GT(apart, 200);
  EXPECT_GT(2000 - apart, 200);
  std::printf("near-collinear corners: %d apart, %d touching, %d across\n", apart, touching, 2000 - apart - touching);
}

TEST(SelfIntersections, CornerOrderAndPairOrderDoNotMatter) {
  Rng rng = seeded();
  std::uniform_real_distribution<double> d(-1, 1);
  std::uniform_int_distribution<int> pick(0, 5);
  std::size_t hits = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    // Random points, some snapped onto others' coordinates so that touching cases come up.
    dvec3 p[6];
    for (auto& q : p) q = dvec3(d(rng), d(rng), d(rng));
    if (trial % 3 == 0) p[3 + pick(rng) % 3] = p[pick(rng) % 3];
    if (trial % 5 == 0) {  // the first triangle level, a corner of the second on its plane
      p[1].z = p[2].z = p[0].z;
      p[3 + pick(rng) % 3].z = p[0].z;
    }
    const bool ref = count(pair_mesh(p[0], p[1], p[2], p[3], p[4], p[5])) == 1;
    hits += ref ? 1 : 0;
    EXPECT_EQ(count(pair_mesh(p[4], p[5], p[3], p[0], p[1], p[2])) == 1, ref) << trial;
    EXPECT_EQ(count(pair_mesh(p[2], p[1], p[0], p[5], p[3], p[4])) == 1, ref) << trial;
    EXPECT_EQ(count(pair_mesh(2.0 * p[1], 2.0 * p[0], 2.0 * p[2], 2.0 * p[3], 2.0 * p[5], 2.0 * p[4])) == 1, ref)
        << trial;
  }
  EXPECT_GT(hits, 100u);
  EXPECT_LT(hits, 1900u);
}

// ---- Random meshes against brute force ---------------------------------------------------------

TEST(SelfIntersections, SmallTrianglesFarApartHaveNone) {
  Rng rng = seeded();
  std::uniform_real_distribution<double> d(-0.4, 0.4);
  TriangleMesh m;
  for (int i = 0; i < 12; ++i)
    for (int j = 0; j < 12; ++j)
      for (int k = 0; k < 12; ++k) {
        const dvec3 c(i, j, k);
        const auto base = static_cast<unsigned>(m.positions.size());
        for (int v = 0; v < 3; ++v) m.positions.push_back(c + dvec3(d(rng), d(rng), d(rng)));
        m.triangles.push_back({base, base + 1, base + 2});
      }
  EXPECT_EQ(count(m), 0u);
}

TEST(SelfIntersections, TrianglesCollapsedToOnePointHaveNone) {
  // Every box a point: Embree's hierarchy builder asserted on such a scene and aborted the
  // process (seen under an address-space limit). Degenerate triangles intersect nothing here.
  TriangleMesh m;
  m.positions.assign(4, dvec3(0.5, -0.25, 2.0));
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  EXPECT_EQ(count(m), 0u);
  const MeshChecks c = check_mesh(m);
  EXPECT_EQ(c.degenerate_triangles, 4u);
  EXPECT_EQ(c.self_intersecting_pairs, 0u);
}

TEST(SelfIntersections, RandomSoupsMatchBruteForce) {
  Rng rng = seeded();
  std::uniform_real_distribution<double> d(0, 1), size(-0.15, 0.15);
  for (int trial = 0; trial < 6; ++trial) {
    TriangleMesh m;  // 300 triangles in the unit cube
    for (unsigned t = 0; t < 300; ++t) {
      const dvec3 c(d(rng), d(rng), d(rng));
      for (int v = 0; v < 3; ++v) m.positions.push_back(c + dvec3(size(rng), size(rng), size(rng)));
      m.triangles.push_back({3 * t, 3 * t + 1, 3 * t + 2});
    }
    expect_matches_brute_force(m, "soup " + std::to_string(trial));
  }
  for (int trial = 0; trial < 6; ++trial) {
    // Corners drawn from a small pool: shared vertices and edges, folds, duplicates; half of
    // them in one tilted plane on a lattice, so coplanar cases are common and exact.
    TriangleMesh m;
    const Lattice l = random_lattice(rng);
    std::uniform_int_distribution<std::int64_t> step(0, 8);
    for (int v = 0; v < 60; ++v) m.positions.push_back(l.at(step(rng), step(rng)));
    for (int v = 0; v < 60; ++v) m.positions.push_back(dvec3(d(rng), d(rng), d(rng)));
    std::uniform_int_distribution<unsigned> in_plane(0, 59), any(0, 119);
    for (int t = 0; t < 300; ++t) {
      const bool flat = t % 2 == 0;
      auto corner = [&] { return flat ? in_plane(rng) : any(rng); };
      const unsigned a = corner(), b = corner(), c = corner();
      m.triangles.push_back({a, b, c});
    }
    expect_matches_brute_force(m, "pooled " + std::to_string(trial));
  }
}

// ---- Flat regular grids -------------------------------------------------------------------------

// Large flat regions of a regular grid (the sweep mesher's boxes) make most candidate pairs
// coplanar neighbours, whose orientation tests are exactly zero: they must come out right and
// fast.
TEST(SelfIntersections, FlatRegularGridsHaveNone) {
  TriangleMesh flat = flat_grid(200, 0.01);  // steps not exact in binary
  ASSERT_EQ(flat.triangles.size(), 80000u);
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(count(flat), 0u) << "flat, in z = 0";
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  std::printf("flat 200 x 200 grid: %zu triangles, %.1f ms\n", flat.triangles.size(), ms);
  TriangleMesh tilted = flat;
  for (auto& p : tilted.positions) p.z = p.x;  // exactly coplanar, in no coordinate plane
  EXPECT_EQ(count(tilted), 0u) << "flat, in z = x";
  const TriangleMesh cube = grid_cube(60);
  const MeshChecks c = check_mesh(cube);
  EXPECT_TRUE(c.watertight());
  EXPECT_EQ(c.self_intersecting_pairs, 0u) << "closed cube of grids";
}

TEST(SelfIntersections, AGridVertexPushedThroughANeighbourFolds) {
  // In the plane: an interior vertex moved past its right-hand neighbour folds its triangles
  // over their neighbours, coplanar.
  TriangleMesh flat = flat_grid(200, 0.01);
  const unsigned v = 100 * 201 + 100, right = v + 1;
  flat.positions[v].x = flat.positions[right].x + 0.003;
  EXPECT_GT(count(flat), 0u) << "folded in the plane";
  // Out of the plane: a vertex of the cube's top face next to the edge x = 1 pushed down and
  // out, through the side face.
  TriangleMesh cube = grid_cube(60);
  auto top_vertex = [&](double x, double y) {
    for (unsigned i = 0; i < cube.positions.size(); ++i)
      if (cube.positions[i] == dvec3(x, y, 1.0)) return i;
    return ~0u;
  };
  const unsigned w = top_vertex(59.0 / 60, 30.0 / 60);
  ASSERT_NE(w, ~0u);
  ASSERT_EQ(count(cube), 0u);
  cube.positions[w] += dvec3(2.0 / 60, 0, -2.0 / 60);
  EXPECT_TRUE(check_mesh(cube).watertight()) << "topology is unchanged";
  EXPECT_GT(count(cube), 0u) << "through the side face";
  // The same on small grids, against brute force.
  TriangleMesh small = flat_grid(12, 0.1);
  small.positions[6 * 13 + 6].x = small.positions[6 * 13 + 7].x + 0.03;
  expect_matches_brute_force(small, "small folded grid");
  TriangleMesh box = grid_cube(6);
  expect_matches_brute_force(box, "small cube");
  for (auto& p : box.positions)
    if (p == dvec3(5.0 / 6, 0.5, 1.0)) p += dvec3(2.0 / 6, 0, -2.0 / 6);
  expect_matches_brute_force(box, "small cube, pushed through");
}

// ---- Real meshes -------------------------------------------------------------------------------

TEST(SelfIntersections, DataMeshes) {
  const Off sphere = read_off("sphere.off");
  if (!sphere.found) GTEST_SKIP() << "data/meshes/sphere.off is missing: run tools/setup.sh";
  EXPECT_EQ(count(sphere.mesh), 0u);
  const Off bunny = read_off("bunny00.off");
  if (!bunny.found) GTEST_SKIP() << "data/meshes/bunny00.off is missing: run tools/setup.sh";
  const auto start = std::chrono::steady_clock::now();
  const SelfIntersections s = find_self_intersections(bunny.mesh);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  std::printf("bunny00.off: %zu triangles, %zu self-intersecting pairs, %.1f ms\n", bunny.mesh.triangles.size(),
              s.pairs, ms);
  for (const auto& e : s.examples) std::printf("  pair %u %u\n", e[0], e[1]);
  EXPECT_EQ(find_self_intersections(bunny.mesh).pairs, s.pairs) << "deterministic";
}

}  // namespace
}  // namespace ht
