// Bridging (meshers/bridge.hpp) on meshes made by hand, where each case is known exactly: a
// sphere cut in two with a gap between the halves, one half the "operand", the other the
// "patch"; then the specks a cut can leave in the patch (a hole that faces nothing, an island),
// and pulling back a boundary that leaves a lone triangle.
#include "meshers/bridge.hpp"
#include "meshers/mesh_checks.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <vector>

namespace ht {
namespace {

// A closed UV sphere of radius 1 (counter-clockwise seen from outside): nu around, nv from pole
// to pole.
TriangleMesh uv_sphere(int nu, int nv) {
  TriangleMesh m;
  const double pi = 3.14159265358979323846;
  m.positions.push_back({0, 0, 1});
  for (int j = 1; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      const double th = pi * j / nv, ph = 2 * pi * i / nu;
      m.positions.push_back({std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)});
    }
  m.positions.push_back({0, 0, -1});
  const auto ring = [nu](int j, int i) { return std::uint32_t(1 + (j - 1) * nu + (i % nu)); };
  const auto south = std::uint32_t(m.positions.size() - 1);
  for (int i = 0; i < nu; ++i) m.triangles.push_back({0, ring(1, i), ring(1, i + 1)});
  for (int j = 1; j + 1 < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      m.triangles.push_back({ring(j, i), ring(j + 1, i), ring(j + 1, i + 1)});
      m.triangles.push_back({ring(j, i), ring(j + 1, i + 1), ring(j, i + 1)});
    }
  for (int i = 0; i < nu; ++i) m.triangles.push_back({south, ring(nv - 1, i + 1), ring(nv - 1, i)});
  return m;
}

// The triangles `keep` accepts (by index and centroid), unused vertices dropped.
TriangleMesh part(const TriangleMesh& m, const std::function<bool(std::size_t, const glm::dvec3&)>& keep) {
  TriangleMesh out;
  std::vector<std::uint32_t> index(m.positions.size(), ~0u);
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    const glm::uvec3 tri = m.triangles[t];
    if (!keep(t, (m.positions[tri[0]] + m.positions[tri[1]] + m.positions[tri[2]]) / 3.0)) continue;
    glm::uvec3 mapped;
    for (int k = 0; k < 3; ++k) {
      if (index[tri[k]] == ~0u) index[tri[k]] = std::uint32_t(out.positions.size()), out.positions.push_back(m.positions[tri[k]]);
      mapped[k] = index[tri[k]];
    }
    out.triangles.push_back(mapped);
  }
  return out;
}

// The triangle of `m` whose centroid is nearest `p`.
std::size_t nearest_triangle(const TriangleMesh& m, const glm::dvec3& p) {
  std::size_t best = 0;
  double best_d = 1e300;
  for (std::size_t t = 0; t < m.triangles.size(); ++t) {
    const glm::uvec3 tri = m.triangles[t];
    const double d = glm::length((m.positions[tri[0]] + m.positions[tri[1]] + m.positions[tri[2]]) / 3.0 - p);
    if (d < best_d) best_d = d, best = t;
  }
  return best;
}

struct Halves {
  TriangleMesh operand, patch;
};

// The sphere's south part (z < -0.1) and north part (z > 0.1), the north part with the triangle
// nearest `hole_at` taken out unless hole_at is zero.
Halves halves(const glm::dvec3& hole_at) {
  const TriangleMesh s = uv_sphere(48, 24);
  const std::size_t hole = glm::length(hole_at) > 0 ? nearest_triangle(s, hole_at) : s.triangles.size();
  return {part(s, [](std::size_t, const glm::dvec3& c) { return c.z < -0.1; }),
          part(s, [hole](std::size_t t, const glm::dvec3& c) { return c.z > 0.1 && t != hole; })};
}

// One closed, oriented piece of genus 0, its triangles apart.
void expect_sphere(const TriangleMesh& m) {
  const MeshChecks c = check_mesh(m);
  EXPECT_TRUE(c.watertight());
  EXPECT_EQ(c.components, 1u);
  EXPECT_EQ(c.euler, 2);
  EXPECT_EQ(c.self_intersecting_pairs, 0u);
}

TEST(Bridge, JoinsFacingLoopsIntoAClosedMesh) {
  const Halves h = halves(glm::dvec3(0.0));
  const TriangleMesh* ops[] = {&h.operand};
  BridgeStats st;
  const TriangleMesh out = bridge(ops, h.patch, 1.0, &st);
  expect_sphere(out);
  EXPECT_EQ(st.loops, 1u);
  EXPECT_EQ(st.holes_closed, 0u);
  EXPECT_EQ(out.positions.size(), h.operand.positions.size() + h.patch.positions.size());
}

TEST(Bridge, ASmallHoleThatFacesNothingIsClosed) {
  // One triangle missing high on the patch: a loop of three edges no operand loop faces.
  const Halves h = halves(glm::normalize(glm::dvec3(0.3, 0.2, 0.7)));
  const TriangleMesh* ops[] = {&h.operand};
  BridgeStats st;
  expect_sphere(bridge(ops, h.patch, 2.0, &st));
  EXPECT_EQ(st.loops, 1u);
  EXPECT_EQ(st.holes_closed, 1u);
  // Too short a limit: the hole is no speck, and the loops do not pair up.
  EXPECT_THROW(bridge(ops, h.patch, 0.4), BridgeError);
}

