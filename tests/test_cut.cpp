// Cutting a mesh along a level set (meshers/cut.hpp): the kept part, its roots on the crossing
// edges within the tolerance, found in few values of the cut function, and the snap that puts
// near vertices on the cut without searching the other roots again.
#include "meshers/cut.hpp"
#include "meshers/mesh_checks.hpp"
#include "meshers/polygonize.hpp"
#include "runtime/builder.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <set>
#include <vector>

using namespace ht;

namespace {

// A sphere of radius about 0.36 (a point primitive), meshed at h.
TriangleMesh sphere(double h) {
  Builder b(0.5);
  const Tree t = b.build(b.point({0, 0, 0}, {0.8}));
  PolygonizeOptions o;
  o.precision = h;
  return polygonize(t.graph_ptr(), t.root(), 0.5, o);
}

// The tail of a compact kernel around q, less a small level: like a blend's cut, flat and curved
// where it crosses (a cubic in the distance to its support's rim), the hard case for false position.
double tail(const glm::dvec3& p) {
  const double u = 1.0 - glm::dot(p - glm::dvec3(0.3, 0.1, 0.0), p - glm::dvec3(0.3, 0.1, 0.0)) / (0.6 * 0.6);
  return (u > 0 ? u * u * u : 0.0) - 0.01;
}

}  // namespace

TEST(Cut, RootsMeetTheToleranceInFewValues) {
  const TriangleMesh m = sphere(0.02);
  std::atomic<std::size_t> calls{0};
  const BatchField c = [&calls](std::span<const glm::dvec3> points, std::span<double> values) {
    ++calls;
    for (std::size_t i = 0; i < points.size(); ++i) values[i] = -tail(points[i]);  // kept: inside the kernel's reach
  };
  CutOptions o;
  o.snap_distance = 0.0;  // every crossing edge gets a root vertex
  CutStats st;
  const TriangleMesh kept = cut_mesh(m, c, o, &st);
  ASSERT_GT(st.new_vertices, 100u);
  EXPECT_GT(calls.load(), 1u);
  // Halving the kept end's weight at every step took 8.3 values an edge here (eleven on the
  // bowl's blend cut); Illinois takes under six.
  EXPECT_LE(double(st.root_evaluations), 6.0 * double(st.new_vertices));
  // Each root within the tolerance: |c| at most 1e-4 of c's change along its edge, or the
  // bracket 1e-4 of the edge; the tail's slope is below 10, the edges below 0.05.
  EXPECT_EQ(check_mesh(kept).nonmanifold_edges, 0u);
  std::size_t on_cut = 0;
  for (const glm::dvec3& p : kept.positions) on_cut += std::abs(tail(p)) <= 1e-4;
  EXPECT_GE(on_cut, st.new_vertices);
}

// Snapping puts the vertices next to the cut on it; the edges that still cross keep their ends
// and values, so their roots are those found before the snap: the cut takes no more values of c
// with snapping than without.
TEST(Cut, SnappingSearchesNoRootTwice) {
  const TriangleMesh m = sphere(0.02);
  const BatchField c = [](std::span<const glm::dvec3> points, std::span<double> values) {
    for (std::size_t i = 0; i < points.size(); ++i) values[i] = -tail(points[i]);
  };
  CutOptions snapping, plain;
  snapping.snap_distance = 0.004;
  plain.snap_distance = 0.0;
  CutStats with, without;
  const TriangleMesh a = cut_mesh(m, c, snapping, &with);
  const TriangleMesh b = cut_mesh(m, c, plain, &without);
  ASSERT_GT(with.snapped_vertices, 0u);
  EXPECT_EQ(with.root_evaluations, without.root_evaluations);
  EXPECT_TRUE(check_mesh(a).manifold());
  EXPECT_LT(a.positions.size(), b.positions.size());
}

