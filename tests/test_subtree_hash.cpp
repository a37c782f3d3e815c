// Content hashes of subtrees (runtime/subtree_hash.hpp): equal for identical subtrees wherever
// they sit, different after any edit that changes meaning, and the same on every run.
#include "nodes/mesh_leaf.hpp"
#include "runtime/builder.hpp"
#include "runtime/subtree_hash.hpp"
#include "tests/support/random_tree.hpp"

#include <gtest/gtest.h>

using namespace ht;
using glm::dvec3;

namespace {

constexpr double kT = 0.5;

std::uint64_t root_hash(const Tree& t) { return subtree_hashes(t.graph(), t.threshold()).alone[t.root()]; }

// Is `n` an ancestor-or-self of `target` in g?
bool reaches(const Graph& g, NodeId n, NodeId target) {
  if (n == target) return true;
  for (NodeId c : g.children_of(n))
    if (reaches(g, c, target)) return true;
  return false;
}

TEST(SubtreeHash, IdenticalRandomTreesHashEqualWhateverTheirIds) {
  test::RandomTreeOptions o;
  o.meshes = test::small_meshes();
  for (int seed = 0; seed < 40; ++seed) {
    test::Rng r1(seed), r2(seed);
    Builder a(kT), b(kT);
    b.point(dvec3(9), {1.0, 1.0});  // shifts every id in b
    b.segment(dvec3(0), dvec3(1), {2.0, 1.0});
    const Tree ta = a.build(test::random_tree(a, r1, o));
    const Tree tb = b.build(test::random_tree(b, r2, o));
    ASSERT_NE(ta.root(), tb.root());
    EXPECT_EQ(root_hash(ta), root_hash(tb)) << "seed " << seed;
  }
}

TEST(SubtreeHash, ANudgedParameterChangesItsNodeAndAncestorsOnly) {
  Builder b(kT);
  const NodeId p = b.point(dvec3(0), {1.0, 1.0});
  const NodeId q = b.point(dvec3(1, 0, 0), {1.0, 1.0});
  const NodeId s = b.segment(dvec3(0, 1, 0), dvec3(0, 2, 0), {1.0, 1.0});
  const NodeId root = b.blend({b.unite({p, q}), s});
  const Tree t0 = b.build(root);
  Builder e(kT);
  const NodeId p2 = e.point(dvec3(0), {1.0, 1.0});
  const NodeId q2 = e.point(dvec3(1, 0, 0), {std::nextafter(1.0, 2.0), 1.0});  // one ulp
  const NodeId s2 = e.segment(dvec3(0, 1, 0), dvec3(0, 2, 0), {1.0, 1.0});
  const NodeId u2 = e.unite({p2, q2});
  const Tree t1 = e.build(e.blend({u2, s2}));
  const SubtreeHashes h0 = subtree_hashes(t0.graph(), kT), h1 = subtree_hashes(t1.graph(), kT);
  EXPECT_EQ(h0.alone[p], h1.alone[p2]);
  EXPECT_EQ(h0.alone[s], h1.alone[s2]);
  EXPECT_NE(h0.alone[q], h1.alone[q2]);
  EXPECT_NE(h0.alone[root], h1.alone[t1.root()]);
  EXPECT_NE(h0.alone[t0.graph().children_of(root)[0]], h1.alone[u2]);
}

TEST(SubtreeHash, RandomNudgesChangeExactlyTheAncestors) {
  for (int seed = 0; seed < 30; ++seed) {
    test::Rng rng(seed);
    Builder b(kT);
    const Tree t = b.build(test::random_tree(b, rng, {}));
    Graph edited = t.graph();
    const NodeId victim = static_cast<NodeId>(rng() % edited.size());
    if (edited.param_count[victim] == 0) continue;
    edited.params[edited.param_begin[victim]] += 1e-9;
    const SubtreeHashes h0 = subtree_hashes(t.graph(), kT), h1 = subtree_hashes(edited, kT);
    for (NodeId n = 0; n < edited.size(); ++n) {
      if (reaches(edited, n, victim))
        EXPECT_NE(h0.alone[n], h1.alone[n]) << "seed " << seed << " node " << n;
      else
        EXPECT_EQ(h0.alone[n], h1.alone[n]) << "seed " << seed << " node " << n;
    }
  }
}

TEST(SubtreeHash, ModeHintThresholdAndChildOrderCount) {
  auto two = [](double t, BooleanMode mode, bool swap) {
    Builder b(t);
    const NodeId p = b.point(dvec3(0), {1.0, 1.0});
    const NodeId q = b.point(dvec3(1, 0, 0), {1.0, 1.0});
    const Tree tree = b.build(swap ? b.subtract({q, p}, mode) : b.subtract({p, q}, mode));
    return subtree_hashes(tree.graph(), t).alone[tree.root()];
  };
  const std::uint64_t base = two(kT, BooleanMode::Auto, false);
  EXPECT_EQ(base, two(kT, BooleanMode::Auto, false));
  EXPECT_NE(base, two(0.25, BooleanMode::Auto, false));
  EXPECT_NE(base, two(kT, BooleanMode::Auto, true));
  EXPECT_NE(base, two(kT, BooleanMode::RFunction, false));
}

TEST(SubtreeHash, AutoBooleansHashByTheirResolvedRule) {
  Builder b(kT);
  const NodeId p = b.point(dvec3(0), {1.0, 1.0});
  const NodeId q = b.point(dvec3(1, 0, 0), {1.0, 1.0});
  const NodeId u = b.unite({p, q});
  const NodeId m = b.unite({p, q}, BooleanMode::MinMax);
  const Tree t = b.build(b.blend({u, m}));
  const SubtreeHashes h = subtree_hashes(t.graph(), kT);
  EXPECT_EQ(h.alone[p], h.blended[p]);        // a primitive means the same either way
  EXPECT_NE(h.alone[u], h.blended[u]);        // auto: min/max alone, R-functions under a blend
  EXPECT_EQ(h.alone[m], h.blended[m]);        // an explicit mode does not depend on context
  EXPECT_NE(h.alone[u], h.alone[m]);          // the mode itself is hashed
}

TEST(SubtreeHash, MeshLeavesHashByContentsNotPath) {
  const auto& meshes = test::small_meshes();
  const auto again = MeshLeaf::from_triangles(meshes[0]->positions(), meshes[0]->triangles(), "elsewhere");
  EXPECT_EQ(mesh_contents_hash(*meshes[0]), mesh_contents_hash(*again));
  EXPECT_NE(mesh_contents_hash(*meshes[0]), mesh_contents_hash(*meshes[1]));
  auto moved = meshes[0]->positions();
  moved[3].x = std::nextafter(moved[3].x, 1e9);
  const auto nudged = MeshLeaf::from_triangles(moved, meshes[0]->triangles(), "nudged");
  EXPECT_NE(mesh_contents_hash(*meshes[0]), mesh_contents_hash(*nudged));
  Builder b1(kT), b2(kT);
  const Tree t1 = b1.build(b1.mesh(meshes[0], {1.0, 1.0}));
  const Tree t2 = b2.build(b2.mesh(again, {1.0, 1.0}));
  EXPECT_EQ(root_hash(t1), root_hash(t2));
}

TEST(SubtreeHash, IsTheSameOnEveryRunAndMachine) {
  // Pinned: a change to the hash (or to what it covers) must bump the disk cache's format
  // version (tools/), since keys on disk are built from it.
  EXPECT_EQ(hash_bytes(0, "HybridTree", 10), 13429594851879167969ull);
  Builder b(kT);
  const Tree t = b.build(b.blend({b.point(dvec3(0), {1.0, 1.0}), b.segment(dvec3(0), dvec3(1, 0, 0), {1.5, 2.0})}));
  EXPECT_EQ(root_hash(t), 8990707668792414656ull);
}

}  // namespace
