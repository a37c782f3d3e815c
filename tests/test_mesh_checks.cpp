// The mesh checks (meshers/mesh_checks.hpp): exact defect counts on small meshes whatever their
// numbering; the angle census: which triangles are a mesh leaf's own, which lie at a crease, and
// that the smooth ones' figures are the ones left.
#include "meshers/edge_sides.hpp"
#include "meshers/edges.hpp"
#include "meshers/mesh_checks.hpp"
#include "meshers/mesh_plan.hpp"
#include "meshers/mesh_run.hpp"
#include "nodes/mesh_leaf.hpp"
#include "runtime/builder.hpp"
#include "runtime/scene.hpp"
#include "runtime/tape_eval.hpp"
#include "tests/support/test_support.hpp"

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include <map>

#include <algorithm>
#include <array>
#include <numeric>
#include <random>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <vector>

namespace ht {
namespace {

constexpr double kT = 0.5;

// A tetrahedron, outward: 4 vertices, 6 edges, 4 faces.
TriangleMesh tetrahedron(glm::dvec3 at = glm::dvec3(0.0)) {
  TriangleMesh m;
  m.positions = {at, at + glm::dvec3(1, 0, 0), at + glm::dvec3(0, 1, 0), at + glm::dvec3(0, 0, 1)};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return m;
}

// Two meshes side by side; with `shared`, the second's first vertex is the first's vertex 0.
TriangleMesh both(const TriangleMesh& a, const TriangleMesh& b, bool shared = false) {
  TriangleMesh m = a;
  const std::uint32_t base = std::uint32_t(a.positions.size()) - (shared ? 1u : 0u);
  for (std::size_t v = shared ? 1 : 0; v < b.positions.size(); ++v) m.positions.push_back(b.positions[v]);
  for (glm::uvec3 t : b.triangles) {
    for (int k = 0; k < 3; ++k) t[k] = shared && t[k] == 0 ? 0u : t[k] + base;
    m.triangles.push_back(t);
  }
  return m;
}

// The same mesh with its vertices and triangles renumbered and each triangle's corners rotated.
TriangleMesh shuffled(const TriangleMesh& m, test::Rng& rng) {
  std::vector<std::uint32_t> to(m.positions.size());
  std::iota(to.begin(), to.end(), 0u);
  std::shuffle(to.begin(), to.end(), rng);
  TriangleMesh out;
  out.positions.resize(m.positions.size());
  for (std::size_t v = 0; v < to.size(); ++v) out.positions[to[v]] = m.positions[v];
  for (const glm::uvec3& t : m.triangles) {
    const int r = int(rng() % 3);
    out.triangles.push_back({to[t[r]], to[t[(r + 1) % 3]], to[t[(r + 2) % 3]]});
  }
  std::shuffle(out.triangles.begin(), out.triangles.end(), rng);
  return out;
}

}  // namespace

TEST(MeshChecks, CountsEveryDefectExactlyWhateverTheNumbering) {
  struct Case {
    const char* what;
    TriangleMesh mesh;
    std::size_t edges, boundary, nonmanifold_edges, misoriented, nonmanifold_vertices, unused, components;
    long genus;
  };
  TriangleMesh flipped = tetrahedron(), open = tetrahedron(), fin = tetrahedron(), spare = tetrahedron();
  std::swap(flipped.triangles[3][0], flipped.triangles[3][1]);
  open.triangles.pop_back();
  fin.positions.push_back({1, 1, 1});
  fin.triangles.push_back({1, 2, 4});  // a third triangle on edge 1-2
  spare.positions.push_back({5, 5, 5});
  const std::vector<Case> cases = {
      {"tetrahedron", tetrahedron(), 6, 0, 0, 0, 0, 0, 1, 0},
      {"one face flipped", flipped, 6, 0, 0, 3, 0, 0, 1, 0},
      {"one face gone", open, 6, 3, 0, 0, 0, 0, 1, 0},
      {"a fin on an edge", fin, 8, 2, 1, 0, 0, 0, 1, 0},
      {"an unused vertex", spare, 6, 0, 0, 0, 0, 1, 1, 0},
      {"two apart", both(tetrahedron(), tetrahedron({3, 0, 0})), 12, 0, 0, 0, 0, 0, 2, 0},
      {"two touching at a vertex", both(tetrahedron(), tetrahedron({-1, -1, -1}), true), 12, 0, 0, 0, 1, 0, 2, 0},
  };
  // What check_watertight(), the lean check the mesh plan runs on every result, counts too.
  auto expect_defects = [](const MeshChecks& c, const Case& k) {
    EXPECT_EQ(c.edges, k.edges) << k.what;
    EXPECT_EQ(c.boundary_edges, k.boundary) << k.what;
    EXPECT_EQ(c.nonmanifold_edges, k.nonmanifold_edges) << k.what;
    EXPECT_EQ(c.misoriented_edges, k.misoriented) << k.what;
    EXPECT_EQ(c.nonmanifold_vertices, k.nonmanifold_vertices) << k.what;
    EXPECT_EQ(c.unused_vertices, k.unused) << k.what;
    EXPECT_EQ(c.degenerate_triangles, 0u) << k.what;
  };
  test::Rng rng = test::seeded();
  for (const Case& k : cases)
    for (int trial = 0; trial < 8; ++trial) {
      const TriangleMesh m = trial == 0 ? k.mesh : shuffled(k.mesh, rng);
      const MeshChecks c = check_mesh(m, false);
      expect_defects(c, k);
      EXPECT_EQ(c.components, k.components) << k.what;
      EXPECT_EQ(c.genus, k.genus) << k.what;
      expect_defects(check_watertight(m), k);
    }
  // A corner moved onto the middle of the opposite edge: one face of zero area.
  TriangleMesh flat = tetrahedron();
  flat.positions[3] = 0.5 * (flat.positions[0] + flat.positions[1]);
  for (const TriangleMesh& m : {flat, shuffled(flat, rng)}) {
    EXPECT_EQ(check_mesh(m, false).degenerate_triangles, 1u);
    EXPECT_EQ(check_watertight(m).degenerate_triangles, 1u);
    EXPECT_TRUE(check_watertight(m).closed());
  }
  const MeshChecks c = check_mesh(shuffled(tetrahedron(), rng), false);
  EXPECT_NEAR(c.volume, 1.0 / 6.0, 1e-15);
  EXPECT_NEAR(c.area, 1.5 + std::sqrt(3.0) / 2.0, 1e-15);
  EXPECT_NEAR(c.min_angle, 45.0, 1e-12);
}

namespace {

// Vertex fans on random index soups (few vertices, so that fins, bow ties, repeated corners and
// unused vertices come up), against the definition counted pairwise: the triangles at v, each
// once per corner at v, linked when they share a vertex besides v, form one group.
// boundary_edges against its definition: the edges exactly one side lies on (a corner named
// twice makes a side from a vertex to itself), with that side's direction and slot, ordered by
// lower then upper vertex; on soups small and large (thousands of sides under one vertex), where
// edges are shared by one, two or more sides.
// A vertex that is not finite makes a mesh no watertight one, in the lean check too; the volume
// is summed about the mesh's box (about the origin, a unit box at 1e6 measured -15499).
TEST(MeshChecks, NonFiniteVerticesAndFarVolumes) {
  TriangleMesh t = tetrahedron();
  const double volume = check_mesh(t).volume;
  for (glm::dvec3& p : t.positions) p += glm::dvec3(1e6, -2e6, 3e6);
  EXPECT_NEAR(check_mesh(t).volume, volume, 1e-9 * std::abs(volume));
  t.positions[1].y = std::numeric_limits<double>::quiet_NaN();
  for (const MeshChecks& c : {check_mesh(t), check_watertight(t)}) {
    EXPECT_EQ(c.nonfinite_vertices, 1u);
    EXPECT_FALSE(c.watertight());
  }
}

TEST(MeshChecks, BoundaryEdgesAreTheEdgesOneSideLiesOn) {
  test::Rng rng = test::seeded();
  std::size_t found = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const bool large = trial % 10 == 0;
    const std::uint32_t vertices = large ? 3000 : 4 + std::uint32_t(rng() % 12);
    const std::size_t faces = large ? 40000 : 1 + rng() % 30;
    TriangleMesh m;
    m.positions.assign(vertices, glm::dvec3(0.0));
    for (std::size_t f = 0; f < faces; ++f) {
      glm::uvec3 t(std::uint32_t(rng() % vertices), std::uint32_t(rng() % vertices), std::uint32_t(rng() % vertices));
      if (rng() % 8 != 0)
        while (t[1] == t[0] || t[2] == t[0] || t[2] == t[1])
          t = {std::uint32_t(rng() % vertices), std::uint32_t(rng() % vertices), std::uint32_t(rng() % vertices)};
      m.triangles.push_back(t);
    }
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<BoundaryEdge>> by_edge;
    for (std::uint32_t t = 0; t < m.triangles.size(); ++t)
      for (std::uint32_t k = 0; k < 3; ++k) {
        const std::uint32_t a = m.triangles[t][k], b = m.triangles[t][(k + 1) % 3];
        by_edge[{std::min(a, b), std::max(a, b)}].push_back({a, b, 3 * t + k});
      }
    std::vector<BoundaryEdge> expected;
    for (const auto& [edge, sides] : by_edge)
      if (sides.size() == 1) expected.push_back(sides[0]);
    const std::vector<BoundaryEdge> got = boundary_edges(m);
    ASSERT_EQ(got.size(), expected.size()) << "trial " << trial;
    for (std::size_t i = 0; i < got.size(); ++i) {
      ASSERT_EQ(got[i].from, expected[i].from) << "trial " << trial << " edge " << i;
      ASSERT_EQ(got[i].to, expected[i].to) << "trial " << trial << " edge " << i;
      ASSERT_EQ(got[i].slot, expected[i].slot) << "trial " << trial << " edge " << i;
    }
    found += got.size();
  }
  EXPECT_GT(found, 1000u);
}

TEST(MeshChecks, VertexFansMatchTheirPairwiseDefinition) {
  test::Rng rng = test::seeded();
  std::size_t nonmanifold_seen = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const std::uint32_t vertices = 4 + std::uint32_t(rng() % 6);
    TriangleMesh m;
    for (std::uint32_t v = 0; v < vertices; ++v) m.positions.push_back(glm::dvec3(v, v * v % 7, v % 3));
    const std::size_t faces = 1 + rng() % 12;
    for (std::size_t f = 0; f < faces; ++f) {
      glm::uvec3 t(std::uint32_t(rng() % vertices), std::uint32_t(rng() % vertices), std::uint32_t(rng() % vertices));
      if (rng() % 8 != 0)  // mostly proper triangles, sometimes a corner named twice
        while (t[1] == t[0] || t[2] == t[0] || t[2] == t[1])
          t = {std::uint32_t(rng() % vertices), std::uint32_t(rng() % vertices), std::uint32_t(rng() % vertices)};
      m.triangles.push_back(t);
    }
    std::size_t unused = 0, nonmanifold = 0;
    for (std::uint32_t v = 0; v < vertices; ++v) {
      std::vector<std::uint32_t> at;  // a triangle once per corner at v
      for (std::uint32_t t = 0; t < m.triangles.size(); ++t)
        for (int k = 0; k < 3; ++k)
          if (m.triangles[t][k] == v) at.push_back(t);
      if (at.empty()) {
        ++unused;
        continue;
      }
      std::vector<std::uint32_t> group(at.size());
      std::iota(group.begin(), group.end(), 0u);
      auto root = [&](std::uint32_t x) {
        while (group[x] != x) x = group[x];
        return x;
      };
      for (std::uint32_t i = 0; i < at.size(); ++i)
        for (std::uint32_t j = i + 1; j < at.size(); ++j) {
          bool shared = false;
          for (int x = 0; x < 3; ++x)
            for (int y = 0; y < 3; ++y)
              shared |= m.triangles[at[i]][x] == m.triangles[at[j]][y] && m.triangles[at[i]][x] != v;
          if (shared) group[root(i)] = root(j);
        }
      std::size_t roots = 0;
      for (std::uint32_t i = 0; i < at.size(); ++i) roots += root(i) == i;
      nonmanifold += roots > 1;
    }
    nonmanifold_seen += nonmanifold;
    for (const MeshChecks& c : {check_watertight(m), check_mesh(m, false)}) {
      EXPECT_EQ(c.unused_vertices, unused) << "trial " << trial;
      EXPECT_EQ(c.nonmanifold_vertices, nonmanifold) << "trial " << trial;
    }
  }
  EXPECT_GT(nonmanifold_seen, 100u);  // the soups do hold non-manifold vertices
}

