// Sharp features (meshers/features.hpp): the creases and corners of min/max Booleans and crops
// come out sharp; the mesh stays watertight with the same topology and no fold; smooth surfaces
// are left alone; the result does not depend on the thread count.
#include "meshers/features.hpp"
#include "meshers/mesh_checks.hpp"
#include "meshers/polygonize.hpp"
#include "nodes/mesh_leaf.hpp"
#include "runtime/builder.hpp"
#include "runtime/tape_eval.hpp"
#include "tests/support/random_tree.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <set>
#include <tuple>
#include <functional>
#include <sstream>
#include <string>

using namespace ht;

namespace {

constexpr double kT = 0.5;

using Result = test::Polygonized;

// The feature step is measured on its own, beside plain marching tetrahedra: the quality pass
// (tests/test_quality.cpp) smooths the chamfer that the feature step replaces.
Result mesh(const Tree& t, double h, bool sharp) {
  PolygonizeOptions o;
  o.precision = h;
  o.sharp_features = sharp;
  o.quality.enabled = false;
  return test::polygonize_checked(t, o);
}

struct Scene {
  const char* name;
  std::function<NodeId(Builder&)> make;
};

// Spheres of radius r0 = 0.454 (R = 1, T = 0.5) overlapping at an angle, a sphere cut by a box,
// and a cube: a crop whose box lies inside the sphere, so 12 sharp edges and 8 corners.
const std::vector<Scene>& sharp_scenes() {
  static const std::vector<Scene> scenes = {
      {"union", [](Builder& b) { return b.unite({b.point({-0.3, 0, 0}, {1.0}), b.point({0.3, 0.05, 0}, {1.0})}, BooleanMode::MinMax); }},
      {"intersection",
       [](Builder& b) { return b.intersect({b.point({-0.3, 0, 0}, {1.0}), b.point({0.3, 0.05, 0}, {1.0})}, BooleanMode::MinMax); }},
      {"difference",
       [](Builder& b) { return b.subtract({b.point({-0.2, 0, 0}, {1.0}), b.point({0.4, 0.05, 0.1}, {0.8})}, BooleanMode::MinMax); }},
      {"crop", [](Builder& b) { return b.crop(b.point({0, 0, 0}, {1.0}), {-1, -1, -0.2}, {0.25, 1, 1}); }},
      {"cube", [](Builder& b) { return b.crop(b.point({0, 0, 0}, {2.0}), {-0.3137, -0.2519, -0.2071}, {0.2963, 0.2481, 0.1929}); }},
  };
  return scenes;
}

}  // namespace

TEST(Features, CreasesComeOutSharp) {
  for (const Scene& s : sharp_scenes())
    for (double h : {0.04, 0.02}) {
      Builder b(kT);
      const Tree t = b.build(s.make(b));
      const Result off = mesh(t, h, false), on = mesh(t, h, true);
      std::ostringstream what;
      what << s.name << " h=" << h << ": face error " << off.checks.face_error_max / h << " h without, "
           << on.checks.face_error_max / h << " h with " << on.stats.crease_edges << " crease edges, "
           << on.stats.corner_vertices << " corners";
      std::printf("%s\n", what.str().c_str());
      // Without the feature step the chamfer along the crease is a sizeable part of a cell (this is
      // what makes the bound below a real test); with it, the whole mesh is as close as a smooth
      // surface's (a lone sphere: 0.03 h).
      EXPECT_GT(off.checks.face_error_max, 0.15 * h) << what.str();
      EXPECT_LT(on.checks.face_error_max, 0.1 * h) << what.str();
      EXPECT_LE(on.checks.face_error_mean, off.checks.face_error_mean) << what.str();
      EXPECT_LT(on.checks.vertex_error_max, FeatureOptions{}.max_error * h) << what.str();
      EXPECT_TRUE(on.checks.watertight()) << what.str();
      EXPECT_EQ(on.checks.unused_vertices, 0u) << what.str();
      // No visible fold: what points inward is a few slivers between crease points almost
      // together, under 0.02% of the area (measured: at most 0.014%).
      EXPECT_LT(on.checks.inverted_area, 2e-4 * on.checks.area) << what.str();
      EXPECT_EQ(on.checks.euler, off.checks.euler) << what.str();
      EXPECT_EQ(on.checks.components, off.checks.components) << what.str();
      EXPECT_NEAR(on.checks.volume, off.checks.volume, 0.01 * off.checks.volume) << what.str();
    }
}

