// The mesh plan: leaves share their mesh, primitives sweep, warps warp their child's mesh and
// split stretched edges with new vertices on the warped surface, hints win; every result is
// watertight.
#include "meshers/mesh_checks.hpp"
#include "meshers/mesh_plan.hpp"
#include "meshers/sweep.hpp"
#include "meshers/warp_mesh.hpp"
#include "nodes/mesh_leaf.hpp"
#include "runtime/builder.hpp"
#include "runtime/optimize.hpp"
#include "runtime/scene.hpp"
#include "runtime/tape.hpp"
#include "runtime/tape_eval.hpp"
#include "tests/support/random_tree.hpp"
#include "tools/scenes.hpp"

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <atomic>

using namespace ht;
using glm::dvec3;

namespace {
constexpr double kT = 0.5;

MeshOptions at(double h, MeshStrategy s = MeshStrategy::Auto) { return test::mesh_options(h, s); }
}  // namespace

TEST(MeshPlan, LeavesShareTheirMesh) {
  Builder b(kT);
  const auto leaf = MeshLeaf::load(test::cgal_mesh("eight.off"));
  const NodeId m = b.mesh(leaf, {0.05});
  const Tree t = b.build(m);
  const MeshResult r = mesh_tree(t, at(0.02));
  EXPECT_EQ(r.mesh.get(), leaf->surface().get());  // the same object: not copied
  ASSERT_EQ(r.nodes.size(), 1u);
  EXPECT_EQ(r.nodes[0].strategy, JobStrategy::SharedLeaf);
}

TEST(MeshPlan, WarpedMeshesStayWatertightAndOnTheSurface) {
  for (int kind = 0; kind < 4; ++kind) {
    Builder b(kT);
    const NodeId child = b.segment({-0.6, 0, 0}, {0.6, 0, 0}, {0.5});
    NodeId w;
    if (kind == 0)
      w = b.affine(child, glm::scale(glm::dmat4(1.0), dvec3(3.0, 1.0, 1.0)));  // stretches triangles 3x
    else if (kind == 1)
      w = b.twist(child, Axis::X, {0, 0, 0}, 2.5);
    else if (kind == 2)
      w = b.taper(child, Axis::X, {0, 0, 0}, -0.8, 0.8, 0.5, 2.0);
    else
      w = b.bend(child, Axis::X, {0, 0, 0}, -0.8, 0.8, 0.9);
    const Tree t = b.build(w);
    const double h = 0.03;
    const MeshResult r = mesh_tree(t, at(h));
    const auto& mesh = r.mesh;
    MeshChecks c = check_mesh(*mesh);
    measure_surface_error(*mesh, t.evaluator(), kT, c);
    EXPECT_TRUE(c.watertight()) << kind << ": boundary " << c.boundary_edges << " degenerate " << c.degenerate_triangles;
    EXPECT_EQ(c.euler, 2) << kind;
    EXPECT_LT(c.vertex_error_max, 0.02 * h) << kind;
    // No edge much longer than the target after remeshing.
    double longest = 0;
    for (const auto& tri : mesh->triangles)
      for (int k = 0; k < 3; ++k) longest = std::max(longest, glm::length(mesh->positions[tri[k]] - mesh->positions[tri[(k + 1) % 3]]));
    EXPECT_LT(longest, 1.5 * h * 1.01) << kind;
    ASSERT_EQ(r.nodes.size(), 2u);
    EXPECT_EQ(r.nodes[0].strategy, JobStrategy::Sweep);
    EXPECT_EQ(r.nodes[1].strategy, JobStrategy::WarpedChild);
  }
}