// sides_by_edge's order, on index soups big enough to be counted in parallel ranges and small:
// by (lo, hi, tri, corner), every side once, each with its own direction.
TEST(MeshChecks, SidesComeByEdgeThenTriangle) {
  test::Rng rng = test::seeded();
  for (const std::size_t faces : {std::size_t(7), std::size_t(40000)}) {
    const std::uint32_t vertices = faces < 100 ? 6 : 9000;
    std::vector<glm::uvec3> tris(faces);
    for (glm::uvec3& t : tris)
      t = {std::uint32_t(rng() % vertices), std::uint32_t(rng() % vertices), std::uint32_t(rng() % vertices)};
    std::vector<std::array<std::uint32_t, 4>> want;  // lo, hi, tri, corner
    for (std::uint32_t t = 0; t < faces; ++t)
      for (std::uint32_t k = 0; k < 3; ++k) {
        const std::uint32_t a = tris[t][k], b = tris[t][(k + 1) % 3];
        want.push_back({std::min(a, b), std::max(a, b), t, k});
      }
    std::sort(want.begin(), want.end());
    const std::vector<Side> got = sides_by_edge(vertices, tris);
    ASSERT_EQ(got.size(), want.size());
    for (std::size_t i = 0; i < got.size(); ++i) {
      const Side& s = got[i];
      ASSERT_EQ((std::array<std::uint32_t, 4>{s.lo, s.hi, s.tri, s.corner}), want[i]) << faces << " faces, side " << i;
      ASSERT_EQ(s.forward, tris[s.tri][s.corner] == s.lo && s.lo < s.hi) << i;
    }
  }
}

