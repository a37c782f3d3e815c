// The optimizer (runtime/optimize.hpp): on random trees (every kind but ffd, every Boolean mode,
// nested warps, mesh leaves) and on the example scenes the optimized field equals the original
// through both engines and after a round trip through the scene writer; meshes keep their
// topology and volume; each rule fires where it should and says what it saved.
#include "meshers/mesh_checks.hpp"
#include "meshers/mesh_plan.hpp"
#include "nodes/mesh_leaf.hpp"
#include "runtime/builder.hpp"
#include "runtime/optimize.hpp"
#include "runtime/scene.hpp"
#include "runtime/scene_write.hpp"
#include "runtime/tape.hpp"
#include "runtime/tape_eval.hpp"
#include "runtime/tree_eval.hpp"
#include "tests/support/random_tree.hpp"
#include "tools/scenes.hpp"

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

using namespace ht;
using glm::dvec3;

namespace {

constexpr double kT = 0.5;

bool near(double a, double b) { return std::abs(a - b) <= 1e-4 * std::max(1.0, std::abs(a)); }

// The reference fields of two trees agree at points in `box` (and a margin around it); the
// tapes too, but for rare points at a kink, where float rounding picks the other branch.
void expect_same_field(const Tree& a, const Tree& b, const Aabb& box, test::Rng& rng, int count, const std::string& what) {
  std::uniform_real_distribution<double> u(-0.1, 1.1);
  std::vector<dvec3> pts(static_cast<std::size_t>(count));
  for (auto& p : pts) p = box.lo + dvec3(u(rng), u(rng), u(rng)) * box.size();
  std::vector<double> ra(pts.size()), rb(pts.size()), ta(pts.size()), tb(pts.size());
  a.reference(pts, ra);
  b.reference(pts, rb);
  a.field(pts, ta);
  b.field(pts, tb);
  std::size_t tape_off = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    ASSERT_TRUE(near(ra[i], rb[i])) << what << " point " << pts[i].x << " " << pts[i].y << " " << pts[i].z << ": " << ra[i]
                                    << " vs " << rb[i];
    tape_off += near(ta[i], tb[i]) ? 0 : 1;
  }
  EXPECT_LE(tape_off, pts.size() / 500) << what;
}

Aabb solid_box(const Tree& t) {
  Aabb box = t.graph().support(t.root(), false);
  if (!box.finite()) box = {dvec3(-2.5), dvec3(2.5)};
  return box;
}

}  // namespace

TEST(Optimize, RandomTreesKeepTheirFieldThroughBothEnginesAndTheWriter) {
  test::Rng rng(81);
  test::RandomTreeOptions opt;
  opt.meshes = test::small_meshes();
  const auto dir = test::temp_dir("optimize-random");
  for (int trial = 0; trial < 300; ++trial) {
    SCOPED_TRACE(trial);
    Builder b(kT);
    const NodeId root = test::random_tree(b, rng, opt);
    const Tree t = b.build(root);
    OptimizeStats s;
    const Tree o = optimize(t, {}, &s);
    EXPECT_LE(s.nodes_after, 2 * s.nodes_before + 4);  // pushed warps copy themselves, a few at most
    expect_same_field(t, o, solid_box(t), rng, 200, "optimized");
    // The rewritten scene reads back into the same tree.
    const Tree back = load_scene_text(write_scene_text(o, dir), dir, "round trip");
    expect_same_field(o, back, solid_box(t), rng, 50, "round trip");
    if (HasFatalFailure()) return;
  }
  std::filesystem::remove_all(dir);
}