// A refinement's own vertices (from CutOptions::snap_freely_from on) snap at any distance; the
// input's keep the distance bound, so each kept one before that index stays bit for bit.
TEST(Cut, OnlyTheRefinementsVerticesSnapBeyondTheDistance) {
  const TriangleMesh m = sphere(0.02);
  const BatchField c = [](std::span<const glm::dvec3> points, std::span<double> values) {
    for (std::size_t i = 0; i < points.size(); ++i) values[i] = -tail(points[i]);
  };
  auto cut = [&](std::size_t from, CutStats& st) {
    CutOptions o;
    o.snap_distance = 0.0;
    o.snap_freely_from = from;
    return cut_mesh(m, c, o, &st);
  };
  const std::size_t n = m.positions.size();
  CutStats none, all, half, unbounded;
  cut(n, none);
  cut(0, all);
  const TriangleMesh out = cut(n / 2, half);
  CutOptions anywhere;  // the default: no distance bound for anyone
  cut_mesh(m, c, anywhere, &unbounded);
  EXPECT_EQ(none.snapped_vertices, 0u);
  EXPECT_EQ(all.snapped_vertices, unbounded.snapped_vertices);
  EXPECT_GT(half.snapped_vertices, 0u);
  EXPECT_LT(half.snapped_vertices, all.snapped_vertices);
  std::set<std::array<double, 3>> kept;
  for (const glm::dvec3& p : out.positions) kept.insert({p.x, p.y, p.z});
  std::size_t checked = 0;
  for (std::size_t v = 0; v < n / 2; ++v) {
    const glm::dvec3& p = m.positions[v];
    if (tail(p) <= 0) continue;  // cut away (c = -tail >= 0)
    ++checked;
    EXPECT_TRUE(kept.count({p.x, p.y, p.z})) << "input vertex " << v << " moved";
  }
  EXPECT_GT(checked, 100u);
}

// The cut reads c at the ends of crossing edges only: a kept vertex none of whose edges crosses
// may be given any negative value instead of its own (as blend patches do for the vertices of
// octants where the operands surely act, meshers/local_blends.cpp), and the result is the same,
// bit for bit, with snapping on.
TEST(Cut, AKeptVertexAwayFromTheCutNeedsNoValueOfItsOwn) {
  const TriangleMesh m = sphere(0.02);
  const BatchField c = [](std::span<const glm::dvec3> points, std::span<double> values) {
    for (std::size_t i = 0; i < points.size(); ++i) values[i] = -tail(points[i]);
  };
  std::vector<double> cv(m.positions.size());
  c(m.positions, cv);
  // A vertex is away from the cut when it and every neighbour are kept.
  std::vector<std::uint8_t> near(m.positions.size(), 0);
  for (const glm::uvec3& t : m.triangles) {
    const bool crossed = std::min({cv[t[0]], cv[t[1]], cv[t[2]]}) < 0 && std::max({cv[t[0]], cv[t[1]], cv[t[2]]}) >= 0;
    if (crossed)
      for (int k = 0; k < 3; ++k) near[t[k]] = 1;
  }
  std::vector<double> blind = cv;
  std::size_t replaced = 0;
  for (std::size_t v = 0; v < cv.size(); ++v)
    if (cv[v] < 0 && !near[v]) blind[v] = -1e-3, ++replaced;
  ASSERT_GT(replaced, 100u);
  CutOptions o;
  o.snap_distance = 0.004;
  CutStats a_st, b_st;
  const TriangleMesh a = cut_mesh(m, cv, c, o, &a_st);
  const TriangleMesh b = cut_mesh(m, blind, c, o, &b_st);
  ASSERT_GT(a_st.snapped_vertices, 0u);
  EXPECT_EQ(a.triangles, b.triangles);
  ASSERT_EQ(a.positions.size(), b.positions.size());
  for (std::size_t v = 0; v < a.positions.size(); ++v) ASSERT_EQ(a.positions[v], b.positions[v]) << v;
}

// A slab narrower than a snap through a vertex: the vertex snaps onto one side of it, where the
// cut passes twice around it, and would pinch the kept part. Cut again without snapping it, the
// kept part is a manifold: no vertex with two boundary fans, whatever the slab's place and turn.
TEST(Cut, ASnappedVertexNeverPinchesTheKeptPart) {
  const TriangleMesh m = sphere(0.05);
  std::size_t snapped = 0;
  for (std::size_t i = 0; i < 300; ++i) {
    const glm::dvec3 at = m.positions[(i * 7919) % m.positions.size()];
    const double a = 0.37 * double(i), b = 0.11 * double(i);
    const glm::dvec3 n(std::cos(a) * std::cos(b), std::sin(a) * std::cos(b), std::sin(b));
    const double half = 0.004 + 0.004 * double(i % 3);  // edges are about 0.05 long
    const BatchField c = [at, n, half](std::span<const glm::dvec3> points, std::span<double> values) {
      for (std::size_t k = 0; k < points.size(); ++k) values[k] = std::abs(glm::dot(points[k] - at, n)) - half;
    };
    CutOptions o;  // snapping within 0.2 of an edge, at any distance
    CutStats st;
    const TriangleMesh kept = cut_mesh(m, c, o, &st);
    snapped += st.snapped_vertices;
    const MeshChecks k = check_mesh(kept);
    ASSERT_EQ(k.nonmanifold_vertices, 0u) << "slab " << i;
    ASSERT_EQ(k.nonmanifold_edges, 0u) << "slab " << i;
  }
  EXPECT_GT(snapped, 300u);  // (without the retry, slab 1 already pinches)
}
