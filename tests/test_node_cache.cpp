// The node-result cache (meshers/node_cache.hpp) in the mesh plan: after random edits on random
// trees, meshing with a cache filled before the edit gives the from-scratch mesh byte for byte,
// reuses the unchanged jobs and never an edited one.
#include "meshers/mesh_plan.hpp"
#include "meshers/node_cache.hpp"
#include "meshers/polygonize.hpp"
#include "runtime/builder.hpp"
#include "tests/support/random_tree.hpp"

#include <gtest/gtest.h>

using namespace ht;
using glm::dvec3;

namespace {

constexpr double kT = 0.5;

bool reaches(const Graph& g, NodeId n, NodeId target) {
  if (n == target) return true;
  for (NodeId c : g.children_of(n))
    if (reaches(g, c, target)) return true;
  return false;
}

// unite(A, B) of two random trees; `b_seed` picks B.
struct Scene {
  Tree tree;
  NodeId b_root;
};
Scene two_trees(int a_seed, int b_seed) {
  test::Rng ra(a_seed), rb(b_seed);
  test::RandomTreeOptions o;
  o.max_depth = 3;
  Builder b(kT);
  const NodeId a = test::random_tree(b, ra, o);
  const NodeId r = test::random_tree(b, rb, o);
  return {b.build(b.unite({a, r})), r};
}

// The same tree with one primitive's radius R scaled (ids unchanged).
Tree nudged(const Tree& t, NodeId victim) {
  auto g = std::make_shared<Graph>(t.graph());
  g->params[g->param_begin[victim]] *= 1.03;
  compute_supports(*g);
  return Tree(g, t.root(), t.threshold());
}

std::optional<MeshResult> try_mesh(const Tree& t, NodeCache* cache) {
  MeshOptions o = test::mesh_options(0.12);
  o.cache = cache;
  try {
    return mesh_tree(t, o);
  } catch (const PolygonizeError&) {  // an unbounded or empty random solid
    return std::nullopt;
  }
}

struct Tally {
  int compared = 0, with_hits = 0;
};

// Meshes `before` into a cache, then `after` with it and from scratch; `edited` and its
// ancestors must not be reused.
void check_edit(const Tree& before, const Tree& after, NodeId edited, Tally& tally, std::size_t bytes = 1u << 30) {
  NodeCache cache(bytes);
  if (!try_mesh(before, &cache)) return;
  const auto scratch = try_mesh(after, nullptr);
  const auto incremental = try_mesh(after, &cache);
  ASSERT_EQ(scratch.has_value(), incremental.has_value());
  if (!scratch) return;
  ++tally.compared;
  ASSERT_TRUE(test::same_bytes(*scratch->mesh, *incremental->mesh));
  bool hit = false;
  for (const NodeReport& r : incremental->nodes) {
    if (r.reused) {
      EXPECT_FALSE(reaches(after.graph(), r.node, edited)) << after.graph().label(r.node);
    }
    hit = hit || r.reused;
    EXPECT_FALSE(scratch->nodes[&r - incremental->nodes.data()].reused);
  }
  tally.with_hits += hit;
}

TEST(NodeCache, ParameterNudgesReuseTheRestByteForByte) {
  Tally tally;
  for (int seed = 0; seed < 24; ++seed) {
    const Scene s = two_trees(100 + seed, 200 + seed);
    const Graph& g = s.tree.graph();
    NodeId victim = kNone;
    for (NodeId n = s.b_root + 1; n-- > 0;)
      if (reaches(g, s.b_root, n) && kind_family(g.kind[n]) == Family::Primitive && g.kind[n] != NodeKind::Curve) {
        victim = n;
        break;
      }
    if (victim == kNone) continue;
    check_edit(s.tree, nudged(s.tree, victim), victim, tally);
  }
  EXPECT_GE(tally.compared, 8);
  EXPECT_GE(tally.with_hits, tally.compared / 3) << "the unchanged subtree was hardly ever reused";
}

TEST(NodeCache, SubtreeSwapsReuseTheRestByteForByte) {
  Tally tally;
  for (int seed = 0; seed < 24; ++seed) {
    const Scene before = two_trees(300 + seed, 400 + seed);
    const Scene after = two_trees(300 + seed, 500 + seed);
    check_edit(before.tree, after.tree, after.b_root, tally);
  }
  EXPECT_GE(tally.compared, 8);
  EXPECT_GE(tally.with_hits, tally.compared / 3);
}

TEST(NodeCache, MeshLeafChangesAreNotReused) {
  const auto& meshes = test::small_meshes();
  auto scene = [&](int leaf) {
    Builder b(kT);
    const NodeId p = b.segment(dvec3(-1, 0, 0), dvec3(1, 0, 0), {0.5, 1.0});
    const NodeId m = b.mesh(meshes[leaf], {0.05, 1.0});
    const NodeId w = b.affine(m, glm::dmat4(1.0));
    return Scene{b.build(b.unite({p, w})), m};
  };
  Tally tally;
  check_edit(scene(0).tree, scene(1).tree, scene(1).b_root, tally);
  EXPECT_EQ(tally.compared, 1);
  EXPECT_EQ(tally.with_hits, 1);  // the segment's sweep
}

TEST(NodeCache, IdenticalSubtreesShareOneEntry) {
  Builder b(kT);
  const NodeId p = b.segment(dvec3(-1, 0, 0), dvec3(1, 0, 0), {0.4, 1.0});
  const NodeId q = b.segment(dvec3(-1, 0, 0), dvec3(1, 0, 0), {0.4, 1.0});  // the same, another id
  const Tree t = b.build(b.unite({b.affine(p, glm::dmat4(1.0)), q}));
  NodeCache cache(1u << 30);
  const auto first = try_mesh(t, &cache);
  ASSERT_TRUE(first);
  // Four jobs (two sweeps, the warp, the union), three keys: p's and q's sweeps are one entry.
  // (Within one run the two sweeps may run at once, so both run; the entry is shared after.)
  EXPECT_EQ(first->nodes.size(), 4u);
  EXPECT_EQ(cache.stats().entries, 3u);
  Builder other(kT);
  other.point(dvec3(5), {1.0, 1.0});  // another id
  const Tree alone = other.build(other.segment(dvec3(-1, 0, 0), dvec3(1, 0, 0), {0.4, 1.0}));
  const auto again = try_mesh(alone, &cache);
  ASSERT_TRUE(again);
  ASSERT_EQ(again->nodes.size(), 1u);
  EXPECT_TRUE(again->nodes[0].reused);
  EXPECT_TRUE(test::same_bytes(*again->mesh, *try_mesh(alone, nullptr)->mesh));
}

TEST(NodeCache, EvictionUnderATinyBoundKeepsResultsIdentical) {
  Tally tally;
  for (int seed = 0; seed < 10; ++seed) {
    const Scene before = two_trees(600 + seed, 700 + seed);
    const Scene after = two_trees(600 + seed, 800 + seed);
    check_edit(before.tree, after.tree, after.b_root, tally, 4096);
  }
  EXPECT_GE(tally.compared, 4);
  NodeCache cache(4096);
  const Scene s = two_trees(600, 700);
  try_mesh(s.tree, &cache);
  EXPECT_LE(cache.stats().bytes, 4096u);
}

TEST(NodeCache, LeastRecentlyUsedGoesFirst) {
  NodeCache cache(2 * 3 * NodeCache::entry_bytes(CachedJob{}));  // half of the bound is for pieces
  for (std::uint64_t k = 1; k <= 3; ++k) cache.insert(k, CachedJob{});
  ASSERT_TRUE(cache.find(1));  // 2 is now the oldest
  cache.insert(4, CachedJob{});
  EXPECT_TRUE(cache.find(1));
  EXPECT_FALSE(cache.find(2));
  EXPECT_TRUE(cache.find(3));
  EXPECT_TRUE(cache.find(4));
  EXPECT_EQ(cache.stats().evictions, 1u);
}

}  // namespace
