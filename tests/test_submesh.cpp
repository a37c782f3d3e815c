// Taking parts of a mesh out and putting them back (meshers/submesh.hpp), on small meshes made
// by hand where every rim and slab is known.
#include "meshers/submesh.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace ht {
namespace {

// A strip of four triangles along x: 0-1-2, 1-3-2, 2-3-4, 3-5-4.
TriangleMesh strip() {
  TriangleMesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {1.5, 1, 0}, {1, 2, 0}, {2, 2, 0}};
  m.triangles = {{0, 1, 2}, {1, 3, 2}, {2, 3, 4}, {3, 5, 4}};
  return m;
}

// The rim flag of the taken vertex whose index in the whole mesh is v.
bool rim_of(const Submesh& s, std::uint32_t v) {
  const auto at = std::find(s.origin.begin(), s.origin.end(), v);
  EXPECT_NE(at, s.origin.end()) << v;
  return s.rim[std::size_t(at - s.origin.begin())] != 0;
}

TEST(Submesh, AVertexAnUntakenTriangleUsesIsARimWhicheverComesFirst) {
  // The untaken triangle comes first in the mesh, then the part's: vertices 1 and 2 are shared.
  const TriangleMesh m = strip();
  const Pieces p = take_pieces(m, {~0u, 0, 0, 0}, 1);
  ASSERT_EQ(p.parts.size(), 1u);
  ASSERT_EQ(p.rest.size(), 1u);
  EXPECT_TRUE(rim_of(p.parts[0], 1));
  EXPECT_TRUE(rim_of(p.parts[0], 2));
  EXPECT_FALSE(rim_of(p.parts[0], 3));
  EXPECT_FALSE(rim_of(p.parts[0], 4));
  EXPECT_FALSE(rim_of(p.parts[0], 5));
  // The same with the untaken triangle last.
  const Pieces q = take_pieces(m, {0, 0, 0, ~0u}, 1);
  EXPECT_TRUE(rim_of(q.parts[0], 3));
  EXPECT_TRUE(rim_of(q.parts[0], 4));
  EXPECT_FALSE(rim_of(q.parts[0], 0));
  // Two parts meeting at a vertex: it is a rim of both.
  const Pieces r = take_pieces(m, {0, 0, 1, 1}, 2);
  EXPECT_TRUE(rim_of(r.parts[0], 2));
  EXPECT_TRUE(rim_of(r.parts[1], 2));
  EXPECT_TRUE(rim_of(r.parts[0], 3));
  EXPECT_FALSE(rim_of(r.parts[0], 0));
}

TEST(Submesh, PartsPutBackUnchangedGiveTheSameSurface) {
  const TriangleMesh m = strip();
  const Pieces p = take_pieces(m, {~0u, 0, 1, 1}, 2);
  std::vector<TriangleMesh> changed;
  std::vector<std::vector<std::uint32_t>> origin;
  for (const Submesh& s : p.parts) changed.push_back(s.mesh), origin.push_back(s.origin);
  TriangleMesh back = m;
  put_back(back, p, changed, origin);
  EXPECT_EQ(back.positions, m.positions);
  auto sorted = [](const TriangleMesh& x) {
    std::vector<std::array<std::uint32_t, 3>> t;
    for (const glm::uvec3& c : x.triangles) {
      // Rotate so the smallest index leads (the orientation stays).
      const int k = c[0] < c[1] ? (c[0] < c[2] ? 0 : 2) : (c[1] < c[2] ? 1 : 2);
      t.push_back({c[k], c[(k + 1) % 3], c[(k + 2) % 3]});
    }
    std::sort(t.begin(), t.end());
    return t;
  };
  EXPECT_EQ(sorted(back), sorted(m));
}