// A mesh leaf of negative strength carves: alone its field is nowhere above T, so its solid is
// empty, and so is every mesh built on it alone (it used to answer its own triangles: an affine
// warp of it then refined its stretched edges by Newton steps toward a surface that is not
// there, 320 triangles becoming 16.6 million). Beside another operand, the local strategies
// give the global polygonizer's solid (the union used to fall back to it).
TEST(MeshPlan, NegativeMeshLeavesHaveNoMeshOfTheirOwn) {
  Builder b(kT);
  const auto sphere = MeshLeaf::load(test::cgal_mesh("sphere.off"));
  const NodeId carve = b.mesh(sphere, {0.3, -1.0});
  const NodeId moved = b.affine(carve, glm::scale(glm::rotate(glm::dmat4(1.0), 1.0, dvec3(0, 0, 1)), dvec3(1.3, 1.3, 0.65)));
  for (const NodeId alone : {carve, moved}) {
    const Tree t = b.build(alone);
    const MeshResult r = mesh_tree(t, at(0.05));
    EXPECT_TRUE(r.mesh->triangles.empty()) << r.mesh->triangles.size() << " triangles";
  }
  const NodeId ball = b.point({0, 0, 0}, {2.0});
  const NodeId small = b.affine(carve, glm::translate(glm::dmat4(1.0), dvec3(0.9, 0, 0)) * glm::scale(glm::dmat4(1.0), dvec3(0.4)));
  for (const NodeId root : {b.unite({ball, small}), b.blend({ball, small}), b.subtract({ball, small})}) {
    const Tree t = b.build(root);
    const MeshResult local = mesh_tree(t, at(0.03)), global = mesh_tree(t, at(0.03, MeshStrategy::Global));
    const MeshChecks c = check_mesh(*local.mesh), g = check_mesh(*global.mesh);
    EXPECT_TRUE(c.watertight());
    EXPECT_EQ(c.self_intersecting_pairs, 0u);
    EXPECT_NEAR(c.volume, g.volume, 0.005 * g.volume);
    EXPECT_NE(local.nodes.back().reason, JobReason::Fallback) << local.nodes.back().fallback_cause;
  }
}

// A subtree whose solid is empty by its bounds (a leaf weaker than T, a difference or crop of
// one, an intersection of disjoint parts) is no job and nothing under it is: an ffd under a
// difference whose first operand carves was deformed and polygonized (7.4 s) before the
// difference found its result empty. The rule is exact: the field of every node so reported is
// below T at every point sampled, on random trees.
TEST(MeshPlan, SubtreesWhoseSolidIsEmptyByBoundsAreNotMeshed) {
  Builder b(kT);
  std::vector<dvec3> lattice;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) lattice.push_back({-1.0 + 2.4 * i, -1.0 + 2.0 * j, -1.0 + 2.0 * k});
  const NodeId ffd = b.ffd(b.point({0, 0, 0}, {0.8}), {-1, -1, -1}, {1, 1, 1}, {1, 1, 1}, lattice, {0.1});
  const NodeId carve = b.point({0.2, 0, 0}, {0.8, -1.0});
  const Tree t = b.build(b.subtract({carve, ffd}));
  const MeshResult r = mesh_tree(t, at(0.05));
  EXPECT_TRUE(r.mesh->triangles.empty());
  ASSERT_EQ(r.nodes.size(), 1u);  // the ffd and the carving point were no jobs
  EXPECT_EQ(r.nodes[0].strategy, JobStrategy::Empty);
  EXPECT_EQ(r.nodes[0].reason, JobReason::EmptyBounds);
  // A union keeps its other operand's mesh; the weak leaf alone is empty.
  const NodeId ball = b.point({0, 0, 0}, {1.0});
  const Tree u = b.build(b.unite({ball, b.point({0.5, 0, 0}, {0.6, 0.4})}));
  const MeshResult ru = mesh_tree(u, at(0.05)), alone = mesh_tree(b.build(ball), at(0.05));
  EXPECT_EQ(check_mesh(*ru.mesh).triangles, check_mesh(*alone.mesh).triangles);
  EXPECT_TRUE(check_mesh(*ru.mesh).watertight());

  test::Rng rng(0x51d);
  test::RandomTreeOptions o;
  o.max_depth = 3;
  o.meshes = test::small_meshes();
  int empty = 0;
  for (int trial = 0; trial < 200; ++trial) {
    Builder rb(kT);
    const Tree rt = rb.build(test::random_tree(rb, rng, o));
    MeshResult rr;
    try {
      rr = mesh_tree(rt, at(0.1));
    } catch (const PolygonizeError&) {
      continue;
    }
    for (const NodeReport& n : rr.nodes) {
      if (n.strategy != JobStrategy::Empty) continue;
      ++empty;
      const Aabb box = rt.graph().support(n.node, false);
      std::uniform_real_distribution<double> u01(0.0, 1.0);
      for (int i = 0; i < 300; ++i) {
        const dvec3 p = box.finite() ? box.lo + dvec3(u01(rng), u01(rng), u01(rng)) * box.size() : test::random_point(rng, 2.5);
        ASSERT_LT(rt.subtree(n.node).reference(p), kT) << "trial " << trial << " node " << rt.graph().label(n.node);
      }
    }
  }
  std::printf("%d nodes of random trees empty by their bounds\n", empty);
  EXPECT_GT(empty, 5);
}