TEST(MeshChecks, KeptTrianglesAreTheLeafsOwnBitForBit) {
  const auto leaf = MeshLeaf::load(test::cgal_mesh("eight.off"));
  TriangleMesh mesh = *leaf->surface();
  const std::vector<glm::dvec3> leaves = leaf->positions();
  auto count = [](const std::vector<std::uint8_t>& f) { return std::size_t(std::count(f.begin(), f.end(), 1)); };
  EXPECT_EQ(count(kept_leaf_triangles(mesh, leaves)), mesh.triangles.size());
  // One vertex moved by one ulp: the triangles around it are no longer the leaf's.
  const std::uint32_t v = mesh.triangles[0][0];
  std::size_t fan = 0;
  for (const auto& t : mesh.triangles) fan += (t[0] == v || t[1] == v || t[2] == v);
  mesh.positions[v].x = std::nextafter(mesh.positions[v].x, 1e300);
  EXPECT_EQ(count(kept_leaf_triangles(mesh, leaves)), mesh.triangles.size() - fan);
  EXPECT_EQ(count(kept_leaf_triangles(mesh, std::vector<glm::dvec3>{})), 0u);
}

TEST(MeshChecks, ALeafMovedByAffinesKeepsItsTriangles) {
  // Rotated, then moved: the warped-child jobs move every vertex, and the census
  // moves the leaf's corners the same way, so all its triangles are still its own. Under a twist
  // they change shape and count as made.
  const auto leaf = MeshLeaf::load(test::cgal_mesh("eight.off"));
  Builder b(kT);
  const glm::dmat4 turn = glm::rotate(glm::dmat4(1.0), 0.7, glm::dvec3(0.3, 1.0, 0.2));
  const glm::dmat4 place = glm::translate(glm::dmat4(1.0), glm::dvec3(1.5, -2, 0.25));
  const NodeId moved = b.affine(b.affine(b.mesh(leaf, {0.05}), turn), place);
  const Tree t = b.build(moved);
  const MeshResult r = mesh_tree(t, test::mesh_options(0.05));
  auto count = [](const std::vector<std::uint8_t>& f) { return std::size_t(std::count(f.begin(), f.end(), 1)); };
  EXPECT_EQ(count(kept_leaf_triangles(*r.mesh, r.tree->graph(), r.tree->root())), leaf->triangles().size());
  Builder b2(kT);
  const Tree twisted = b2.build(b2.twist(b2.mesh(leaf, {0.05}), Axis::Y, {0, 0, 0}, 1.0));
  const MeshResult r2 = mesh_tree(twisted, test::mesh_options(0.05));
  EXPECT_EQ(count(kept_leaf_triangles(*r2.mesh, r2.tree->graph(), r2.tree->root())), 0u);
}