// An n x n grid of vertices in two triangles a square: open along its four sides, or (closed)
// wrapped both ways into a torus.
TriangleMesh grid(int n, bool closed) {
  TriangleMesh m;
  const int cols = closed ? n : n - 1;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const double u = 2 * M_PI * i / n, v = 2 * M_PI * j / n;
      m.positions.push_back(closed ? glm::dvec3((2 + std::cos(v)) * std::cos(u), (2 + std::cos(v)) * std::sin(u), std::sin(v))
                                   : glm::dvec3(i, j, 0));
    }
  auto at = [&](int i, int j) { return std::uint32_t(i % n + n * (j % n)); };
  for (int j = 0; j < cols; ++j)
    for (int i = 0; i < cols; ++i) {
      m.triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      m.triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return m;
}

// The vertices of a part's own triangles that two of its boundary edges leave: where it touches
// itself (found by brute force: every edge against every other).
std::size_t pinches(const TriangleMesh& part) {
  std::vector<std::array<std::uint32_t, 2>> edges;
  for (const glm::uvec3& t : part.triangles)
    for (int k = 0; k < 3; ++k) edges.push_back({t[k], t[(k + 1) % 3]});
  std::vector<int> leaving(part.positions.size(), 0);
  for (const auto& e : edges) {
    int uses = 0;
    for (const auto& f : edges) uses += (f[0] == e[0] && f[1] == e[1]) || (f[0] == e[1] && f[1] == e[0]);
    if (uses == 1) ++leaving[e[0]];
  }
  return std::size_t(std::count_if(leaving.begin(), leaving.end(), [](int n) { return n > 1; }));
}

TEST(Submesh, NoPartTouchesItselfOnOpenOrClosedMeshes) {
  // Triangles dealt to parts at random touch themselves at vertices everywhere, on the sides of
  // an open mesh too (where an edge is the mesh's own boundary): every part taken, its pinches
  // given back or widened, is one fan at each vertex, as OpenMesh's halfedges need.
  std::mt19937 rng(7);
  for (const bool closed : {false, true})
    for (int trial = 0; trial < 40; ++trial) {
      const TriangleMesh m = grid(7, closed);
      std::vector<std::uint32_t> piece_of(m.triangles.size());
      std::vector<std::uint8_t> region(m.positions.size());
      for (std::uint32_t& p : piece_of) p = rng() % 4 == 0 ? ~0u : std::uint32_t(rng() % 2);
      for (std::uint8_t& r : region) r = rng() % 4 == 0;
      const Pieces pieces = take_pieces(m, piece_of, 2), region_parts = take_region(m, region, true);
      for (const Pieces* p : {&pieces, &region_parts})
        for (const Submesh& part : p->parts)
          EXPECT_EQ(pinches(part.mesh), 0u) << (closed ? "torus" : "open grid") << ", trial " << trial;
    }
}

TEST(Submesh, SlabsSitAtFixedPlaces) {
  // Slab k holds [k d, (k + 1) d) along the longest axis, numbered from the lowest one used: a
  // vertex added far away renumbers them but moves no boundary.
  TriangleMesh m;
  for (int i = 0; i < 40; ++i) m.positions.push_back({0.37 * i, 0.1 * (i % 3), 0.0});
  std::size_t count = 0;
  const std::vector<std::uint32_t> a = slab_of_vertices(m, 1.0, count);
  EXPECT_EQ(count, std::size_t(std::floor(0.37 * 39)) + 1);
  for (std::size_t v = 0; v < a.size(); ++v) EXPECT_EQ(a[v], std::uint32_t(std::floor(m.positions[v].x))) << v;
  TriangleMesh wider = m;
  wider.positions.push_back({-5.5, 0, 0});
  const std::vector<std::uint32_t> b = slab_of_vertices(wider, 1.0, count);
  for (std::size_t v = 0; v < a.size(); ++v) EXPECT_EQ(b[v], a[v] + 6) << v;
  EXPECT_EQ(b.back(), 0u);
  // A NaN coordinate goes to slab 0 (no undefined conversion).
  wider.positions.push_back({std::numeric_limits<double>::quiet_NaN(), 0, 0});
  EXPECT_EQ(slab_of_vertices(wider, 1.0, count).back(), 0u);
}

}  // namespace
}  // namespace ht