// From a review of the rule above (scenes in tests/data/stress): a blend of two R-function
// differences, each about 0.586 T everywhere, sums past T far from both, yet its bounds were its
// operands' solids', so an intersection of it with a far ball was called empty (and a union with
// it lost the ball even globally); now that blend is unbounded and its parent, bounded, is
// polygonized. An empty intersection over an ffd beside a ball: the union's local strategy reads
// the intersection's field, so the ffd under the empty job is still prepared (the run failed).
TEST(MeshPlan, EmptyAndUnboundedOperandsKeepTheirParentsRight) {
  const std::filesystem::path dir = std::filesystem::path(HYBRIDTREE_SOURCE_DIR) / "tests/data/stress";
  for (const char* scene : {"blend_of_two_rfunction_differences.json", "union_of_empty_intersection_over_ffd.json"}) {
    const Tree t = load_scene(dir / scene);
    const MeshResult local = mesh_tree(t, at(0.05)), global = mesh_tree(t, at(0.05, MeshStrategy::Global));
    const MeshChecks c = check_mesh(*local.mesh), g = check_mesh(*global.mesh);
    EXPECT_TRUE(c.watertight()) << scene;
    EXPECT_EQ(c.components, g.components) << scene;
    EXPECT_NEAR(c.volume, g.volume, 0.02 * g.volume) << scene;
  }
  const Tree blend = load_scene(dir / "blend_of_two_rfunction_differences.json");
  bool unbounded_operand = false;
  for (const NodeReport& n : mesh_tree(blend, at(0.05)).nodes) unbounded_operand |= n.reason == JobReason::UnboundedOperand;
  EXPECT_TRUE(unbounded_operand);
  // An unprepared ffd's support is a placeholder, not a field reaching everywhere: a blend of
  // two stays bounded (a second review: it lost its default precision and came out empty), and
  // a union over it keeps its local strategy.
  const Tree ffds = load_scene(dir / "blend_of_two_ffds.json");
  EXPECT_TRUE(solid_bounds(ffds.graph(), ffds.root(), ffds.threshold()).finite());
  for (const NodeReport& n : mesh_tree(load_scene(dir / "union_over_blend_of_two_ffds.json"), at(0.05)).nodes)
    EXPECT_NE(n.reason, JobReason::UnboundedOperand) << ffds.graph().label(n.node);
}

