// Every scene in examples/ loads and meshes with its own precision and the default strategy
// into a closed, oriented 2-manifold without degenerate or self-intersecting triangles, and its
// surface lies on the field's T level (vertex error under a tenth of the precision).
#include "meshers/mesh_checks.hpp"
#include "meshers/mesh_plan.hpp"
#include "meshers/surface_field.hpp"
#include "runtime/scene.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

using namespace ht;

TEST(Examples, EveryExampleMeshesClosedOnItsSurface) {
  std::vector<std::filesystem::path> scenes;
  for (const auto& e : std::filesystem::directory_iterator(std::filesystem::path(HYBRIDTREE_SOURCE_DIR) / "examples"))
    if (e.path().extension() == ".json") scenes.push_back(e.path());
  std::sort(scenes.begin(), scenes.end());
  ASSERT_GE(scenes.size(), 6u);
  const bool igea = test::igea_available();
  for (const auto& file : scenes) {
    SCOPED_TRACE(file.filename().string());
    // Igea comes from ../shared beside the checkout; where that is missing, so are its scenes.
    if (!igea &&
        (file.filename() == "bowl.json" || file.filename() == "restoration.json" ||
         file.filename() == "snake_woman.json" || file.filename() == "spiky_snake_woman.json")) {
      std::printf("skipping %s: no igea-67k.ply in data/meshes/ or ../shared\n", file.filename().c_str());
      continue;
    }
    const Tree tree = load_scene(file);
    const double h = tree.mesher_settings().precision;
    ASSERT_GT(h, 0.0) << "every example says its precision";
    const MeshResult r = mesh_tree(tree, test::mesh_options(h));
    MeshChecks c = check_mesh(*r.mesh);
    SurfaceField field(r.tree->graph_ptr(), r.tree->root(), tree.threshold(), r.mesh->positions.front(), 8.0 * h);
    measure_surface_error(*r.mesh, field, c);
    EXPECT_GT(c.triangles, 1000u);
    EXPECT_TRUE(c.watertight()) << c.boundary_edges << " boundary, " << c.nonmanifold_edges << " non-manifold edges";
    EXPECT_TRUE(c.oriented());
    EXPECT_EQ(c.degenerate_triangles, 0u);
    EXPECT_EQ(c.self_intersecting_pairs, 0u);
    // Faces whose normal points along grad f at their centre: a handful where a mesh leaf's
    // triangle lies in another part's blend zone. Their area stays negligible.
    EXPECT_LT(c.inverted_area, 1e-4 * c.area) << c.inverted_faces << " inverted faces";
    // None turned over onto its neighbours (the snake-woman had four beside its neck, the bowl one).
    EXPECT_EQ(c.folded_triangles, 0u);
    // The carved box's made triangles are all at its Booleans' seams: with the seams' points
    // welded within 0.3 of the shorter boundary edge and the cuts snapping an operand's vertex
    // by at most 0.1 of the precision their first percentile was 9.29 degrees; with the weld at
    // 0.45 (meshers/local_parts.hpp kCreaseWeldFraction) 11.22, with the snap at 0.15 at creases
    // (kCreaseCutSnap) 14.28 and the smallest 1.63 (0.47 before both); with the band around
    // each seam through the quality pass, the seam's points evened along it
    // (meshers/local_booleans.cpp polish_seam), 24.43 and 6.79; with the seam's points merged
    // along it whatever the mean normal of their two-sheet ring, 28.26 and 7.80.
    if (file.filename() == "carved_box.json") {
      EXPECT_GT(c.made_min_angle_p1, 26.5);
      EXPECT_GT(c.made_min_angle, 6.5);
    }
    EXPECT_LT(c.vertex_error_max, 0.1 * h);
  }
}

TEST(Examples, TheFfdSceneStaysIntersectionFreeAcrossPrecisions) {
  // At 0.071 and 0.065 the lattice closed three and two folds the snake-woman's blend band all but
  // made (before the deformed mesh was unfolded); the spiky scene must come out clean at each.
  const auto file = std::filesystem::path(HYBRIDTREE_SOURCE_DIR) / "examples/spiky_snake_woman.json";
  if (!test::igea_available())
    GTEST_SKIP() << "no igea-67k.ply in data/meshes/ or ../shared";
  const Tree tree = load_scene(file);
  for (double h : {0.071, 0.065}) {
    const MeshResult r = mesh_tree(tree, test::mesh_options(h));
    const MeshChecks c = check_mesh(*r.mesh);
    EXPECT_TRUE(c.watertight()) << h;
    EXPECT_EQ(c.self_intersecting_pairs, 0u) << h;
  }
}

TEST(Examples, BlendsStayLocalAwayFromTheirOwnPrecision) {
  // A trim blend joins each operand's cut loop to the patch's by a strip. Where the two loops
  // touched and crossed by a hair, the strip used to spare a triangle turned against the surface
  // by running the other loop ahead until the band passed its width, and the blend fell back to
  // a global polygonization (four to eight times the triangles and the time): each of the first
  // five. Where a turned triangle the strip makes is not mended (the snake-woman's wings at 1.25
  // of its precision), the blend falls back rather than return a fold.
  struct Case {
    const char* file;
    double factor;  // of the scene's own precision
    bool igea, local;
  };
  for (const Case& k : {Case{"winged_bunny.json", 0.7, false, true}, Case{"winged_bunny.json", 0.85, false, true},
                        Case{"winged_bunny.json", 1.6, false, true}, Case{"restoration.json", 1.25, true, true},
                        Case{"bowl.json", 0.5, true, true}, Case{"snake_woman.json", 1.25, true, false}}) {
    SCOPED_TRACE(std::string(k.file) + " at " + std::to_string(k.factor) + " of its precision");
    if (k.igea && !test::igea_available()) {
      std::printf("skipping %s: no igea-67k.ply in data/meshes/ or ../shared\n", k.file);
      continue;
    }
    const Tree tree = load_scene(std::filesystem::path(HYBRIDTREE_SOURCE_DIR) / "examples" / k.file);
    const double h = k.factor * tree.mesher_settings().precision;
    const MeshResult r = mesh_tree(tree, test::mesh_options(h));
    for (const NodeReport& n : r.nodes) {
      if (n.node != r.tree->root() || !k.local) continue;
      EXPECT_NE(n.reason, JobReason::Fallback) << n.fallback_cause;
    }
    const MeshChecks c = test::checks_with_surface(r, tree.threshold());  // folded triangles counted
    EXPECT_TRUE(c.watertight());
    EXPECT_EQ(c.self_intersecting_pairs, 0u);
    EXPECT_EQ(c.folded_triangles, 0u);
  }
}