TEST(MeshChecks, LeafBlendedWithABallKeepsItsFarTriangles) {
  // The leaf's own triangles away from the ball are counted kept; the patch the blend made is not.
  const auto leaf = MeshLeaf::load(test::cgal_mesh("eight.off"));
  Builder b(kT);
  const Aabb box = leaf->bounds();
  const glm::dvec3 top{0.5 * (box.lo.x + box.hi.x), box.hi.y, 0.5 * (box.lo.z + box.hi.z)};
  const double size = glm::length(box.hi - box.lo);
  const Tree t = b.build(b.blend({b.mesh(leaf, {0.02 * size}), b.point(top, {0.1 * size})}));
  MeshRunOptions o;
  o.precision = 0.01 * size;
  const MeshRun run = run_mesh(t, o);
  const MeshChecks& c = run.checks;
  EXPECT_GT(c.kept_triangles, leaf->triangles().size() / 2);
  EXPECT_LT(c.kept_triangles, leaf->triangles().size());
  EXPECT_EQ(c.kept_triangles + c.crease_triangles + c.smooth_triangles, c.triangles);
  EXPECT_GT(c.smooth_triangles, 0u);
}

TEST(MeshChecks, FaceErrorIsBoundedWhereTheGradientVanishes) {
  // A triangle through a point primitive's centre, its corners on the surface: grad f is zero
  // at its centre, where |f - T| / |grad f| read 1e300 (the scatter scene reported it). The
  // centre is one radius r from the surface and from each corner; the cap says r.
  Builder b(kT);
  const Tree t = b.build(b.point({0, 0, 0}, {1.0}));
  double lo = 0, hi = 1;  // f(lo) > T > f(hi) along x
  for (int i = 0; i < 60; ++i) (t.evaluator().field(glm::dvec3(0.5 * (lo + hi), 0, 0)) > kT ? lo : hi) = 0.5 * (lo + hi);
  const double r = 0.5 * (lo + hi);
  TriangleMesh m;
  for (int k = 0; k < 3; ++k) {
    const double a = 2.0 * std::acos(-1.0) * k / 3;
    m.positions.push_back(r * glm::dvec3(std::cos(a), std::sin(a), 0));
  }
  m.triangles = {{0, 1, 2}, {0, 2, 1}};
  MeshChecks c;
  measure_surface_error(m, t.evaluator(), kT, c);
  EXPECT_LT(c.vertex_error_max, 1e-5);
  EXPECT_NEAR(c.face_error_max, r, 1e-5);
  EXPECT_NEAR(c.face_error_mean, r, 1e-5);
  // Where grad f is sound the quotient stands: a small triangle on the surface around +x, its
  // corners 0.1 radians from the pole, has its centre r (1 - cos 0.1) inside.
  for (int k = 0; k < 3; ++k) {
    const double a = 2.0 * std::acos(-1.0) * k / 3;
    m.positions[k] = r * glm::dvec3(std::cos(0.1), std::sin(0.1) * std::cos(a), std::sin(0.1) * std::sin(a));
  }
  measure_surface_error(m, t.evaluator(), kT, c);
  EXPECT_NEAR(c.face_error_max, r * (1 - std::cos(0.1)), 0.05 * r * (1 - std::cos(0.1)));
}

