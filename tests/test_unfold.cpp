// Folded triangles (meshers/unfold.hpp): found where a triangle is turned over onto its
// neighbours, never on sound meshes (smooth or sharp), and collapsed away with the mesh left
// closed, manifold and free of intersections.
#include "meshers/unfold.hpp"

#include "meshers/mesh_checks.hpp"
#include "meshers/self_intersections.hpp"
#include "runtime/builder.hpp"
#include "runtime/scene.hpp"
#include "runtime/tape_eval.hpp"
#include "tests/support/test_support.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <set>

using namespace ht;

namespace {

constexpr double kT = 0.5;

test::Polygonized sphere(Builder& b, double h, bool quality) {
  const Tree t = b.build(b.point({0, 0, 0}, {1.0}));
  PolygonizeOptions o;
  o.precision = h;
  o.quality.enabled = quality;
  return test::polygonize_checked(t, o);
}

BatchGradient gradient_of_tree(const Tree& t) {
  return [&t](std::span<const glm::dvec3> p, std::span<double> v, std::span<glm::dvec3> g) { t.evaluator().gradient(p, v, g); };
}

// Moves corner 0 of triangle `t` past its opposite edge by `past` of the distance to it, within
// the sphere (projected back onto radius r): t turns over.
void fold_over(TriangleMesh& m, std::uint32_t t, double past) {
  const glm::uvec3 c = m.triangles[t];
  const glm::dvec3 a = m.positions[c[0]], mid = 0.5 * (m.positions[c[1]] + m.positions[c[2]]);
  const double r = glm::length(a);
  m.positions[c[0]] = r * glm::normalize(mid + past * (mid - a));
}

}  // namespace

TEST(Unfold, SoundMeshesHaveNoFoldedTriangles) {
  Builder b(kT);
  const Tree t = b.build(b.point({0, 0, 0}, {1.0}));
  for (const bool quality : {false, true}) {
    const test::Polygonized s = sphere(b, 0.05, quality);
    EXPECT_TRUE(folded_triangles(s.mesh, gradient_of_tree(t)).empty()) << quality;
    EXPECT_EQ(s.checks.folded_triangles, 0u) << quality;
  }
  // A cube's crop: triangles across its sharp edges point away from one face's normal, never
  // from both.
  Builder c(kT);
  const Tree cube = c.build(c.crop(c.point({0, 0, 0}, {2.0}), {-0.3137, -0.2519, -0.2071}, {0.2963, 0.2481, 0.1929}));
  PolygonizeOptions o;
  o.precision = 0.03;
  for (const bool sharp : {false, true}) {
    o.sharp_features = sharp;
    const test::Polygonized r = test::polygonize_checked(cube, o);
    EXPECT_EQ(r.checks.folded_triangles, 0u) << sharp;
    EXPECT_TRUE(folded_triangles(r.mesh, gradient_of_tree(cube)).empty()) << sharp;
  }
}

TEST(Unfold, FoldedTrianglesAreFoundAndCollapsed) {
  Builder b(kT);
  const Tree t = b.build(b.point({0, 0, 0}, {1.0}));
  const BatchGradient g = gradient_of_tree(t);
  test::Rng rng = test::seeded();
  const test::Polygonized s = sphere(b, 0.05, true);
  for (int trial = 0; trial < 10; ++trial) {
    TriangleMesh m = s.mesh;
    // A few triangles far apart turned over.
    std::set<std::uint32_t> turned;
    std::set<std::uint32_t> moved;
    while (turned.size() < 1 + std::size_t(trial % 4)) {
      const auto tri = std::uint32_t(rng() % m.triangles.size());
      const glm::uvec3 c = m.triangles[tri];
      if (std::any_of(moved.begin(), moved.end(), [&](std::uint32_t v) {
            return glm::length(m.positions[v] - m.positions[c[0]]) < 0.3;
          }))
        continue;
      fold_over(m, tri, 0.2);
      turned.insert(tri);
      moved.insert(c[0]);
    }
    const std::vector<std::uint32_t> found = folded_triangles(m, g);
    for (const std::uint32_t tri : turned)
      EXPECT_TRUE(std::binary_search(found.begin(), found.end(), tri)) << "trial " << trial << " triangle " << tri;
    std::vector<std::uint8_t> crease;
    const UnfoldStats st = unfold_folded(m, crease, g, kT);
    EXPECT_EQ(st.pairs_before, found.size()) << trial;
    EXPECT_EQ(st.pairs_after, 0u) << trial;
    EXPECT_GT(st.collapses, 0u) << trial;
    EXPECT_TRUE(folded_triangles(m, g).empty()) << trial;
    const MeshChecks after = check_mesh(m);
    EXPECT_TRUE(after.watertight()) << trial;
    EXPECT_EQ(after.euler, 2) << trial;
    EXPECT_EQ(after.self_intersecting_pairs, 0u) << trial;
    EXPECT_EQ(after.unused_vertices, 0u) << trial;
  }
}

// A min/max union of a circle, a segment and a box (a second stress run's scene): the quality pass
// turned two triangles beside a crease over where no collapse mends them. Its next run keeps their
// corners as extracted, and what it returns folds nowhere, crosses nothing and has no sliver.
TEST(Unfold, FoldsThePassLeavesAreKeptAsExtractedOnTheNextRun) {
  const Tree tree = load_scene(std::filesystem::path(HYBRIDTREE_SOURCE_DIR) / "tests/data/stress/folded_minmax_union.json");
  PolygonizeOptions o;
  o.precision = tree.mesher_settings().precision;
  const test::Polygonized r = test::polygonize_checked(tree, o);
  EXPECT_GE(r.stats.quality.retries, 1u);
  EXPECT_TRUE(r.checks.watertight());
  EXPECT_EQ(r.checks.genus, 2);
  EXPECT_EQ(r.checks.self_intersecting_pairs, 0u);
  EXPECT_EQ(r.checks.folded_triangles, 0u);
  EXPECT_EQ(r.stats.folds.pairs_after, 0u);
  EXPECT_GT(r.checks.min_angle, 1.0);  // boxes two cells wide kept a 0.17 degree sliver
}