// A warped mesh's new vertices go onto the child's surface by Newton steps; where there is no
// surface near (here a field negative everywhere), a step that flies off is not taken and the
// vertex stays at its edge's midpoint, so the refinement is the midpoints' own and ends.
TEST(MeshPlan, WarpRefinementKeepsMidpointsWhereNoSurfaceIsNear) {
  Builder b(kT);
  const Tree ball = b.build(b.point({0, 0, 0}, {1.0}));
  const TriangleMesh sphere = sweep_mesh(ball.graph(), ball.root(), kT, 0.2);
  const Tree carve = b.build(b.point({0, 0, 0}, {1.0, -1.0}));
  const TapeEvaluator nowhere(std::make_shared<const Tape>(compile_tape(carve.graph_ptr(), carve.root(), kT)));
  const auto stretch = [](const glm::dvec3& p) { return dvec3(3.0 * p.x, 1.3 * p.y, p.z); };
  WarpRemeshStats with, without;
  const TriangleMesh projected = warp_mesh(sphere, stretch, &nowhere, kT, 0.05, &with);
  const TriangleMesh midpoints = warp_mesh(sphere, stretch, nullptr, kT, 0.05, &without);
  EXPECT_TRUE(projected.triangles == midpoints.triangles);
  EXPECT_TRUE(projected.positions == midpoints.positions);
  EXPECT_EQ(with.passes, without.passes);
  // Each pass halves the split edges (the warp stretches by at most 3); a quad's diagonal may
  // take one more.
  double longest = 0;
  for (const glm::uvec3& t : sphere.triangles)
    for (int k = 0; k < 3; ++k) longest = std::max(longest, glm::length(sphere.positions[t[k]] - sphere.positions[t[(k + 1) % 3]]));
  EXPECT_LE(with.passes, int(std::ceil(std::log2(3.0 * longest / 0.05))) + 1);
  EXPECT_GT(with.passes, 1);
}

// A twist of a million radians a unit turns a ball about its own axis: the same ball, but its
// sweep mesh's edges between two heights come out across the whole ball at every split, so
// refinement filled 6 GB and ended in std::bad_alloc. It stops at kWarpGrowth times the
// child's triangles (plus a slack) and the node is polygonized: a ball.
TEST(MeshPlan, AWarpThatStretchesWithoutEndIsPolygonized) {
  Builder b(kT);
  const NodeId ball = b.point({0, 0, 0}, {1.0});
  const Tree twisted = b.build(b.twist(ball, Axis::Z, {0, 0, 0}, 1e6));
  const MeshResult r = mesh_tree(twisted, test::mesh_options(0.1));
  const NodeReport& root = r.nodes.back();
  EXPECT_EQ(root.reason, JobReason::Fallback);
  EXPECT_NE(root.fallback_cause.find("the warped mesh would need more than"), std::string::npos) << root.fallback_cause;
  const MeshChecks c = check_mesh(*r.mesh);
  EXPECT_TRUE(c.watertight());
  EXPECT_EQ(c.genus, 0);
  const double r0 = 0.4542;  // the ball's surface at T = 0.5, F = 1
  EXPECT_NEAR(c.volume, 4.0 / 3.0 * 3.14159265358979 * r0 * r0 * r0, 0.03 * c.volume);
  // The cap is also what the run's memory budget has room for (kWarpedBytesPerTriangle a
  // triangle): a twist of rate 1.7e308 stretched every edge past any count its infinite area
  // predicts and filled 4 GB refining. Under 8 MiB the cap is at most 32,768 triangles, less
  // than the area allows here, and the fallback still meshes the ball.
  MeshOptions tight = test::mesh_options(0.1);
  tight.polygonize.memory_budget = std::size_t(8) << 20;
  const MeshResult small = mesh_tree(twisted, tight);
  const std::string& cause = small.nodes.back().fallback_cause;
  const std::size_t at = cause.find("more than ");
  ASSERT_NE(at, std::string::npos) << cause;
  const double cap = std::stod(cause.substr(at + 10));
  EXPECT_EQ(cap, 32768.0) << cause;  // the limit's, not the room left at the moment
  EXPECT_NE(cause.find("(what the memory budget holds)"), std::string::npos) << cause;
  EXPECT_LT(cap, std::stod(root.fallback_cause.substr(root.fallback_cause.find("more than ") + 10))) << cause;
  EXPECT_TRUE(check_mesh(*small.mesh).watertight());
  // The warp alone: the cap is a pass's triangles, never exceeded.
  const TriangleMesh sphere = sweep_mesh(twisted.graph(), ball, kT, 0.1);
  WarpRemeshStats ws;
  const TriangleMesh capped = warp_mesh(sphere, forward_map(twisted.graph(), twisted.root()), nullptr, kT, 0.15, &ws,
                                        nullptr, {}, 10 * sphere.triangles.size());
  EXPECT_TRUE(ws.stopped);
  EXPECT_LE(capped.triangles.size(), 10 * sphere.triangles.size());
  // A coarse mesh leaf scaled at a fine precision refines far past 64 times its triangles, but
  // no further than its area asks: it stays a warped child (a multiple of the child alone sent
  // it to the global polygonizer: three times the triangles, five times the time).
  const TriangleMesh coarse = sweep_mesh(twisted.graph(), ball, kT, 0.4);
  const auto leaf = MeshLeaf::from_triangles(coarse.positions, coarse.triangles, "coarse ball");
  Builder b2(kT);
  const Tree scaled = b2.build(b2.affine(b2.mesh(leaf, {0.1}), glm::scale(glm::dmat4(1.0), glm::dvec3(1.5))));
  const MeshResult s = mesh_tree(scaled, test::mesh_options(0.007));
  EXPECT_NE(s.nodes.back().reason, JobReason::Fallback) << s.nodes.back().fallback_cause;
  EXPECT_GT(s.mesh->triangles.size(), 64 * coarse.triangles.size());
  EXPECT_TRUE(check_mesh(*s.mesh).watertight());
  // Scaled 80 times, the leaf's edges halve until they are 80 times shorter than the limit in
  // its own space: the ffd's tear rule (edges stretched 32 times more than the median are left
  // long) must not stop a uniform stretch, which sent this to the global polygonizer.
  const Tree big = b2.build(b2.affine(b2.mesh(leaf, {0.1}), glm::scale(glm::dmat4(1.0), glm::dvec3(80.0))));
  const MeshResult m = mesh_tree(big, test::mesh_options(2.0));
  EXPECT_EQ(m.nodes.back().strategy, JobStrategy::WarpedChild) << m.nodes.back().fallback_cause;
  EXPECT_GT(m.nodes.back().edges_split, 0u);
  EXPECT_TRUE(check_mesh(*m.mesh).watertight());
}