TEST(MeshChecks, WithoutFullChecksTheTopologyStaysAndTheFieldIsNotTaken) {
  // The CLI's run without --stats-json: the same mesh and topology figures, no surface error.
  const auto leaf = MeshLeaf::load(test::cgal_mesh("eight.off"));
  Builder b(kT);
  const Aabb box = leaf->bounds();
  const double size = glm::length(box.hi - box.lo);
  const Tree t = b.build(b.blend({b.mesh(leaf, {0.02 * size}), b.point(box.hi, {0.1 * size})}));
  MeshRunOptions o;
  o.precision = 0.01 * size;
  const MeshRun full = run_mesh(t, o);
  o.full_checks = false;
  const MeshRun lean = run_mesh(t, o);
  ASSERT_EQ(lean.result.mesh->triangles, full.result.mesh->triangles);
  const MeshChecks &f = full.checks, &l = lean.checks;
  EXPECT_TRUE(l.watertight());
  EXPECT_EQ(l.components, f.components);
  EXPECT_EQ(l.genus, f.genus);
  EXPECT_EQ(l.volume, f.volume);
  EXPECT_EQ(l.min_angle_p1, f.min_angle_p1);
  EXPECT_GT(f.face_error_max, 0.0);
  EXPECT_EQ(l.face_error_max, 0.0);
  EXPECT_EQ(l.vertex_error_max, 0.0);
  EXPECT_EQ(l.kept_triangles, 0u);
  EXPECT_GT(f.kept_triangles, 0u);
}