TEST(Features, EveryTriangleTheStepChangesHasACreasePoint) {
  // The polygonizer's untangling after the crease step searches only near the crease points
  // (meshers/relax.hpp untangle's `changed`): every triangle the step cut or moved must have one
  // for a corner, the others be the extracted mesh's as they were.
  std::size_t changed = 0;
  for (const Scene& s : sharp_scenes())
    for (double h : {0.04, 0.02}) {
      Builder b(kT);
      const Tree t = b.build(s.make(b));
      const TriangleMesh before = mesh(t, h, false).mesh;
      const TapeEvaluator eval(std::make_shared<const Tape>(compile_tape(t.graph_ptr(), t.root(), kT)));
      std::vector<glm::dvec3> grad(before.positions.size());
      eval.gradient(before.positions, {}, grad);
      std::vector<glm::vec3> normals(grad.size());
      for (std::size_t v = 0; v < grad.size(); ++v) normals[v] = glm::vec3(-glm::normalize(grad[v]));
      TriangleMesh after = before;
      std::vector<std::uint8_t> on_crease;
      const CreaseStats st = split_creases(after, normals, eval, kT, h, {}, &on_crease);
      ASSERT_EQ(on_crease.size(), after.positions.size());
      // Triangles by their corners' positions, each rotated to start at its least corner.
      using Key = std::array<double, 9>;
      auto key = [](const TriangleMesh& m, const glm::uvec3& tri) {
        std::array<glm::dvec3, 3> c{m.positions[tri[0]], m.positions[tri[1]], m.positions[tri[2]]};
        auto less = [](const glm::dvec3& p, const glm::dvec3& q) { return std::tie(p.x, p.y, p.z) < std::tie(q.x, q.y, q.z); };
        std::rotate(c.begin(), std::min_element(c.begin(), c.end(), less), c.end());
        return Key{c[0].x, c[0].y, c[0].z, c[1].x, c[1].y, c[1].z, c[2].x, c[2].y, c[2].z};
      };
      std::set<Key> extracted;
      for (const glm::uvec3& tri : before.triangles) extracted.insert(key(before, tri));
      std::size_t here = 0;
      for (const glm::uvec3& tri : after.triangles) {
        if (extracted.count(key(after, tri))) continue;
        ++here;
        EXPECT_TRUE(on_crease[tri[0]] || on_crease[tri[1]] || on_crease[tri[2]]) << s.name << " h=" << h;
      }
      EXPECT_GT(here, 0u) << s.name << " h=" << h << ": " << st.split_edges << " split edges";
      changed += here;
    }
  EXPECT_GT(changed, 1000u);
}

TEST(Features, NoFoldsLeft) {
  // Crease points placed past their neighbours' fold triangles into each other: sliding them
  // along their crease (meshers/relax.hpp untangle) takes most folds out without rounding the
  // edge, collapses (meshers/unfold.hpp) the rest; the face-error bounds above hold with both.
  // Before, the cube had 720 intersecting pairs at h = 0.02 and the union of spheres 20 at 0.04.
  std::size_t found = 0;
  for (const Scene& s : sharp_scenes())
    for (double h : {0.04, 0.02}) {
      Builder b(kT);
      const Result r = mesh(b.build(s.make(b)), h, true);
      EXPECT_EQ(r.checks.self_intersecting_pairs, 0u) << s.name << " h=" << h;
      EXPECT_EQ(r.stats.crease_intersections, 0u) << s.name << " h=" << h;
      EXPECT_EQ(r.checks.folded_triangles, 0u) << s.name << " h=" << h;
      found += r.stats.unfold.pairs_before;
      std::printf("%s h=%g: %zu pairs after sliding, %zu collapses\n", s.name, h, r.stats.unfold.pairs_before,
                  r.stats.unfold.collapses);
    }
  // The scenes do exercise the collapses.
  EXPECT_GT(found, 0u);
}

TEST(Features, GridAlignedBoxStaysWatertight) {
  // Box faces on grid planes put marching-tetrahedra vertices on the box's edges and corners:
  // the worst case for crease points next to vertices.
  Builder b(kT);
  const Tree t = b.build(b.crop(b.point({0, 0, 0}, {2.0}), {-0.3, -0.25, -0.2}, {0.3, 0.25, 0.2}));
  for (double h : {0.04, 0.02}) {
    const Result r = mesh(t, h, true);
    EXPECT_TRUE(r.checks.watertight()) << h;
    EXPECT_EQ(r.checks.euler, 2) << h;
    EXPECT_LT(r.checks.face_error_max, 0.1 * h) << h;
    EXPECT_LT(r.checks.inverted_area, 2e-4 * r.checks.area) << h;
    EXPECT_NEAR(r.checks.volume, 0.6 * 0.5 * 0.4, 0.005 * 0.6 * 0.5 * 0.4) << h;
  }
}