// Random trees under a stretching warp: the warped child's split edges get midpoints projected
// onto the child's surface, which may land on another sheet where the surface comes near itself
// (random trees found 7 of 150 meshes crossing themselves at h = 0.05). Such a warp's mesh is
// checked and, crossing, polygonized instead: every result is closed and crosses nothing.
TEST(MeshPlan, WarpedRandomTreesNeverCrossThemselves) {
  test::Rng rng(0x3a7f);
  test::RandomTreeOptions o;
  o.max_depth = 3;
  o.meshes = test::small_meshes();
  int checked = 0, overlapped = 0;
  for (int trial = 0; trial < 80; ++trial) {
    Builder b(kT);
    const NodeId child = test::random_tree(b, rng, o);
    const NodeId root =
        trial % 3 == 0 ? b.affine(child, glm::scale(glm::rotate(glm::dmat4(1.0), 0.7, dvec3(1, 2, 3)), dvec3(1.4, 1.0, 0.7)))
        : trial % 3 == 1 ? b.twist(child, Axis::Z, {0, 0, 0}, 1.2)
                         : b.taper(child, Axis::Y, {0, 0, 0}, -1.0, 1.0, 0.6, 1.6);
    const Tree t = b.build(root);
    MeshResult r;
    try {
      r = mesh_tree(t, at(0.05));
    } catch (const PolygonizeError&) {
      continue;  // unbounded solids are refused
    }
    ++checked;
    const MeshChecks c = check_mesh(*r.mesh);
    EXPECT_TRUE(c.watertight()) << "trial " << trial;
    EXPECT_EQ(c.self_intersecting_pairs, 0u) << "trial " << trial;
    for (const NodeReport& n : r.nodes)
      overlapped += n.fallback_cause.starts_with("the warped mesh overlaps itself");
  }
  std::printf("%d warped random trees, %d warped meshes polygonized instead\n", checked, overlapped);
  EXPECT_GT(checked, 60);
  EXPECT_GT(overlapped, 0);  // the check is exercised
}