TEST(Optimize, ExampleScenesKeepTheirFieldTopologyAndVolume) {
  test::Rng rng(82);
  const auto examples = std::filesystem::path(HYBRIDTREE_SOURCE_DIR) / "examples";
  const auto dir = test::temp_dir("optimize-examples");
  const bool igea = std::filesystem::exists(std::filesystem::path(HYBRIDTREE_SOURCE_DIR) / "data/meshes/igea-67k.ply");
  for (const char* name : {"bunny_ear.json", "bunny_garden.json", "carved_box.json", "winged_bunny.json", "bowl.json",
                           "restoration.json", "local_blend.json"}) {
    SCOPED_TRACE(name);
    if (!igea && (std::string(name) == "bowl.json" || std::string(name) == "restoration.json")) {
      std::printf("skipping %s: no igea-67k.ply in data/meshes/\n", name);
      continue;
    }
    const Tree t = load_scene(examples / name);
    const Tree o = optimize(t);
    expect_same_field(t, o, solid_box(t), rng, 2000, name);
    const Tree back = load_scene_text(write_scene_text(o, dir), dir, "round trip");
    expect_same_field(t, back, solid_box(t), rng, 500, std::string(name) + " round trip");
    const double h = t.mesher_settings().precision;
    const MeshChecks a = check_mesh(*mesh_tree(t, test::mesh_options(h)).mesh);
    const MeshChecks c = check_mesh(*mesh_tree(o, test::mesh_options(h)).mesh);
    EXPECT_TRUE(c.watertight());
    EXPECT_EQ(c.components, a.components);
    EXPECT_EQ(c.genus, a.genus);
    EXPECT_NEAR(c.volume, a.volume, 0.005 * std::abs(a.volume));
  }
  std::filesystem::remove_all(dir);
}

TEST(Optimize, FlatteningMakesOneBlendOfAChain) {
  Builder b(kT);
  const NodeId chain = scenes::scatter(b, 200, 3);
  const Tree t = b.build(chain);
  OptimizeOptions flat_only;
  flat_only.regroup = false;
  OptimizeStats s;
  const Tree o = optimize(t, flat_only, &s);
  EXPECT_EQ(s.flattened, 198u);  // 199 binary blends, one left
  EXPECT_EQ(o.graph().kind[o.root()], NodeKind::Blend);
  EXPECT_EQ(o.graph().child_count[o.root()], 200u);
  EXPECT_LT(s.nodes_after, s.nodes_before);
}

TEST(Optimize, RegroupingMakesGuardedGroupsAndFasterTapes) {
  Builder b(kT);
  const Tree t = b.build(scenes::scatter(b, 900, 1));
  OptimizeStats s;
  const Tree o = optimize(t, {}, &s);
  EXPECT_GT(s.groups, 100u);
  const Tape before = compile_tape(t.graph_ptr(), t.root(), kT), after = compile_tape(o.graph_ptr(), o.root(), kT);
  EXPECT_LT(before.skips, 10u) << "random order: hardly a prefix of the chain is small";
  EXPECT_GT(after.skips, 100u);
  EXPECT_EQ(after.leaf_count(), before.leaf_count());
  // The folded affines are instructions saved; the guards cost one each.
  EXPECT_EQ(after.size() + s.affines_folded, before.size() - before.skips + after.skips);
}

TEST(Optimize, AffinesComposeFoldIntoPrimitivesAndPushDown) {
  Builder b(kT);
  const glm::dmat4 m = glm::rotate(glm::translate(glm::dmat4(1.0), {1, 2, 3}), 0.7, dvec3(1, 1, 0)) *
                       glm::scale(glm::dmat4(1.0), dvec3(1.5));
  const NodeId seg = b.affine(b.segment({0, 0, 0}, {1, 0, 0}, {0.5, 1.0}), m);
  const NodeId twice = b.affine(b.affine(b.mesh(test::small_meshes()[0], {0.2, 1.0}), m), glm::translate(glm::dmat4(1.0), {0.5, 0, 0}));
  const NodeId leaf = b.mesh(test::small_meshes()[1], {0.2, 1.0});
  const NodeId pushed = b.affine(b.blend({leaf, b.point({0, 0, 0}, {0.6, 1.0})}), m);
  const NodeId stretched = b.affine(b.box({0, 0, 0}, {1, 1, 1}, {0.3, 1.0}), glm::scale(glm::dmat4(1.0), dvec3(1, 2, 1)));
  const Tree t = b.build(b.blend({seg, twice, pushed, stretched}));
  OptimizeStats s;
  const Tree o = optimize(t, {}, &s);
  EXPECT_EQ(s.affines_composed, 1u);
  EXPECT_GE(s.affines_folded, 2u);  // the segment, the point
  EXPECT_EQ(s.warps_pushed, 1u);
  std::size_t affines = 0;
  for (NodeId n = 0; n < o.graph().size(); ++n) affines += o.graph().kind[n] == NodeKind::Affine;
  EXPECT_EQ(affines, 3u);  // above each mesh leaf, and the box stretched unevenly
  test::Rng rng(83);
  expect_same_field(t, o, solid_box(t), rng, 4000, "affines");
}

