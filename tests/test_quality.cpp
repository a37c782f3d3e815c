// The quality pass (meshers/quality.hpp) as properties: on every mesh it keeps the topology
// (closed, manifold, oriented, same Euler characteristic and components), the volume (0.5%), the
// surface (vertex and face-centre error no worse than the extracted mesh's), never adds a
// self-intersection, and leaves well-shaped triangles: the first percentile of the smallest angle
// at least 25 degrees on smooth surfaces. Deterministic at any thread count.
#include "meshers/mesh_checks.hpp"
#include "meshers/polygonize.hpp"
#include "nodes/mesh_leaf.hpp"
#include "runtime/builder.hpp"
#include "runtime/optimize.hpp"
#include "runtime/scene.hpp"
#include "tests/support/random_tree.hpp"
#include "tests/support/test_support.hpp"
#include "tools/scenes.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <string>
#include <tuple>
#include <vector>

namespace ht {
namespace {

constexpr double kT = 0.5;

using Meshed = test::Polygonized;

Meshed mesh(const Tree& t, double h, bool quality) {
  PolygonizeOptions o;
  o.precision = h;
  o.quality.enabled = quality;
  return test::polygonize_checked(t, o);
}

// The smallest angle of each triangle, degrees, sorted.
std::vector<double> min_angles(const TriangleMesh& m) {
  std::vector<double> out;
  out.reserve(m.triangles.size());
  for (const glm::uvec3& t : m.triangles) {
    const glm::dvec3 p[3] = {m.positions[t[0]], m.positions[t[1]], m.positions[t[2]]};
    double best = 180.0;
    for (int k = 0; k < 3; ++k) {
      const glm::dvec3 u = p[(k + 1) % 3] - p[k], v = p[(k + 2) % 3] - p[k];
      best = std::min(best, std::atan2(glm::length(glm::cross(u, v)), glm::dot(u, v)) * 180.0 / 3.14159265358979323846);
    }
    out.push_back(best);
  }
  std::sort(out.begin(), out.end());
  return out;
}

double percentile(const std::vector<double>& sorted, double q) {
  return sorted.empty() ? 0.0 : sorted[std::min(sorted.size() - 1, std::size_t(q * double(sorted.size())))];
}

// What the pass must keep, whatever the surface.
void expect_kept(const Meshed& off, const Meshed& on, const std::string& what) {
  EXPECT_TRUE(on.checks.watertight()) << what;
  EXPECT_EQ(on.checks.unused_vertices, 0u) << what;
  EXPECT_EQ(on.checks.euler, off.checks.euler) << what;
  EXPECT_EQ(on.checks.components, off.checks.components) << what;
  EXPECT_NEAR(on.checks.volume, off.checks.volume, 0.005 * std::abs(off.checks.volume)) << what;
  EXPECT_FALSE(on.stats.quality.skipped) << what;
}

TEST(Quality, SnakeTrianglesAreWellShaped) {
  Builder b(kT);
  const Tree t = b.build(scenes::snake(b, 250));  // bench/mesh_bench.cpp's MeshSnakeQuality
  const double h = 0.065;
  const Meshed off = mesh(t, h, false), on = mesh(t, h, true);
  expect_kept(off, on, "snake");
  const std::vector<double> a0 = min_angles(off.mesh), a1 = min_angles(on.mesh);
  std::printf("snake: %zu -> %zu triangles; 1st percentile %.1f -> %.1f deg, smallest %.2f -> %.2f deg; "
              "face error %.3g -> %.3g h; %zu collapses, %zu flips, %zu moves\n",
              off.mesh.triangles.size(), on.mesh.triangles.size(), percentile(a0, 0.01), percentile(a1, 0.01), a0.front(),
              a1.front(), off.checks.face_error_max / h, on.checks.face_error_max / h, on.stats.quality.collapses,
              on.stats.quality.flips, on.stats.quality.moved);
  // Marching tetrahedra alone: a first percentile near 1 degree (what makes the bound a test).
  EXPECT_LT(percentile(a0, 0.01), 5.0);
  EXPECT_GE(percentile(a1, 0.01), 25.0);
  // Issue 9's aim away from creases (the snake has none) is no triangle under 5 degrees. Specks
  // of marching tetrahedra (vertices a few hundredths of a cell apart around a grid point) left
  // one at 3.2 degrees here before remove_valence3 took their corners.
  EXPECT_GE(a1.front(), 15.0);
  // The checks' own percentile (meshers/mesh_checks.hpp), as --stats-json reports it.
  EXPECT_NEAR(on.checks.min_angle_p1, percentile(a1, 0.01), 1e-4);
  EXPECT_NEAR(off.checks.min_angle_p1, percentile(a0, 0.01), 1e-4);
  EXPECT_EQ(on.checks.self_intersecting_pairs, 0u);
  EXPECT_EQ(on.checks.inverted_faces, 0u);
  EXPECT_LE(on.checks.vertex_error_max, off.checks.vertex_error_max * 1.05 + 1e-9);
  EXPECT_LE(on.checks.face_error_max, off.checks.face_error_max * 1.05);
}

TEST(Quality, RandomTreesKeepTopologyVolumeAndSurface) {
  test::Rng rng = test::seeded();
  test::RandomTreeOptions opt;
  opt.meshes = {MeshLeaf::load(test::cgal_mesh("eight.off")), MeshLeaf::load(test::cgal_mesh("sphere.off"))};
  int meshed = 0, smooth = 0;
  for (int trial = 0; trial < 40; ++trial) {
    Builder b(kT);
    const Tree t = b.build(test::random_tree(b, rng, opt));
    Meshed off, on;
    try {
      off = mesh(t, 0.06, false);
      on = mesh(t, 0.06, true);
    } catch (const PolygonizeError&) {
      continue;  // an unbounded solid: tests/test_polygonize.cpp covers it
    }
    if (off.mesh.triangles.empty()) continue;
    ++meshed;
    const std::string what = "trial " + std::to_string(trial);
    expect_kept(off, on, what);
    // Within 15% of the extraction's largest face error: since the vertices beside creases are
    // the pass's too (guarded: no face further off the surface than it was or 0.02 cells), one
    // tree of the 40 (a blend of eight.off where the field is weak, the face 0.33 cells off as
    // extracted) ended 6.8% further off by the quotient |f - T| / |grad f|. Where the field is
    // that weak the quotient read several cells (5 on trial 2), and the checks now cap it by
    // the distance to a corner (meshers/mesh_checks.hpp): such faces measure their triangle's
    // size, which the pass grows (28k -> 20k triangles there), and trial 2 ends 10.4% further.
    // The crease scenes' largest errors stay or shrink.
    EXPECT_LE(on.checks.face_error_max, off.checks.face_error_max * 1.15 + 1e-9) << what;
    const std::vector<double> a1 = min_angles(on.mesh);
    // No fold with or without the pass, creases or not (the crease step's are unfolded).
    EXPECT_EQ(off.checks.self_intersecting_pairs, 0u) << what;
    EXPECT_EQ(on.checks.self_intersecting_pairs, 0u) << what;
    // Nor a triangle turned over onto its neighbours (marching tetrahedra makes a few where the
    // field turns within a cell; collapsed or relaxed away: meshers/unfold.hpp).
    EXPECT_EQ(on.checks.folded_triangles, 0u) << what;
    // Where no crease was found, every triangle is the pass's to shape.
    if (off.stats.crease_edges == 0 && off.stats.corner_vertices == 0) {
      ++smooth;
      EXPECT_GE(percentile(a1, 0.01), 25.0) << what;
      // Inverted against -grad f: mesh leaves' gradients near their surface are issue 14's; the
      // pass adds none.
      EXPECT_LE(on.checks.inverted_faces, off.checks.inverted_faces) << what;
    }
  }
  std::printf("%d random trees meshed, %d without creases\n", meshed, smooth);
  EXPECT_GE(meshed, 20);
  EXPECT_GE(smooth, 5);
}

TEST(Quality, CreasesStaySharp) {
  // The feature step's crease points are the pass's constraints, and the two rings around them
  // take only steps that keep their faces on the surface (quality.hpp kNearCrease): the error
  // figures of tests/test_features.cpp hold with the pass on.
  Builder b(kT);
  const Tree t = b.build(b.subtract({b.point({-0.2, 0, 0}, {1.0}), b.point({0.4, 0.05, 0.1}, {0.8})}, BooleanMode::MinMax));
  for (double h : {0.04, 0.02}) {
    const Meshed off = mesh(t, h, false), on = mesh(t, h, true);
    expect_kept(off, on, "h=" + std::to_string(h));
    EXPECT_GT(on.stats.crease_edges, 0u);
    EXPECT_LT(on.checks.face_error_max, 0.1 * h) << h;
    EXPECT_LE(on.checks.face_error_mean, off.checks.face_error_mean * 1.05) << h;
    std::printf("crease scene h=%g: first percentile %.2f, smallest %.2f degrees, %zu triangles\n", h,
                on.checks.min_angle_p1, on.checks.min_angle, on.checks.triangles);
    // Beside the crease. With the two rings locked the first percentile was 10.9 and 15.1
    // degrees, the smallest angle 1.53 and 1.07 (7.6, 10.9, 0.08 and 0.16 before the short
    // needle edges and cap flips there); then 18.8, 24.7, 1.53 and 3.19 with the crease points
    // where the crease step put them; now, their chains evened (meshers/quality_creases.cpp),
    // 29.1, 30.0, 6.86 and 12.3.
    EXPECT_GT(on.checks.min_angle_p1, 27.0) << h;
    EXPECT_GT(on.checks.min_angle, 5.0) << h;
  }
}

TEST(Quality, CreaseScenesAreWellShapedBesideTheirCreases) {
  // Globally polygonized crease scenes: examples/carved_box.json (a cropped ball minus eight
  // balls), bunny00 united with a ball and minus another (the OpenVDB peer's csg) and eight.off,
  // a polyhedral mesh whose every edge turns the surface 16-41 degrees. With the two rings around
  // crease points locked, the carved box's smooth triangles had a smallest angle of 1.93 degrees
  // and a first percentile of 14.8, the csg's made triangles a first percentile of 23.0
  // (OpenVDB's mesher: 27.6); then 7.3, 32.3 and 29.5. The csg's smooth smallest angle passes
  // issue 9's 5 degrees since a collapse or flip beside a crease may leave a face's middle 0.05
  // cells off the surface (0.02 before: 4.87 degrees). With crease points locked where the
  // crease step put them, the made triangles' first percentiles were 16.4 (carved box), 29.8
  // (csg) and 9.6 (eight.off, smooth 11.5); with their chains evened and their neighbours free
  // (meshers/quality_creases.cpp) 29.5, 31.5 and 20.5 (smooth 26.0).
  struct Scene {
    const char* name;
    Tree tree;
    double h, smooth_min, smooth_p1, made_p1;
  };
  Builder b(kT);
  NodeId csg = b.mesh(test::cgal_mesh("bunny00.off"), {0.05});
  csg = b.unite({csg, b.point({0.50, -0.22, 0.06}, {0.12 / 0.4542})});
  csg = b.subtract({csg, b.point({0.10, -0.17, 0.44}, {0.15 / 0.4542})});
  const Scene scenes[] = {
      {"carved_box", load_scene(std::filesystem::path(HYBRIDTREE_SOURCE_DIR) / "examples/carved_box.json"), 0.01, 5.0,
       30.0, 26.0},
      {"csg", b.build(csg), 0.01, 5.0, 30.0, 30.5},
      {"eight", b.build(b.mesh(test::cgal_mesh("eight.off"), {0.05})), 0.0128, 0.5, 23.0, 18.0}};
  for (const Scene& s : scenes) {
    const Meshed on = mesh(s.tree, s.h, true);
    const MeshChecks& c = on.checks;
    EXPECT_TRUE(c.watertight()) << s.name;
    EXPECT_EQ(c.self_intersecting_pairs, 0u) << s.name;
    EXPECT_EQ(c.folded_triangles, 0u) << s.name;
    EXPECT_GT(on.stats.crease_edges, 0u) << s.name;
    EXPECT_GT(c.smooth_min_angle, s.smooth_min) << s.name;
    EXPECT_GT(c.smooth_min_angle_p1, s.smooth_p1) << s.name;
    EXPECT_GT(c.made_min_angle_p1, s.made_p1) << s.name;
    std::printf("%s: smooth smallest %.2f, first percentile %.2f; made first percentile %.2f degrees\n", s.name,
                c.smooth_min_angle, c.smooth_min_angle_p1, c.made_min_angle_p1);
  }
}

TEST(Quality, SameBytesAtAnyThreadCount) {
  Builder b(kT);
  const Tree t = b.build(scenes::snake(b, 40));
  TriangleMesh one, two;
  tbb::task_arena(1).execute([&] { one = mesh(t, 0.05, true).mesh; });
  tbb::task_arena(2).execute([&] { two = mesh(t, 0.05, true).mesh; });
  ASSERT_EQ(one.positions.size(), two.positions.size());
  ASSERT_EQ(one.triangles.size(), two.triangles.size());
  EXPECT_EQ(std::memcmp(one.positions.data(), two.positions.data(), one.positions.size() * sizeof(glm::dvec3)), 0);
  EXPECT_EQ(std::memcmp(one.triangles.data(), two.triangles.data(), one.triangles.size() * sizeof(glm::uvec3)), 0);
}

TEST(Quality, OffLeavesTheExtractedMesh) {
  Builder b(kT);
  const Tree t = b.build(b.point({0, 0, 0}, {1.0}));
  const Meshed off = mesh(t, 0.05, false);
  EXPECT_EQ(off.stats.quality.collapses + off.stats.quality.flips + off.stats.quality.moved, 0u);
  const Meshed on = mesh(t, 0.05, true);
  EXPECT_GT(on.stats.quality.flips + on.stats.quality.collapses, 0u);
}

TEST(Quality, ComponentsSmallerThanTwoCellsStayAsExtracted) {
  // A blob about two cells across beside a large sphere: the pass improves the sphere and leaves
  // every vertex of the blob where extraction put it (collapsing or relaxing so few triangles
  // folds them into each other).
  Builder b(kT);
  const Tree t = b.build(b.blend({b.point({0, 0, 0}, {1.0}), b.point({3, 0, 0}, {0.2})}));
  const double h = 0.1;
  const Meshed off = mesh(t, h, false), on = mesh(t, h, true);
  expect_kept(off, on, "sphere and blob");
  auto blob = [](const TriangleMesh& m) {
    std::vector<glm::dvec3> out;
    for (const glm::dvec3& p : m.positions)
      if (p.x > 2.0) out.push_back(p);
    std::sort(out.begin(), out.end(), [](const glm::dvec3& a, const glm::dvec3& c) {
      return std::tie(a.x, a.y, a.z) < std::tie(c.x, c.y, c.z);
    });
    return out;
  };
  const std::vector<glm::dvec3> before = blob(off.mesh), after = blob(on.mesh);
  ASSERT_GE(before.size(), 4u);
  glm::dvec3 lo(1e9), hi(-1e9);
  for (const glm::dvec3& p : before) lo = glm::min(lo, p), hi = glm::max(hi, p);
  for (int axis = 0; axis < 3; ++axis) ASSERT_LT(hi[axis] - lo[axis], 2.0 * h) << axis;
  EXPECT_EQ(before, after);
  EXPECT_GT(on.stats.quality.collapses + on.stats.quality.moved, 0u);
}

TEST(Quality, FoldsThePassLeavesAreMendedWithoutARefinement) {
  // 900 primitives at a precision where many are thinner than a cell: relaxing pushes sheets
  // through each other and collapsing does not undo them all (before this rule, 6 pairs were
  // left and the mesh plan polygonized twice more). The pass runs again from the extracted mesh
  // with the folds' surroundings kept: nothing intersects.
  Builder b(kT);
  const Tree t = optimize(b.build(scenes::scatter(b)));
  PolygonizeOptions o;
  o.precision = 0.2;
  const Meshed on = test::polygonize_checked(t, o);
  EXPECT_TRUE(on.checks.watertight());
  EXPECT_EQ(on.checks.self_intersecting_pairs, 0u);
  EXPECT_EQ(on.stats.crease_intersections, 0u);
  EXPECT_LE(on.stats.quality.retries, 1u);
}

}  // namespace
}  // namespace ht