TEST(MeshChecks, CreaseTrianglesLieAlongTheCrease) {
  // A ball minus a ball with min/max: the crease is the circle where the two spheres meet. Every
  // The crease triangles are about as many as the triangles with a corner near both spheres;
  // a ball alone has no crease triangle.
  const glm::dvec3 c1{-0.2, 0, 0}, c2{0.4, 0.05, 0.1};
  const double h = 0.03;
  Builder b(kT);
  const Tree ball = b.build(b.point(c1, {1.0}));
  PolygonizeOptions po;
  po.precision = h;
  const test::Polygonized alone = test::polygonize_checked(ball, po);
  EXPECT_EQ(alone.checks.crease_triangles, 0u);
  EXPECT_EQ(alone.checks.smooth_triangles, alone.checks.triangles);

  Builder b2(kT);
  const Tree carved = b2.build(b2.subtract({b2.point(c1, {1.0}), b2.point(c2, {0.8})}, BooleanMode::MinMax));
  const test::Polygonized r = test::polygonize_checked(carved, po);
  const MeshChecks& c = r.checks;
  ASSERT_GT(c.crease_triangles, 0u);
  EXPECT_LT(c.crease_triangles, c.triangles / 4);
  EXPECT_EQ(c.crease_triangles + c.smooth_triangles, c.triangles);
  // The spheres' radii as meshed: the outer one is the farthest vertex from c1, the dent's the
  // median distance to c2 of the vertices well inside the outer sphere.
  const auto& P = r.mesh.positions;
  double r1 = 0;
  for (const auto& p : P) r1 = std::max(r1, glm::length(p - c1));
  std::vector<double> d2;
  for (const auto& p : P)
    if (glm::length(p - c1) < r1 - 3 * h) d2.push_back(glm::length(p - c2));
  ASSERT_FALSE(d2.empty());
  std::nth_element(d2.begin(), d2.begin() + std::ptrdiff_t(d2.size() / 2), d2.end());
  const double r2 = d2[d2.size() / 2];
  auto near_both = [&](const glm::dvec3& p) {
    return std::abs(glm::length(p - c1) - r1) < 3 * h && std::abs(glm::length(p - c2) - r2) < 3 * h;
  };
  // Within a factor of 3 of the triangles near both spheres; the smooth figure is no worse than
  // the overall one (the small angles are at the crease).
  std::size_t near = 0;
  for (const auto& t : r.mesh.triangles) near += near_both(P[t[0]]) || near_both(P[t[1]]) || near_both(P[t[2]]);
  EXPECT_GT(near, 0u);
  EXPECT_LT(c.crease_triangles, 3 * near);
  EXPECT_GT(3 * c.crease_triangles, near / 3);
  EXPECT_GE(c.smooth_min_angle_p1, c.min_angle_p1);
}

}  // namespace
}  // namespace ht