TEST(Optimize, IdenticalSubtreesMergeAndZerosArePruned) {
  Builder b(kT);
  auto arm = [&] { return b.twist(b.blend({b.segment({0, 0, 0}, {1, 0, 0}, {0.4}), b.point({1, 0, 0}, {0.5})}), Axis::X, {0, 0, 0}, 0.3); };
  // Disjoint non-negative operands: the intersection is 0 everywhere.
  const NodeId never = b.intersect({b.point({5, 0, 0}, {0.5}), b.point({-5, 0, 0}, {0.5})}, BooleanMode::MinMax);
  const NodeId missed = b.crop(b.point({0, 9, 0}, {0.5}), {-1, -1, -1}, {1, 1, 1});
  const NodeId single = b.blend({b.point({0, -1, 0}, {0.5})});
  const Tree t = b.build(b.blend({arm(), arm(), never, missed, single}));
  OptimizeStats s;
  const Tree o = optimize(t, {}, &s);
  EXPECT_GE(s.merged, 3u);   // the second arm's segment, point, blend and twist
  EXPECT_EQ(s.pruned, 2u);   // the intersection and the crop
  EXPECT_GE(s.flattened, 1u);  // the one-child blend's term joins the root's
  EXPECT_EQ(s.nodes_before, 16u);
  EXPECT_LE(s.nodes_after, 7u);  // one arm (its twist pushed onto its two leaves), the single point, the root
  test::Rng rng(84);
  expect_same_field(t, o, Aabb{dvec3(-6), dvec3(6)}, rng, 4000, "merged and pruned");
}

TEST(Optimize, BooleansKeepTheirMeaningWhenTheyLeaveABlend) {
  // union(auto) under a one-operand blend means R-functions; folding the blend away puts the
  // union at the root, where auto would mean min/max: it must say rfunction.
  Builder b(kT);
  const NodeId u = b.unite({b.point({0, 0, 0}, {1.0}), b.point({0.8, 0, 0}, {1.0})});
  const NodeId top = b.blend({u});
  b.set_name(u, "u");
  const Tree t = b.build(top);
  OptimizeStats s;
  const Tree o = optimize(t, {}, &s);
  EXPECT_EQ(s.folded, 1u);
  EXPECT_EQ(o.graph().kind[o.root()], NodeKind::Union);
  EXPECT_EQ(o.graph().boolean[o.root()], BooleanMode::RFunction);
  test::Rng rng(85);
  expect_same_field(t, o, solid_box(t), rng, 2000, "context");
  // And in a blend it stays auto.
  Builder c(kT);
  const NodeId v = c.unite({c.point({0, 0, 0}, {1.0}), c.point({0.8, 0, 0}, {1.0})});
  const Tree t2 = c.build(c.blend({v, c.point({3, 0, 0}, {1.0})}));
  const Tree o2 = optimize(t2);
  for (NodeId n = 0; n < o2.graph().size(); ++n) {
    if (o2.graph().kind[n] == NodeKind::Union) {
      EXPECT_EQ(o2.graph().boolean[n], BooleanMode::Auto);
    }
  }
}

