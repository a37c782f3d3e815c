// Certified fans (meshers/embedded_fans.hpp): on closed well-shaped spheres every fan is
// certified; boundaries, pinches and a turned triangle's corners are not (a pushed-through cone
// is, and the search still finds where it crosses); and the certificate is sound: on spheres
// jittered until they fold, squashed almost flat or with corners pulled together, no two
// triangles of a certified fan intersect by the exact test, and the self-intersection search that
// skips their pairs finds exactly the pairs a brute-force run of the exact test finds.
#include "meshers/embedded_fans.hpp"
#include "meshers/self_intersections.hpp"
#include "tests/support/test_support.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <map>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace ht {
namespace {

using glm::dvec3;

// All intersecting pairs (i < j) by the exact test, in order.
std::vector<std::array<std::uint32_t, 2>> brute_force(const TriangleMesh& m) {
  std::vector<std::array<std::uint32_t, 2>> r;
  const auto n = static_cast<std::uint32_t>(m.triangles.size());
  for (std::uint32_t i = 0; i < n; ++i)
    for (std::uint32_t j = i + 1; j < n; ++j)
      if (triangles_intersect(m, i, j)) r.push_back({i, j});
  return r;
}

// No two triangles around a certified vertex intersect; returns how many vertices were certified.
std::size_t expect_sound(const TriangleMesh& m, const std::string& what) {
  const std::vector<std::uint8_t> ok = embedded_fans(m);
  std::vector<std::vector<std::uint32_t>> around(m.positions.size());
  for (std::uint32_t t = 0; t < m.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) around[m.triangles[t][k]].push_back(t);
  std::size_t certified = 0;
  for (std::size_t v = 0; v < ok.size(); ++v) {
    if (!ok[v]) continue;
    ++certified;
    for (std::size_t a = 0; a < around[v].size(); ++a)
      for (std::size_t b = a + 1; b < around[v].size(); ++b)
        EXPECT_FALSE(triangles_intersect(m, around[v][a], around[v][b]))
            << what << ": vertex " << v << " is certified, yet triangles " << around[v][a] << " and " << around[v][b] << " meet";
  }
  return certified;
}

void expect_search_exact(const TriangleMesh& m, const std::string& what) {
  const auto ref = brute_force(m);
  const SelfIntersections s = find_self_intersections(m, ref.size());
  EXPECT_EQ(s.pairs, ref.size()) << what;
  EXPECT_EQ(s.examples, ref) << what;
}

TEST(EmbeddedFans, EveryFanOfAClosedSphere) {
  const TriangleMesh m = test::icosphere(4);
  const std::vector<std::uint8_t> ok = embedded_fans(m);
  std::size_t certified = 0;
  for (const std::uint8_t c : ok) certified += c;
  EXPECT_EQ(certified, m.positions.size());
}

TEST(EmbeddedFans, BoundariesPinchesAndFoldsAreNot) {
  // A cap of the sphere (z > 0.3): its rim vertices have open fans.
  const TriangleMesh whole = test::icosphere(3);
  TriangleMesh cap;
  cap.positions = whole.positions;
  for (const auto& t : whole.triangles)
    if (whole.positions[t[0]].z > 0.3 && whole.positions[t[1]].z > 0.3 && whole.positions[t[2]].z > 0.3) cap.triangles.push_back(t);
  std::vector<int> used(cap.positions.size(), 0), rim(cap.positions.size(), 0);
  std::map<std::pair<unsigned, unsigned>, int> edges;
  for (const auto& t : cap.triangles)
    for (int k = 0; k < 3; ++k) used[t[k]] = 1, ++edges[std::minmax(t[k], t[(k + 1) % 3])];
  for (const auto& [e, n] : edges)
    if (n == 1) rim[e.first] = rim[e.second] = 1;
  const std::vector<std::uint8_t> ok = embedded_fans(cap);
  for (std::size_t v = 0; v < ok.size(); ++v) {
    if (used[v]) {
      EXPECT_EQ(ok[v], rim[v] ? 0 : 1) << "vertex " << v;
    }
  }
  // The topmost and bottommost vertices (the icosahedron's corners (0, +-1, +-g) on the sphere).
  unsigned top = 0, bottom = 0;
  for (unsigned v = 0; v < whole.positions.size(); ++v) {
    if (whole.positions[v].z > whole.positions[top].z) top = v;
    if (whole.positions[v].z < whole.positions[bottom].z) bottom = v;
  }
  // A second sphere standing on the first, its bottom vertex the first's top one (one index):
  // the pinch's link is two cycles.
  TriangleMesh two = whole;
  const auto base = static_cast<unsigned>(two.positions.size());
  const dvec3 lift = whole.positions[top] - whole.positions[bottom];
  for (const dvec3& p : whole.positions) two.positions.push_back(p + lift);
  for (const auto& t : whole.triangles) {
    glm::uvec3 u = t + glm::uvec3(base);
    for (int k = 0; k < 3; ++k)
      if (t[k] == bottom) u[k] = top;
    two.triangles.push_back(u);
  }
  EXPECT_EQ(embedded_fans(two)[top], 0);
  // One triangle turned over: its corners are not certified.
  TriangleMesh flipped = whole;
  std::swap(flipped.triangles[7][0], flipped.triangles[7][1]);
  const std::vector<std::uint8_t> f = embedded_fans(flipped);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(f[flipped.triangles[7][k]], 0);
  // A vertex pushed through the sphere to the far side: its own fan is an embedded cone (so
  // certified), which crosses the far side: fans say nothing of triangles outside them.
  TriangleMesh pushed = whole;
  pushed.positions[top] = dvec3(0, 0, -1.5);
  EXPECT_EQ(embedded_fans(pushed)[top], 1);
  expect_sound(pushed, "pushed through");
  EXPECT_GT(find_self_intersections(pushed).pairs, 0u);
  expect_search_exact(pushed, "pushed through");
}

// A fan whose corner w lies within about 1e-10 of the direction it is projected along, with an
// exact coplanar fold of (v, a, w) over (v, w, b): measured against the projected sides, the
// margin let the rounding of w's tiny projection certify it (a review found this one).
TEST(EmbeddedFans, ACornerAlongTheProjectionIsNoLoophole) {
  TriangleMesh m;
  m.positions = {{0x0p+0, 0x0p+0, 0x0p+0},
                 {0x1.bd4870985890ep-1, -0x1.f670cdf6d382cp-5, 0x1p-2},
                 {-0x1.0ade3d9e9dbc6p-1, -0x1.f670cdf6d382cp-3, 0x1p+0},
                 {-0x1.904d5c6dec668p+0, -0x1.78d49a791ea21p-1, 0x1.8p+1},
                 {0x1.0000000000001p-1, 0x1.bb67ae8584caap-1, -0x1.a6035b71dcc71p-3},
                 {-0x1.3c6ef372fe94ep-2, 0x1.e6f0e134455p-1, 0x1.dd4714c3a0dc6p-3},
                 {-0x1.d3bc3aeff7f94p-1, 0x1.a07f921061ad5p-2, 0x1.82d1dd9bd8102p-3},
                 {-0x1.d3bc3aeff7f97p-1, -0x1.a07f921061acap-2, 0x1.2a27e4a560e7fp-2},
                 {-0x1.3c6ef372fe952p-2, -0x1.e6f0e134454ffp-1, -0x1.2944509773899p-2},
                 {0x1.ffffffffffff4p-2, -0x1.bb67ae8584caep-1, -0x1.87599e49f55fap-3}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {0, 4, 5}, {0, 5, 6}, {0, 6, 7}, {0, 7, 8}, {0, 8, 9}, {0, 9, 1}};
  ASSERT_TRUE(triangles_intersect(m, 0, 1));
  EXPECT_EQ(embedded_fans(m)[0], 0);
  expect_sound(m, "corner along the normal");
  expect_search_exact(m, "corner along the normal");
}

// The property: jitter from nothing to past folding, squashing to almost flat (turns near the
// margin) and corners pulled together; the certificate never vouches for a fan that intersects.
TEST(EmbeddedFans, CertifiedFansNeverIntersect) {
  test::Rng rng = test::seeded();
  const TriangleMesh base = test::icosphere(2);  // 320 triangles, edges about 0.3 long
  std::size_t certified = 0, uncertified = 0;
  for (int trial = 0; trial < 60; ++trial) {
    TriangleMesh m = base;
    const double amplitude = 0.6 * (trial % 12) / 11.0;
    std::uniform_real_distribution<double> d(-amplitude, amplitude);
    for (dvec3& p : m.positions) p += dvec3(d(rng), d(rng), d(rng));
    if (trial % 3 == 1)
      for (dvec3& p : m.positions) p.z *= 1e-7;  // nearly flat fans: turns at the margin
    if (trial % 3 == 2) {
      std::uniform_int_distribution<std::size_t> pick(0, m.positions.size() - 1);
      for (int k = 0; k < 10; ++k) m.positions[pick(rng)] = m.positions[pick(rng)];  // corners pulled together
    }
    const std::string what = "trial " + std::to_string(trial);
    const std::size_t c = expect_sound(m, what);
    certified += c;
    uncertified += m.positions.size() - c;
    expect_search_exact(m, what);
  }
  // Both kinds occur, or the property says nothing.
  EXPECT_GT(certified, 500u);
  EXPECT_GT(uncertified, 500u);
}

}  // namespace
}  // namespace ht