TEST(MeshPlan, HintsWinOverTheRequest) {
  Builder b(kT);
  const NodeId a = b.point({0, 0, 0}, {1.0});
  const NodeId c = b.point({0.5, 0, 0}, {1.0});
  const NodeId blend = b.blend({a, c});
  const NodeId warped = b.affine(blend, glm::translate(glm::dmat4(1.0), dvec3(1, 0, 0)));
  b.set_mesher(blend, MesherHint::Global);
  const Tree t = b.build(warped);
  const MeshResult r = mesh_tree(t, at(0.04, MeshStrategy::Local));
  EXPECT_TRUE(check_mesh(*r.mesh).watertight());
  ASSERT_EQ(r.nodes.size(), 2u);  // the blend's children need no jobs
  EXPECT_EQ(r.nodes[0].node, blend);
  EXPECT_EQ(r.nodes[0].strategy, JobStrategy::Global);
  EXPECT_EQ(r.nodes[0].reason, JobReason::Hint);
  EXPECT_EQ(r.nodes[1].strategy, JobStrategy::WarpedChild);
}

TEST(MeshPlan, ASharedSubtreeIsMeshedOnce) {
  Builder b(kT);
  const NodeId seg = b.segment({-0.5, 0, 0}, {0.5, 0, 0}, {0.4});
  const NodeId moved = b.affine(seg, glm::translate(glm::dmat4(1.0), dvec3(0, 2, 0)));
  const NodeId root = b.blend({seg, moved});  // seg is read twice: by the blend and by the affine
  const Tree t = b.build(root);
  const MeshResult r = mesh_tree(t, at(0.03));
  std::size_t seg_jobs = 0;
  for (const NodeReport& n : r.nodes) seg_jobs += n.node == seg;
  EXPECT_EQ(seg_jobs, 1u);
  EXPECT_EQ(r.nodes.size(), 3u);
  const MeshChecks c = check_mesh(*r.mesh);
  EXPECT_TRUE(c.watertight());
  EXPECT_EQ(c.components, 2u);
  // Reports come by node id.
  for (std::size_t i = 1; i < r.nodes.size(); ++i) EXPECT_LT(r.nodes[i - 1].node, r.nodes[i].node);
}

TEST(MeshPlan, ProgressRisesToOneAndCancellingThrows) {
  Builder b(kT);
  std::vector<NodeId> parts;
  for (int i = 0; i < 6; ++i) parts.push_back(b.point({1.5 * i, 0, 0}, {1.0}));
  const Tree t = b.build(b.blend(parts));
  MeshOptions o = at(0.02);
  std::vector<double> seen;
  o.progress = [&](double f) { seen.push_back(f); };
  mesh_tree(t, o);
  ASSERT_FALSE(seen.empty());
  EXPECT_TRUE(std::is_sorted(seen.begin(), seen.end()));
  EXPECT_DOUBLE_EQ(seen.back(), 1.0);
  std::atomic<bool> cancel{true};
  o.cancel = &cancel;
  EXPECT_THROW(mesh_tree(t, o), MeshCancelled);
  // A flag raised while the jobs run stops the rest.
  cancel = false;
  o.progress = [&](double f) {
    if (f > 0.2) cancel = true;
  };
  EXPECT_THROW(mesh_tree(t, o), MeshCancelled);
}