TEST(Optimize, CommandLineWritesTheRewrittenSceneAndEvaluatesTheSame) {
  const auto dir = test::temp_dir("optimize-cli");
  const std::string scene = (std::filesystem::path(HYBRIDTREE_SOURCE_DIR) / "examples" / "bunny_garden.json").string();
  const std::string out = (dir / "opt.json").string();
  const auto r = test::run_cli("optimize " + scene + " -o " + out);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("optimizer "), std::string::npos) << r.out;
  const std::string points = "0 0 0\n0.1 0.2 -0.3\n-0.4 0.1 0.2\n0.3 -0.2 0.1\n";
  const auto a = test::run_cli("eval " + scene + " --no-optimize", points);
  const auto b = test::run_cli("eval " + out + " --no-optimize", points);
  const auto c = test::run_cli("eval " + scene, points);
  ASSERT_EQ(a.code, 0) << a.err;
  ASSERT_EQ(b.code, 0) << b.err;
  std::istringstream sa(a.out), sb(b.out), sc(c.out);
  double va, vb, vc;
  int rows = 0;
  while (sa >> va && sb >> vb && sc >> vc) {
    EXPECT_TRUE(near(va, vb)) << va << " vs " << vb;
    EXPECT_TRUE(near(va, vc)) << va << " vs " << vc;
    ++rows;
  }
  EXPECT_EQ(rows, 4);
  const auto info = test::run_cli("info " + scene);
  EXPECT_NE(info.out.find("optimizer      "), std::string::npos) << info.out;
  EXPECT_EQ(test::run_cli("info " + scene + " --no-optimize").out.find("optimizer "), std::string::npos);
  // A bad scene: exit 2, no file.
  const std::string bad = (dir / "bad.json").string();
  { std::ofstream(bad) << R"({"hybridtree": 1, "root": {"type": "point", "center": [0, 0, 0], "radius": -1}})"; }
  const auto f = test::run_cli("optimize " + bad + " -o " + (dir / "none.json").string());
  EXPECT_EQ(f.code, 2);
  EXPECT_NE(f.err.find("root.radius"), std::string::npos) << f.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "none.json"));
  std::filesystem::remove_all(dir);
}

TEST(Optimize, GroupsDoNotChangeTheMeshPlan) {
  // The 250-curve snake is one blend of 250 operands: polygonized whole. Regrouped into blends of
  // 4, the plan still counts 250 (meshers/mesh_plan.cpp), so the job and the mesh stay the same.
  Builder b(kT);
  const Tree t = b.build(scenes::snake(b, 250, 1));
  OptimizeStats s;
  const Tree o = optimize(t, {}, &s);
  ASSERT_GT(s.groups, 10u);
  const MeshResult a = mesh_tree(t, test::mesh_options(0.15)), c = mesh_tree(o, test::mesh_options(0.15));
  ASSERT_EQ(a.nodes.size(), 1u);
  ASSERT_EQ(c.nodes.size(), 1u);
  EXPECT_EQ(c.nodes[0].strategy, JobStrategy::Global);
  EXPECT_EQ(c.nodes[0].reason, JobReason::NoLocalMethod);
  const MeshChecks ca = check_mesh(*a.mesh), cc = check_mesh(*c.mesh);
  EXPECT_EQ(cc.genus, ca.genus);
  EXPECT_NEAR(cc.volume, ca.volume, 1e-3 * ca.volume);
}

TEST(Optimize, BigOperandsRewrittenAsTasksGiveTheSameGraphAtAnyThreadCount) {
  Builder b(kT);
  std::vector<NodeId> parts;
  for (int i = 0; i < 3; ++i)
    parts.push_back(b.affine(scenes::scatter(b, 300, 10 + std::uint64_t(i)), glm::translate(glm::dmat4(1.0), {30.0 * i, 0, 0})));
  parts.push_back(parts[0]);  // shared: rewritten once or twice, one node either way
  const Tree t = b.build(b.blend(parts));
  auto same = [](const Graph& x, const Graph& y) {
    return x.kind == y.kind && x.boolean == y.boolean && x.params == y.params && x.children == y.children &&
           x.child_count == y.child_count;
  };
  OptimizeOptions serial;
  serial.parallel = false;
  const Tree one = optimize(t, serial);
  for (int threads : {1, 2, 4}) {
    tbb::task_arena arena(threads);
    OptimizeStats s;
    const Tree o = arena.execute([&] { return optimize(t, {}, &s); });
    EXPECT_EQ(s.tasks, 3u);
    EXPECT_TRUE(same(o.graph(), one.graph())) << threads << " threads";
    EXPECT_EQ(o.root(), one.root());
  }
  test::Rng rng(86);
  expect_same_field(t, one, solid_box(t), rng, 2000, "tasks");
}
