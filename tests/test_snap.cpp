// Vertex snapping (meshers/snap.hpp): where the surface passes through grid points, marching
// tetrahedra's vertices a hair from them merge into one, so faces on grid planes come out as
// plain triangles instead of specks; snapping never changes the topology or the volume, and
// creases through grid points keep their place.
#include "meshers/mesh_checks.hpp"
#include "meshers/polygonize.hpp"
#include "nodes/mesh_leaf.hpp"
#include "runtime/builder.hpp"
#include "tests/support/random_tree.hpp"
#include "tests/support/test_support.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace ht {
namespace {

constexpr double kT = 0.5;

test::Polygonized mesh(const Tree& t, double h, bool snap, bool sharp) {
  PolygonizeOptions o;
  o.precision = h;
  o.snap = snap;
  o.sharp_features = sharp;
  o.quality.enabled = false;
  return test::polygonize_checked(t, o);
}

// Edges shorter than `fraction` of the cell: the specks of a surface through grid points.
std::size_t short_edges(const TriangleMesh& m, double length) {
  std::size_t n = 0;
  for (const glm::uvec3& t : m.triangles)
    for (int k = 0; k < 3; ++k) n += glm::length(m.positions[t[k]] - m.positions[t[(k + 1) % 3]]) < length;
  return n;
}

// A box cut from a large sphere whose faces lie on grid planes at both precisions: the grid
// starts two cells before the solid, and the box is a whole number of cells wide.
Tree grid_box(Builder& b) { return b.build(b.crop(b.point({0, 0, 0}, {2.0}), {-0.3, -0.25, -0.2}, {0.3, 0.25, 0.2})); }

}  // namespace

TEST(Snap, FacesOnGridPlanesHaveNoSpecks) {
  Builder b(kT);
  const Tree t = grid_box(b);
  for (double h : {0.04, 0.02}) {
    const auto off = mesh(t, h, false, false), on = mesh(t, h, true, false);
    const std::size_t specks_off = short_edges(off.mesh, 0.01 * h), specks_on = short_edges(on.mesh, 0.01 * h);
    std::printf("h=%g: %zu edges under 0.01 h without snapping, %zu with; %zu vertices merged\n", h, specks_off,
                specks_on, on.stats.snap.merged_vertices);
    EXPECT_GT(specks_off, 1000u) << h;  // what makes the next line a test
    EXPECT_EQ(specks_on, 0u) << h;
    EXPECT_EQ(on.stats.snap.skipped_points, 0u) << h;
    EXPECT_TRUE(on.checks.watertight()) << h;
    EXPECT_EQ(on.checks.degenerate_triangles, 0u) << h;
    EXPECT_EQ(on.checks.self_intersecting_pairs, 0u) << h;
    EXPECT_EQ(on.checks.euler, 2) << h;
    EXPECT_LT(on.mesh.triangles.size(), off.mesh.triangles.size()) << h;
  }
}

TEST(Snap, CreasesThroughGridPointsAreExact) {
  // The box's edges and corners lie on grid points: merged clusters whose normals disagree go to
  // the point of their tangent planes, and the crease step splits the rest. Without snapping the
  // error along the edges was a tenth of a cell.
  Builder b(kT);
  const Tree t = grid_box(b);
  for (double h : {0.04, 0.02}) {
    const auto on = mesh(t, h, true, true);
    EXPECT_GT(on.stats.snap.crease_points, 0u) << h;
    EXPECT_LT(on.checks.face_error_max, 0.01 * h) << h;
    EXPECT_EQ(on.checks.self_intersecting_pairs, 0u) << h;
    EXPECT_NEAR(on.checks.volume, 0.6 * 0.5 * 0.4, 5e-4 * 0.6 * 0.5 * 0.4) << h;  // 0.5% in test_features
  }
}

TEST(Snap, RandomTreesKeepTopologyAndVolume) {
  test::Rng rng = test::seeded();
  test::RandomTreeOptions opt;
  opt.meshes = {MeshLeaf::load(test::cgal_mesh("eight.off")), MeshLeaf::load(test::cgal_mesh("sphere.off"))};
  int meshed = 0, snapped = 0;
  for (int trial = 0; trial < 40; ++trial) {
    Builder b(kT);
    const Tree t = b.build(test::random_tree(b, rng, opt));
    try {
      const auto off = mesh(t, 0.06, false, false), on = mesh(t, 0.06, true, false);
      if (off.mesh.triangles.empty()) continue;
      ++meshed;
      snapped += on.stats.snap.merged_vertices > 0;
      const std::string what = "trial " + std::to_string(trial);
      EXPECT_TRUE(on.checks.watertight()) << what;
      EXPECT_EQ(on.checks.degenerate_triangles, 0u) << what;
      EXPECT_EQ(on.checks.unused_vertices, 0u) << what;
      EXPECT_EQ(on.checks.self_intersecting_pairs, 0u) << what;
      EXPECT_EQ(on.checks.euler, off.checks.euler) << what;
      EXPECT_EQ(on.checks.components, off.checks.components) << what;
      EXPECT_NEAR(on.checks.volume, off.checks.volume, 0.005 * std::abs(off.checks.volume)) << what;
      EXPECT_LE(on.checks.vertex_error_max, off.checks.vertex_error_max + 0.01 * 0.06) << what;
    } catch (const PolygonizeError&) {
      // an unbounded solid: tests/test_polygonize.cpp covers it
    }
  }
  EXPECT_GE(meshed, 20);
  EXPECT_GE(snapped, 10) << "the random trees should exercise snapping";
}

}  // namespace ht