TEST(MeshPlan, BlendsAboveTheOverlapThresholdPolygonizeTheirWholeSubtree) {
  Builder b(kT);
  const NodeId inner = b.blend({b.point({0, 0, 0}, {1.0}), b.point({0.2, 0, 0}, {1.0})});  // rho near 0.7
  const NodeId far = b.point({3, 0, 0}, {1.0});
  const NodeId root = b.blend({inner, far});  // disjoint: rho 0
  const Tree t = b.build(root);
  const MeshResult r = mesh_tree(t, at(0.03));
  ASSERT_EQ(r.nodes.size(), 3u);  // inner (global), far (sweep), root (trim)
  for (const NodeReport& n : r.nodes) {
    if (n.node == inner) {
      EXPECT_EQ(n.strategy, JobStrategy::Global);
      EXPECT_EQ(n.reason, JobReason::HighOverlap);
      EXPECT_GT(n.rho, 0.5);
    }
    if (n.node == root) {
      EXPECT_EQ(n.strategy, JobStrategy::TrimBlend);
      EXPECT_EQ(n.reason, JobReason::LowOverlap);
      EXPECT_EQ(n.rho, 0.0);
    }
  }
  // With a threshold above rho the inner blend is trimmed too, and the mesh is still closed.
  MeshOptions o = at(0.03);
  o.blend_overlap = 0.9;
  const MeshResult local = mesh_tree(t, o);
  EXPECT_EQ(local.nodes.size(), 5u);
  EXPECT_TRUE(check_mesh(*local.mesh).watertight());
}

// One budget for the whole run: the stage that would pass it stops before it allocates, and the
// message names it. Each limit is set a byte below what the stage needs on top of the others,
// read from the peak of a run with room to spare.
TEST(MeshPlan, EveryStageTakesFromOneMemoryBudget) {
  Builder b(kT);
  const auto leaf = MeshLeaf::load(test::cgal_mesh("eight.off"));
  const NodeId blob = b.blend({b.point({0, 0, 0}, {0.6}), b.point({0.4, 0, 0}, {0.6})});
  const Tree t = b.build(b.unite({b.mesh(leaf, {0.05}), b.affine(blob, glm::translate(glm::dmat4(1.0), dvec3(3, 0, 0)))}));
  auto run = [&](std::size_t limit, bool quality, MemoryBudget* out = nullptr) {
    MemoryBudget budget(limit);
    MeshOptions o = at(0.03, MeshStrategy::Global);
    o.polygonize.quality.enabled = quality;
    o.polygonize.budget = out ? out : &budget;
    return mesh_tree(t, o);
  };
  auto fails_at = [&](std::size_t limit, bool quality) -> std::string {
    try {
      run(limit, quality);
    } catch (const MemoryBudgetError& e) {
      EXPECT_LE(e.in_use, e.limit);
      return e.what();
    }
    return "no error";
  };
  MemoryBudget roomy(std::size_t(8) << 30);
  const MeshResult r = run(roomy.limit(), true, &roomy);
  ASSERT_GT(r.mesh->triangles.size(), 0u);
  const std::size_t with_quality = roomy.peak();
  MemoryBudget roomy2(std::size_t(8) << 30);
  run(roomy2.limit(), false, &roomy2);
  const std::size_t without = roomy2.peak();
  ASSERT_GT(with_quality, without);
  EXPECT_NE(fails_at(leaf->bytes() - 1, true).find("mesh leaf"), std::string::npos);
  EXPECT_NE(fails_at(with_quality - 1, true).find("quality pass on"), std::string::npos) << fails_at(with_quality - 1, true);
  const std::string grid = fails_at(without - 1, false);
  EXPECT_TRUE(grid.find("bricks the surface crosses") != std::string::npos || grid.find("the mesh of node") != std::string::npos)
      << grid;
  EXPECT_NE(grid.find("already held by this run"), std::string::npos) << grid;  // the leaf, at least
  EXPECT_EQ(fails_at(with_quality, true), "no error");
  // A sweep mesh takes its estimate before it is built.
  Builder b2(kT);
  const Tree ball = b2.build(b2.point({0, 0, 0}, {1.0}));
  MeshOptions o = at(0.001);
  MemoryBudget small(std::size_t(1) << 20);
  o.polygonize.budget = &small;
  try {
    mesh_tree(ball, o);
    ADD_FAILURE() << "a sphere of 10^7 triangles fitted in 1 MiB";
  } catch (const MemoryBudgetError& e) {
    EXPECT_NE(std::string(e.what()).find("the sweep mesh of node"), std::string::npos) << e.what();
    EXPECT_EQ(small.in_use(), 0u);
  }
}