namespace ht {
namespace {

TEST(MeshChecks, BlendsOfScansLeaveNoSliverAwayFromCreases) {
  // The trim blend's remeshing locks only creases the field has (grad f turns), not edges a
  // sliver's own tilted plane makes look sharp: before, bunny_ear's smallest smooth angle was
  // 0.18 degrees and bunny_garden's 0.13. The operands are refined only near their seams
  // (meshers/local_parts.hpp refined_and_cut): refined across the whole interaction box, the
  // scans' own thin triangles split into thinner ones (first percentiles 22.6, 26.0 and 17.0
  // degrees, the winged bunny's smallest 3.7; now 28.5, 26.4, 24.7 and 11.4). The remesher ends
  // by collapsing or flipping the slivers left beside its locked rim, and lets a crease point go
  // into a neighbour 0.3 of an edge away (meshers/remesh.cpp clean_slivers): without that,
  // the smallest smooth angles of these trees (as loaded, not rewritten by the CLI's optimizer)
  // are restoration 1.96 (first percentile 17.4), the snake-woman 1.58 and the bowl 0.47
  // degrees; with it 12.9 (25.8), 5.8 and 4.7.
  // The targets hold on all six (smallest at least 5 degrees, first percentile at least
  // 25) since the refinement splits a triangle with two long edges along the better of its
  // quad's diagonals (meshers/warp_mesh.cpp): with the fixed diagonal a projected midpoint left
  // caps against the scan's kept edges (bunny_ear 3.76, bowl 4.73; the winged bunny's first
  // percentile 24.7); now 8.2, 6.3 and 27.0.
  // Beside creases too (all made triangles' first percentile, made_p1): a crease point may go
  // into a neighbour 0.3 of an edge away; at 0.1 these were 10.5, 17.4, 20.2 and 30.9 on the
  // winged bunny, restoration, the snake-woman and the bowl, now 11.9, 20.0, 22.9 and 32.1.
  // The local blend's union crease is polished as a Boolean's seams are since the nineteenth
  // stop: its made_p1 17.5 -> 28.6 degrees.
  struct Scene {
    const char* name;
    double min, p1, made_p1;
    bool igea = false;  // skipped where Igea is missing (tests/support/test_support.hpp)
  };
  for (const Scene& s : {Scene{"bunny_ear.json", 5.0, 25.0, 26.0}, Scene{"bunny_garden.json", 5.0, 25.0, 25.0},
                         Scene{"winged_bunny.json", 5.0, 25.0, 11.5}, Scene{"restoration.json", 5.0, 25.0, 19.0, true},
                         Scene{"snake_woman.json", 5.0, 25.0, 22.0, true}, Scene{"bowl.json", 5.0, 25.0, 31.5, true},
                         Scene{"local_blend.json", 5.0, 25.0, 27.0}}) {
    if (s.igea && !test::igea_available()) {
      std::printf("skipping %s: no igea-67k.ply in data/meshes/ or ../shared\n", s.name);
      continue;
    }
    const Tree tree = load_scene(std::filesystem::path(HYBRIDTREE_SOURCE_DIR) / "examples" / s.name);
    const MeshRun run = run_mesh(tree, {});
    const MeshChecks& c = run.checks;
    EXPECT_TRUE(c.watertight()) << s.name;
    EXPECT_EQ(c.self_intersecting_pairs, 0u) << s.name;
    EXPECT_GT(c.smooth_triangles, 1000u) << s.name;
    EXPECT_GT(c.smooth_min_angle, s.min) << s.name;
    EXPECT_GT(c.smooth_min_angle_p1, s.p1) << s.name;
    EXPECT_GT(c.made_min_angle_p1, s.made_p1) << s.name;
  }
}

TEST(MeshChecks, BooleansOfScansLeaveNoSliverAwayFromCreases) {
  // bunny00 united with a ball at its tail and minus one at its flank (the OpenVDB peer's csg,
  // bench/vdb_peer_bench.cpp). A Boolean refines its operands first only near the seams
  // (local::RefinedMesh::refine_near_seam): across the operands' whole meeting box, the scan's
  // own long triangles were bisected into 8-20 degree slivers the seam never reached (smooth
  // triangles' first percentile 24.98 degrees, smallest 8.3; now 29.9 and 10.8). At the seams
  // themselves (made triangles) the first percentile was 9.43 and the smallest angle 1.99 with
  // the stitch's points where both operands' edges cross the seam; with the band around the
  // seam through the quality pass (meshers/local_booleans.cpp polish_seam) 17.3 and 7.28; with
  // the seam's points merged along it past the mean normal of their two-sheet ring, 23.7 and 10.8.
  Builder b(0.5);
  NodeId root = b.mesh(test::cgal_mesh("bunny00.off"), {0.05});
  root = b.unite({root, b.point({0.50, -0.22, 0.06}, {0.12 / 0.4542})});
  root = b.subtract({root, b.point({0.10, -0.17, 0.44}, {0.15 / 0.4542})});
  const Tree tree = b.build(root);
  MeshRunOptions o;
  o.precision = 0.01;
  const MeshRun run = run_mesh(tree, o);
  const MeshChecks& c = run.checks;
  EXPECT_TRUE(c.watertight());
  EXPECT_EQ(c.genus, 0);
  EXPECT_EQ(c.self_intersecting_pairs, 0u);
  EXPECT_EQ(c.degenerate_triangles, 0u);
  EXPECT_GT(c.smooth_triangles, 1000u);
  EXPECT_GT(c.smooth_min_angle, 5.0);
  EXPECT_GT(c.smooth_min_angle_p1, 27.0);
  EXPECT_GT(c.made_min_angle_p1, 21.5);
  EXPECT_GT(c.made_min_angle, 9.0);
}

}  // namespace
}  // namespace ht