TEST(Bridge, AHoleOfMoreEdgesIsClosedAroundItsCentroid) {
  // The two triangles of one quad missing: a loop of four edges, closed by four triangles around
  // a new vertex.
  const TriangleMesh s = uv_sphere(48, 24);
  const std::size_t a = nearest_triangle(s, glm::normalize(glm::dvec3(0.3, 0.2, 0.7)));
  const std::size_t b = a % 2 == 0 ? a + 1 : a - 1;  // its quad's other half (rows of two per quad)
  const TriangleMesh operand = part(s, [](std::size_t, const glm::dvec3& c) { return c.z < -0.1; });
  const TriangleMesh patch = part(s, [a, b](std::size_t t, const glm::dvec3& c) { return c.z > 0.1 && t != a && t != b; });
  const TriangleMesh* ops[] = {&operand};
  BridgeStats st;
  const TriangleMesh out = bridge(ops, patch, 2.0, &st);
  expect_sphere(out);
  EXPECT_EQ(st.holes_closed, 1u);
  EXPECT_EQ(out.positions.size(), operand.positions.size() + patch.positions.size() + 1);
}

TEST(Bridge, AnIslandIsNoHole) {
  // A lone triangle beside the patch has a loop no operand loop faces, but closing it would make
  // a second, flat component: the loops do not pair up.
  Halves h = halves(glm::dvec3(0.0));
  const auto base = std::uint32_t(h.patch.positions.size());
  h.patch.positions.push_back({0.0, 0.0, 1.5});
  h.patch.positions.push_back({0.01, 0.0, 1.5});
  h.patch.positions.push_back({0.0, 0.01, 1.5});
  h.patch.triangles.push_back({base, base + 1, base + 2});
  const TriangleMesh* ops[] = {&h.operand};
  EXPECT_THROW(bridge(ops, h.patch, 2.0), BridgeError);
}

TEST(Bridge, PullingBackDropsAPieceLeftWithNoInteriorVertex) {
  // A small triangle inside a large one, joined to it by a band of six triangles: pulling back
  // the outer rim takes the band, and the small triangle left has only rim vertices.
  TriangleMesh m;
  m.positions = {{0, 0, 0}, {4, 0, 0}, {2, 3.4, 0}, {1.7, 1, 0}, {2.3, 1, 0}, {2, 1.5, 0}};
  const std::uint32_t o0 = 0, o1 = 1, o2 = 2, i0 = 3, i1 = 4, i2 = 5;
  m.triangles = {{i0, i1, i2}, {o0, o1, i1}, {o0, i1, i0}, {o1, o2, i2}, {o1, i2, i1}, {o2, o0, i0}, {o2, i0, i2}};
  ASSERT_TRUE(check_mesh(m).oriented());
  EXPECT_TRUE(pull_back_boundary(m).triangles.empty());
  // With an interior vertex left, the piece stays.
  const TriangleMesh s = uv_sphere(16, 8);
  const TriangleMesh cap = part(s, [](std::size_t, const glm::dvec3& c) { return c.z > -0.5; });
  const TriangleMesh back = pull_back_boundary(cap);
  EXPECT_FALSE(back.triangles.empty());
  EXPECT_LT(back.triangles.size(), cap.triangles.size());
}

TEST(Bridge, PinchedFansAreDroppedUntilTheBoundaryIsLoops) {
  // Two triangles around one vertex of a sphere, sharing only that vertex, taken out: two holes
  // meet there and the boundary passes through it twice, which boundary_loops() refuses.
  TriangleMesh m = uv_sphere(16, 8);
  const std::uint32_t v = m.triangles[m.triangles.size() / 2][0];
  std::vector<std::size_t> fan;
  for (std::size_t t = 0; t < m.triangles.size(); ++t)
    if (m.triangles[t][0] == v || m.triangles[t][1] == v || m.triangles[t][2] == v) fan.push_back(t);
  ASSERT_GE(fan.size(), 5u);
  auto shared = [&](std::size_t a, std::size_t b) {
    int n = 0;
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k) n += m.triangles[a][i] == m.triangles[b][k];
    return n;
  };
  std::size_t other = 0;
  for (std::size_t i = 1; i < fan.size() && !other; ++i)
    if (shared(fan[0], fan[i]) == 1) other = fan[i];
  ASSERT_NE(other, 0u);
  const TriangleMesh before = part(m, [&](std::size_t t, const glm::dvec3&) { return t != fan[0] && t != other; });
  EXPECT_THROW(boundary_loops(before), BridgeError);
  TriangleMesh after = before;
  std::vector<std::uint32_t> renumber;
  EXPECT_TRUE(drop_pinched_fans(after, &renumber));
  ASSERT_EQ(renumber.size(), before.positions.size());
  EXPECT_EQ(boundary_loops(after).size(), 1u);  // the two holes and the fan between them are one
  EXPECT_TRUE(check_mesh(after).oriented());
  std::size_t gone = 0;
  for (std::size_t w = 0; w < renumber.size(); ++w) {
    if (renumber[w] == ~0u) ++gone;
    else EXPECT_EQ(after.positions[renumber[w]], before.positions[w]);
  }
  EXPECT_EQ(gone, 1u);  // only the pinch: its neighbours keep triangles of their own
  EXPECT_EQ(after.triangles.size(), before.triangles.size() - (fan.size() - 2));
  // A mesh with no pinch is left as it is.
  TriangleMesh closed = uv_sphere(16, 8);
  EXPECT_FALSE(drop_pinched_fans(closed));
  EXPECT_EQ(closed.triangles.size(), m.triangles.size());
}

}  // namespace
}  // namespace ht
