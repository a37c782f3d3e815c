// Parts of global polygonizations kept across runs (meshers/piece_cache.hpp, issue 15): bricks
// and quality-pass slabs and bands. After edits, a polygonization that takes its unchanged parts
// from the cache, in memory or from files, gives the from-scratch mesh byte for byte, and does
// take them.
#include "meshers/disk_cache.hpp"
#include "meshers/mesh_plan.hpp"
#include "meshers/node_cache.hpp"
#include "meshers/piece_cache.hpp"
#include "meshers/polygonize.hpp"
#include "meshers/quality.hpp"
#include "runtime/builder.hpp"
#include "runtime/scene.hpp"
#include "runtime/tree_eval.hpp"
#include "tests/support/random_tree.hpp"
#include "tools/scenes.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <string>
#include <utility>
#include <optional>

using namespace ht;
using glm::dvec3;

namespace {

constexpr double kT = 0.5;

std::optional<MeshResult> try_mesh(const Tree& t, NodeCache* cache, double h) {
  MeshOptions o = test::mesh_options(h, MeshStrategy::Global);
  o.cache = cache;
  try {
    return mesh_tree(t, o);
  } catch (const PolygonizeError&) {  // an unbounded or empty random solid
    return std::nullopt;
  }
}

struct Reuse {
  std::size_t bricks = 0, active = 0, pieces = 0, pieces_reused = 0;
};

Reuse reuse_of(const MeshResult& r) {
  Reuse out;
  for (const NodeReport& n : r.nodes) {
    out.bricks += n.polygonize.bricks_reused;
    out.active += n.polygonize.bricks_active;
    out.pieces += n.polygonize.quality.pieces;
    out.pieces_reused += n.polygonize.quality.pieces_reused;
  }
  return out;
}

// Meshes `before` into a cache, then `after` with that cache and from scratch: the same bytes.
// Returns what the incremental run reused (nothing when a solid could not be meshed).
Reuse check_edit(const Tree& before, const Tree& after, double h, std::size_t bytes = std::size_t(1) << 30) {
  NodeCache cache(bytes);
  if (!try_mesh(before, &cache, h)) return {};
  const auto scratch = try_mesh(after, nullptr, h);
  const auto incremental = try_mesh(after, &cache, h);
  EXPECT_EQ(scratch.has_value(), incremental.has_value());
  if (!scratch || !incremental) return {};
  EXPECT_TRUE(test::same_bytes(*scratch->mesh, *incremental->mesh));
  EXPECT_EQ(reuse_of(*scratch).bricks, 0u);
  return reuse_of(*incremental);
}

// The tree with primitive `victim`'s parameter `at` (from its first) moved by `by` (ids unchanged).
Tree nudged(const Tree& t, NodeId victim, std::size_t at, double by) {
  auto g = std::make_shared<Graph>(t.graph());
  g->params[g->param_begin[victim] + at] += by;
  compute_supports(*g);
  return Tree(g, t.root(), t.threshold());
}

TEST(PieceCache, FindsOnlyTheTypeStoredAndEvictsTheOldest) {
  PieceCache cache(300);
  cache.insert<int>(1, std::make_shared<const int>(10), 100);
  cache.insert<double>(2, std::make_shared<const double>(2.5), 100);
  EXPECT_EQ(cache.find<double>(1), nullptr);  // stored as an int
  ASSERT_NE(cache.find<int>(1), nullptr);     // 2 is now the oldest
  EXPECT_EQ(*cache.find<int>(1), 10);
  cache.insert<int>(3, std::make_shared<const int>(30), 150);
  EXPECT_EQ(cache.find<double>(2), nullptr);
  EXPECT_NE(cache.find<int>(1), nullptr);
  EXPECT_NE(cache.find<int>(3), nullptr);
  EXPECT_LE(cache.stats().bytes, 300u);
  EXPECT_EQ(cache.stats().evictions, 1u);
  cache.insert<int>(4, std::make_shared<const int>(40), 301);  // larger than the bound: not kept
  EXPECT_EQ(cache.find<int>(4), nullptr);
}

// Random tree `seed` blended with a point beside it, and the point's id: the edits move it.
std::pair<Tree, NodeId> tree_and_point(int seed) {
  test::Rng rng(900 + seed);
  test::RandomTreeOptions o;
  o.max_depth = 3;
  Builder b(kT);
  const NodeId x = test::random_tree(b, rng, o);
  const NodeId y = b.point(dvec3(3.0 + 0.1 * seed, 0.2, -0.1), {0.6, 1.0});
  return {b.build(b.blend({x, y})), y};
}

TEST(PieceReuse, NudgedRandomTreesReuseBricksAndGiveTheSameBytes) {
  std::size_t compared = 0, with_bricks = 0;
  for (int seed = 0; seed < 16; ++seed) {
    const auto [before, y] = tree_and_point(seed);
    const Reuse r = check_edit(before, nudged(before, y, 0, 0.05), 0.1);
    compared += r.active > 0;
    with_bricks += r.bricks > 0;
    EXPECT_LT(r.bricks, r.active);  // the point's bricks changed
  }
  EXPECT_GE(compared, 8u);
  EXPECT_GE(with_bricks, compared / 2) << "bricks far from the edit were hardly ever reused";
}

// check_edit through the disk level (`hybridtree mesh --cache DIR`): `before` meshed by one
// process's caches over `dir`, `after` by a fresh one's, as two runs of the CLI would. No file may
// be ignored.
Reuse check_edit_on_disk(const Tree& before, const Tree& after, double h, const std::filesystem::path& dir) {
  std::vector<std::string> warnings;
  auto warn = [&](const std::string& line) { warnings.push_back(line); };
  {
    DiskCache disk(dir, std::uint64_t(1) << 30, warn);
    NodeCache cache(std::size_t(1) << 30, &disk);
    if (!try_mesh(before, &cache, h)) return {};
  }
  const auto scratch = try_mesh(after, nullptr, h);
  DiskCache disk(dir, std::uint64_t(1) << 30, warn);
  NodeCache cache(std::size_t(1) << 30, &disk);
  const auto incremental = try_mesh(after, &cache, h);
  disk.flush();
  EXPECT_EQ(scratch.has_value(), incremental.has_value());
  EXPECT_TRUE(warnings.empty()) << warnings.front();
  if (!scratch || !incremental) return {};
  EXPECT_TRUE(test::same_bytes(*scratch->mesh, *incremental->mesh));
  const Reuse r = reuse_of(*incremental);
  EXPECT_GE(disk.stats().part_hits, r.bricks + r.pieces_reused) << "every part reused came from a file";
  return r;
}

TEST(PieceReuse, NudgedRandomTreesThroughTheDiskGiveTheSameBytes) {
  std::size_t compared = 0, with_bricks = 0;
  for (int seed = 0; seed < 8; ++seed) {
    const auto [before, y] = tree_and_point(seed);
    const std::filesystem::path dir = test::temp_dir("parts-disk-" + std::to_string(seed));
    const Reuse r = check_edit_on_disk(before, nudged(before, y, 0, 0.05), 0.1, dir);
    std::filesystem::remove_all(dir);
    compared += r.active > 0;
    with_bricks += r.bricks > 0;
    EXPECT_LT(r.bricks, r.active);
  }
  EXPECT_GE(compared, 4u);
  EXPECT_GE(with_bricks, compared / 2) << "bricks far from the edit were hardly ever read back";
}

// The snake of `count` curves as JSON, and with curve `which`'s first point moved by `dx` in x.
std::pair<Tree, Tree> snake_edit(int count, int which, double dx) {
  const std::string text = scenes::snake_json(count, 3);
  std::size_t at = 0;
  for (int i = 0; i <= which; ++i) at = text.find("\"points\": [[", at + 1);
  EXPECT_NE(at, std::string::npos);
  at += 12;
  char* end = nullptr;
  const double x = std::strtod(text.c_str() + at, &end);
  const std::string moved = text.substr(0, at) + std::to_string(x + dx) + text.substr(std::size_t(end - text.c_str()));
  return {load_scene_text(text, "."), load_scene_text(moved, ".")};
}

TEST(PieceReuse, MovingOneCurveOfTheSnakeReusesMostOfItsPolygonization) {
  const auto [before, after] = snake_edit(80, 40, 0.01);
  const Reuse r = check_edit(before, after, 0.12);
  ASSERT_GT(r.active, 0u);
  // The curve's field reaches about a sixth of the body; its bricks' tapes change.
  EXPECT_GT(r.bricks * 10, r.active * 6) << r.bricks << " of " << r.active << " bricks reused";
  EXPECT_GT(r.pieces_reused, 0u);
  EXPECT_LT(r.pieces_reused, r.pieces);
}

TEST(PieceReuse, ATinyBoundStillGivesTheSameBytes) {
  const auto [before, after] = snake_edit(30, 12, 0.02);
  check_edit(before, after, 0.15, 64 << 10);
}

// The quality pass keeps a piece only when every evaluation fell in a part of the field with a
// key, takes it again only while those parts keep their keys, and a kept piece comes back
// identical to running the pass.
TEST(PieceReuse, QualityPiecesAreKeptWithThePartsOfTheFieldTheyRead) {
  Builder b(kT);
  const Tree t = b.build(b.point(dvec3(0), {1.0, 1.0}));
  PolygonizeOptions po;
  po.precision = 0.08;
  po.quality.enabled = false;
  const TriangleMesh raw = polygonize(t.graph_ptr(), t.root(), kT, po);
  ASSERT_FALSE(raw.triangles.empty());
  const BatchField field = [&](std::span<const dvec3> p, std::span<double> v) {
    for (std::size_t i = 0; i < p.size(); ++i) v[i] = reference_field(t.graph(), t.root(), kT, p[i]);
  };
  // Two parts: x < 0 and x >= 0; or none anywhere.
  auto run = [&](PieceCache& cache, bool parts, std::uint64_t key_right, QualityStats& st) {
    QualityReuse reuse;
    reuse.cache = &cache;
    reuse.part_of = [parts](const dvec3& p) { return parts ? std::uint64_t(p.x >= 0.0) : QualityReuse::kNoPart; };
    reuse.part_key = [key_right](std::uint64_t part) { return part == 1 ? key_right : 7; };
    TriangleMesh m = raw;
    improve_quality(m, {}, {}, field, kT, 0.08, {}, &st, nullptr, &reuse);
    return m;
  };
  PieceCache nowhere(1 << 30), cache(1 << 30);
  QualityStats a, first_st, again_st, changed_st, plain_st;
  run(nowhere, false, 1, a);
  EXPECT_EQ(nowhere.stats().entries, 0u);
  const TriangleMesh first = run(cache, true, 1, first_st);
  ASSERT_GT(first_st.pieces, 1u);  // slabs and bands
  EXPECT_EQ(cache.stats().entries, first_st.pieces);
  const TriangleMesh again = run(cache, true, 1, again_st);
  EXPECT_EQ(again_st.pieces_reused, again_st.pieces);
  // The right half's key changed: the pieces that read it run again, the others are kept.
  const TriangleMesh changed = run(cache, true, 2, changed_st);
  EXPECT_GT(changed_st.pieces_reused, 0u);
  EXPECT_LT(changed_st.pieces_reused, changed_st.pieces);
  TriangleMesh plain = raw;
  improve_quality(plain, {}, {}, field, kT, 0.08, {}, &plain_st);
  EXPECT_TRUE(test::same_bytes(first, plain));
  EXPECT_TRUE(test::same_bytes(again, plain));
  EXPECT_TRUE(test::same_bytes(changed, plain));
}

}  // namespace
