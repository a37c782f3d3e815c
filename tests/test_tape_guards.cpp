// Skip guards (runtime/tape.hpp): a guarded tape gives the values of the unguarded one (to float
// rounding: guarded sums are summed apart), and the same bits in a batch (run in Morton order)
// as point by point; the guards skip
// where a block misses their box; narrowing drops them and keeps the values.
#include "runtime/builder.hpp"
#include "runtime/morton.hpp"
#include "runtime/tape.hpp"
#include "runtime/tape_eval.hpp"
#include "tests/support/random_tree.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <random>

using namespace ht;
using glm::dvec3;

namespace {

constexpr double kT = 0.5;

// Clusters of points (what a guard can skip for) and points anywhere, shuffled together.
std::vector<dvec3> clustered_points(test::Rng& rng, std::size_t n, double extent = 2.5) {
  std::vector<dvec3> pts;
  while (pts.size() < n) {
    const dvec3 c = test::random_point(rng, extent);
    for (int i = 0; i < 64 && pts.size() < n; ++i) pts.push_back(c + test::random_point(rng, 0.08 * extent));
    pts.push_back(test::random_point(rng, 1.2 * extent));
  }
  for (std::size_t i = pts.size(); i-- > 1;) std::swap(pts[i], pts[std::uniform_int_distribution<std::size_t>(0, i)(rng)]);
  pts.resize(n);
  return pts;
}

// The same value: the same bits, but for the sign of zero (a skipped range writes +0 where a
// negative primitive computes -0).
bool same_bits(double a, double b) { return (a == 0.0 && b == 0.0) || std::memcmp(&a, &b, sizeof a) == 0; }

// n primitives of the given radius scattered in a cube of side `extent`, grouped four by four
// into nested blends (what the optimizer's regrouping makes).
NodeId nested_groups(Builder& b, test::Rng& rng, int n, double extent) {
  std::vector<dvec3> centers(static_cast<std::size_t>(n));
  for (auto& c : centers) c = test::random_point(rng, 0.5 * extent);
  // In Morton order, then grouped: neighbours in space share a group.
  std::vector<NodeId> level;
  for (std::uint32_t i : morton::order(centers.size(), [&](std::size_t i) { return glm::vec3(centers[i]); }))
    level.push_back(b.point(centers[i], {1.5, 1.0}));
  while (level.size() > 1) {
    std::vector<NodeId> next;
    for (std::size_t i = 0; i < level.size(); i += 4) {
      std::vector<NodeId> group(level.begin() + std::ptrdiff_t(i), level.begin() + std::ptrdiff_t(std::min(level.size(), i + 4)));
      next.push_back(group.size() == 1 ? group[0] : b.blend(group));
    }
    level = std::move(next);
  }
  return level[0];
}

}  // namespace

TEST(TapeGuards, GuardedTapesGiveTheSameBitsOnRandomTrees) {
  test::Rng rng(71);
  test::RandomTreeOptions opt;
  opt.max_depth = 5;
  std::size_t guarded_trees = 0;
  for (int trial = 0; trial < 300; ++trial) {
    Builder b(kT);
    const NodeId root = test::random_tree(b, rng, opt);
    const Tree t = b.build(root);
    const auto plain = std::make_shared<const Tape>(compile_tape(t.graph_ptr(), root, kT, nullptr, false, false));
    const auto guarded = std::make_shared<const Tape>(compile_tape(t.graph_ptr(), root, kT));
    ASSERT_EQ(plain->skips, 0u);
    guarded_trees += guarded->skips ? 1 : 0;
    const TapeEvaluator a(plain), g(guarded);
    const auto pts = clustered_points(rng, 9 * kBlock + 17);  // big enough for Morton order
    std::vector<double> va(pts.size()), vg(pts.size());
    a.field(pts, va);
    g.field(pts, vg);
    std::vector<glm::dvec3> ga(pts.size()), gg(pts.size());
    a.gradient(pts, {}, ga);
    g.gradient(pts, {}, gg);
    for (std::size_t i = 0; i < pts.size(); ++i) {
      // A guarded nested blend is summed on its own, not into its parent's sum: the values
      // differ by float rounding only.
      ASSERT_NEAR(va[i], vg[i], 1e-6 * std::max(1.0, std::abs(va[i])))
          << "trial " << trial << " point " << i << "\n" << guarded->listing();
      // The batch ran in Morton order, in other blocks: each point's bits are its own.
      ASSERT_TRUE(same_bits(vg[i], g.field(pts[i]))) << "one point alone, trial " << trial << " point " << i << ": " << vg[i] << " vs "
                                                           << g.field(pts[i]) << "\n" << guarded->listing();
      // Gradients of a curve pick the nearest segment chunk by chunk, so a tie may go the other
      // way in another block: equal to float rounding.
      for (int k = 0; k < 3; ++k)
        ASSERT_NEAR(ga[i][k], gg[i][k], 1e-5 * std::max(1.0, std::abs(ga[i][k]))) << "trial " << trial << " point " << i;
    }
  }
  EXPECT_GT(guarded_trees, 10u) << "the random trees should exercise guards";
}

TEST(TapeGuards, SkipWhereABlockMissesTheBoxAndNarrowingDropsThem) {
  test::Rng rng(72);
  Builder b(kT);
  const NodeId root = nested_groups(b, rng, 256, 30.0);
  const Tree t = b.build(root);
  const auto guarded = std::make_shared<const Tape>(compile_tape(t.graph_ptr(), root, kT));
  const auto plain = std::make_shared<const Tape>(compile_tape(t.graph_ptr(), root, kT, nullptr, false, false));
  EXPECT_GT(guarded->skips, 20u);
  EXPECT_EQ(guarded->size(), plain->size() + guarded->skips);
  const auto pts = clustered_points(rng, 64 * kBlock, 15.0);
  std::vector<double> va(pts.size()), vg(pts.size());
  TapeEvaluator(plain).field(pts, va);
  TapeEvaluator(guarded).field(pts, vg);
  std::size_t nonzero = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    ASSERT_TRUE(same_bits(va[i], vg[i])) << i;
    nonzero += va[i] != 0.0 ? 1 : 0;
  }
  EXPECT_GT(nonzero, 100u);
  // A narrowed tape has no Skips and the same values inside its box.
  const Aabb box{{-3, -3, -3}, {3, 3, 3}};
  const auto narrow = std::make_shared<const Tape>(narrow_tape(*guarded, box));
  EXPECT_EQ(narrow->skips, 0u);
  for (const Instruction& ins : narrow->code) ASSERT_NE(ins.op, OpCode::Skip);
  const TapeEvaluator n(narrow), full(guarded);
  for (int i = 0; i < 2000; ++i) {
    const dvec3 p = test::random_point(rng, 3.0);
    EXPECT_NEAR(n.field(p), full.field(p), 1e-6) << p.x;
  }
}