TEST(Features, SmoothSurfacesAreLeftAlone) {
  // Two spheres apart under a min/max union: the tape can crease, the surface does not.
  Builder b(kT);
  const Tree t = b.build(b.unite({b.point({-0.6, 0, 0}, {1.0}), b.point({0.6, 0, 0}, {1.0})}, BooleanMode::MinMax));
  for (double h : {0.08, 0.04, 0.02}) {
    const Result on = mesh(t, h, true), off = mesh(t, h, false);
    EXPECT_EQ(on.stats.crease_edges, 0u) << h;
    EXPECT_EQ(on.mesh.triangles, off.mesh.triangles) << h;
  }
  // A blend of primitives cannot crease: no normals are even computed.
  Builder c(kT);
  const Tree blend = c.build(c.blend({c.point({-0.3, 0, 0}, {1.0}), c.segment({0, 0, 0}, {0.5, 0.4, 0}, {0.5})}));
  EXPECT_FALSE(may_have_creases(blend.evaluator().tape()));
  EXPECT_TRUE(may_have_creases(Tree(t).evaluator().tape()));
}

TEST(Features, SameMeshAtAnyThreadCount) {
  Builder b(kT);
  const Tree t = b.build(sharp_scenes()[2].make(b));
  auto run = [&](int threads) {
    tbb::task_arena arena(threads);
    TriangleMesh m;
    arena.execute([&] { m = mesh(t, 0.03, true).mesh; });
    return m;
  };
  const TriangleMesh one = run(1), two = run(2);
  EXPECT_EQ(one.triangles, two.triangles);
  EXPECT_EQ(one.positions, two.positions);
}

TEST(Features, RandomTreesStayWatertightWithoutFolds) {
  test::Rng rng(71);
  test::RandomTreeOptions opt;
  opt.meshes = {MeshLeaf::load(test::cgal_mesh("eight.off")), MeshLeaf::load(test::cgal_mesh("sphere.off"))};
  int creased = 0, meshed = 0;
  std::size_t inverted_on = 0, inverted_off = 0, folded_off = 0;
  double inverted_area_on = 0, inverted_area_off = 0, area_on = 0;
  for (int trial = 0; trial < 60; ++trial) {
    Builder b(kT);
    const Tree t = b.build(test::random_tree(b, rng, opt));
    try {
      const Result on = mesh(t, 0.06, true), off = mesh(t, 0.06, false);
      ++meshed;
      creased += on.stats.crease_edges > 0;
      inverted_on += on.checks.inverted_faces;
      inverted_off += off.checks.inverted_faces;
      inverted_area_on += on.checks.inverted_area;
      inverted_area_off += off.checks.inverted_area;
      area_on += on.checks.area;
      EXPECT_TRUE(on.checks.watertight()) << "trial " << trial;
      EXPECT_EQ(on.checks.self_intersecting_pairs, 0u) << "trial " << trial;
      EXPECT_EQ(off.checks.self_intersecting_pairs, 0u) << "trial " << trial;
      // Triangles turned over onto their neighbours without crossing them: marching tetrahedra
      // makes a few where the field turns within a cell (the quality pass takes them out:
      // tests/test_quality.cpp); the crease step's own are collapsed (meshers/unfold.hpp).
      EXPECT_LE(on.checks.folded_triangles, off.checks.folded_triangles) << "trial " << trial;
      folded_off += off.checks.folded_triangles;
      EXPECT_EQ(on.checks.unused_vertices, 0u) << "trial " << trial;
      EXPECT_EQ(on.checks.euler, off.checks.euler) << "trial " << trial;
      EXPECT_LE(on.checks.face_error_max, off.checks.face_error_max * 1.05 + 1e-9) << "trial " << trial;
    } catch (const PolygonizeError&) {
      // An unbounded solid (a blend over R-function differences): test_polygonize covers it.
    }
  }
  std::printf("%d trees meshed, %d with creases; inverted faces %zu (%.2g of the area) with features, %zu (%.2g) without\n",
              meshed, creased, inverted_on, inverted_area_on / area_on, inverted_off, inverted_area_off / area_on);
  EXPECT_GT(creased, 5) << "the random trees should exercise the crease step";
  EXPECT_GT(folded_off, 0u) << "the extraction's folds should be there to compare with";
  EXPECT_LT(inverted_area_on, inverted_area_off + 2e-4 * area_on);
}