// A job's mesh is held only until the jobs that read it are done: after a run with several
// jobs (a blob meshed, moved, and united with a mesh leaf), the budget holds the leaf and the
// root's mesh alone, while its peak held the intermediate meshes too.
TEST(MeshPlan, IntermediateMeshesAreGivenBackOnceRead) {
  Builder b(kT);
  const auto leaf = MeshLeaf::load(test::cgal_mesh("eight.off"));
  const NodeId blob = b.blend({b.point({0, 0, 0}, {0.6}), b.point({0.4, 0, 0}, {0.6})});
  const Tree t = b.build(b.unite({b.mesh(leaf, {0.05}), b.affine(blob, glm::translate(glm::dmat4(1.0), dvec3(0.9, 0, 0)))}));
  MemoryBudget budget(std::size_t(8) << 30);
  MeshOptions o = at(0.03);
  o.polygonize.budget = &budget;
  const MeshResult r = mesh_tree(t, o);
  std::size_t jobs = 0;
  for (const NodeReport& n : r.nodes) jobs += n.strategy != JobStrategy::SharedLeaf;
  ASSERT_GE(jobs, 3u);  // the blob, its move and the union at least
  const std::size_t root = 24 * r.mesh->positions.size() + 12 * r.mesh->triangles.size();
  EXPECT_EQ(budget.in_use(), leaf->bytes() + root);
  EXPECT_GT(budget.peak(), leaf->bytes() + root);
}

TEST(MeshPlan, MemoryBudgetCountsAndRefuses) {
  MemoryBudget b(1000);
  b.take(600, "a");
  EXPECT_EQ(b.in_use(), 600u);
  EXPECT_THROW(b.take(401, "b"), MemoryBudgetError);
  EXPECT_EQ(b.in_use(), 600u);  // a refused take holds nothing
  {
    const MemoryReservation r(b, 400, "c");
    EXPECT_EQ(b.in_use(), 1000u);
  }
  EXPECT_EQ(b.in_use(), 600u);
  EXPECT_EQ(b.peak(), 1000u);
  EXPECT_THROW(b.take(std::nan(""), "nan"), MemoryBudgetError);
  EXPECT_THROW(b.take(1e30, "huge"), MemoryBudgetError);
  EXPECT_THROW(b.take(-1.0, "negative"), MemoryBudgetError);
  try {
    b.take(2048.0 * 1024 * 1024, "the thing");
  } catch (const MemoryBudgetError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("the thing needs 2.00 GiB, over the memory budget of 1000 bytes", 0), 0u) << e.what();
  }
}

TEST(MeshPlan, CoarseGlobalGridsAreRefinedUntilTheMeshIsClean) {
  // 900 primitives, many thinner than a cell at these precisions (the scene's default is 0.3006):
  // the first grid's repair steps may leave folds; whatever the tries, the mesh returned is
  // watertight and free of self-intersections, and each refinement says what it fixed.
  Builder b(kT);
  const Tree t = optimize(b.build(scenes::scatter(b)));
  for (double h : {0.3006, 0.32}) {
    const MeshResult r = mesh_tree(t, at(h));
    const MeshChecks c = check_mesh(*r.mesh);
    EXPECT_TRUE(c.watertight()) << h;
    EXPECT_EQ(c.self_intersecting_pairs, 0u) << h;
    ASSERT_EQ(r.nodes.size(), 1u);
    EXPECT_LE(r.nodes[0].refinements.size(), std::size_t(kRefinements));
    for (const std::string& why : r.nodes[0].refinements) EXPECT_NE(why.find("precision "), std::string::npos) << why;
  }
}
