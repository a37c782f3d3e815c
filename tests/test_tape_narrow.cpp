// Narrowing (runtime/tape.hpp narrow_tape): a tape specialized to a box made from the tape of a
// larger box equals the full tape inside it on random trees (every node kind but ffd, every
// Boolean mode, nested warps, mesh leaves), nested boxes narrow again, and what a box cannot
// reach is gone.
#include "nodes/mesh_leaf.hpp"
#include "runtime/builder.hpp"
#include "runtime/tape.hpp"
#include "runtime/tape_eval.hpp"
#include "tests/support/random_tree.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace ht;
using glm::dvec3;

namespace {

constexpr double kT = 0.5;

std::vector<dvec3> points_in(const Aabb& box, test::Rng& rng, std::size_t n) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<dvec3> pts(n);
  for (auto& p : pts) p = box.lo + box.size() * dvec3(u(rng), u(rng), u(rng));
  return pts;
}

// Values of a and b at the points agree (constants folded from leaves round once more).
void expect_same(const std::shared_ptr<const Tape>& a, const std::shared_ptr<const Tape>& b, const std::vector<dvec3>& pts,
                 int trial) {
  const TapeEvaluator ea(a), eb(b);
  std::vector<double> va(pts.size()), vb(pts.size());
  ea.field(pts, va);
  eb.field(pts, vb);
  for (std::size_t i = 0; i < pts.size(); ++i)
    ASSERT_NEAR(vb[i], va[i], 1e-5 * std::max(1.0, std::abs(va[i]))) << "trial " << trial << "\nwide\n"
                                                                     << a->listing() << "narrowed\n"
                                                                     << b->listing();
}

}  // namespace

TEST(TapeNarrow, EqualsTheFullTapeInsideTheBoxOnRandomTrees) {
  test::Rng rng(71);
  test::RandomTreeOptions opt;
  opt.meshes = {MeshLeaf::load(test::cgal_mesh("eight.off")), MeshLeaf::load(test::cgal_mesh("sphere.off"))};
  opt.max_depth = 5;  // bigger trees than the default: more to narrow
  opt.max_children = 4;
  std::size_t shorter = 0, trials = 0, gradients_checked = 0;
  for (int trial = 0; trial < 500; ++trial) {
    Builder b(kT);
    const NodeId root = test::random_tree(b, rng, opt);
    const Tree t = b.build(root);
    const auto full = std::make_shared<const Tape>(compile_tape(t.graph_ptr(), root, kT));
    // A box, a box inside it, and a box inside that: narrowed from the root's tape, then from
    // each other.
    const dvec3 lo = test::random_point(rng, 2.5);
    const double size = std::uniform_real_distribution<double>(0.2, 2.0)(rng);
    const Aabb outer{lo, lo + dvec3(size)};
    const Aabb middle{lo + 0.25 * size, lo + 0.75 * size};
    const Aabb inner{lo + 0.4 * size, lo + 0.55 * size};
    const auto wide = std::make_shared<const Tape>(narrow_tape(*full, outer));
    const auto mid = std::make_shared<const Tape>(narrow_tape(*wide, middle));
    const auto in = std::make_shared<const Tape>(narrow_tape(*mid, inner));
    ASSERT_LE(wide->size(), full->size());
    ASSERT_LE(mid->size(), wide->size());
    ASSERT_LE(in->size(), mid->size());
    expect_same(full, wide, points_in(outer, rng, 96), trial);
    expect_same(full, mid, points_in(middle, rng, 96), trial);
    expect_same(full, in, points_in(inner, rng, 96), trial);
    // Narrowing the compiler's own specialized tape keeps its values too.
    const auto compiled = std::make_shared<const Tape>(compile_tape(t.graph_ptr(), root, kT, &outer));
    expect_same(compiled, std::make_shared<const Tape>(narrow_tape(*compiled, middle)), points_in(middle, rng, 64), trial);
    // And the gradient path reads the narrowed tape the same way.
    if (trial % 5 == 0) {
      const std::vector<dvec3> pts = points_in(inner, rng, 32);
      std::vector<dvec3> ga(pts.size()), gb(pts.size());
      TapeEvaluator(full).gradient(pts, {}, ga);
      TapeEvaluator(in).gradient(pts, {}, gb);
      for (std::size_t i = 0; i < pts.size(); ++i)
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(gb[i][c], ga[i][c], 1e-4 * std::max(1.0, std::abs(ga[i][c]))) << trial;
      ++gradients_checked;
    }
    ++trials;
    shorter += in->size() < full->size() ? 1 : 0;
  }
  EXPECT_GT(shorter, trials / 4);
  EXPECT_GT(gradients_checked, 50u);
}

TEST(TapeNarrow, DropsWhatTheBoxCannotReach) {
  // A row of 100 points 1 apart with radius 0.6, blended: a box around one keeps only it.
  Builder b(kT);
  std::vector<NodeId> parts;
  for (int i = 0; i < 100; ++i) parts.push_back(b.point({i, 0, 0}, {0.6}));
  const Tree t = b.build(b.blend(parts));
  const Tape full = compile_tape(t.graph_ptr(), t.root(), kT);
  const Tape ten = narrow_tape(full, {{39.5, -1, -1}, {49.5, 1, 1}});
  EXPECT_EQ(ten.leaf_count(), 12u);  // points 39 to 50 reach into it, 0.6 each side
  const Tape one = narrow_tape(ten, {{41.8, -0.2, -0.2}, {42.2, 0.2, 0.2}});
  EXPECT_EQ(one.leaf_count(), 1u);
  EXPECT_LE(one.size(), 3u) << one.listing();  // at most the sum's first term, now Zero, and one Add
  EXPECT_LT(one.constants.size(), 16u);  // only its own constants are carried
  const Tape none = narrow_tape(full, {{500, 500, 500}, {501, 501, 501}});
  EXPECT_EQ(none.leaf_count(), 0u);
  EXPECT_EQ(none.size(), 1u);  // Zero
}

TEST(TapeNarrow, DecidedBranchesAndBlendWeightsFold) {
  Builder b(kT);
  const NodeId big = b.point({0, 0, 0}, {2.0, 3.0});
  const NodeId small = b.point({0.3, 0, 0}, {0.5, 0.6});
  const NodeId u = b.unite({big, small}, BooleanMode::MinMax);
  // A local blend whose region is far from the box: there it is the union alone.
  const NodeId lb = b.local_blend(b.point({0, 0, 0}, {1.0}), b.point({0.5, 0, 0}, {1.0}), b.point({5, 0, 0}, {0.5}),
                                  BooleanMode::MinMax);
  const Tree t = b.build(b.blend({u, lb}));
  const Tape full = compile_tape(t.graph_ptr(), t.root(), kT);
  const Tape part = narrow_tape(full, {{-0.05, -0.05, -0.05}, {0.05, 0.05, 0.05}});  // big ~ 3 here, small <= 0.6
  EXPECT_EQ(full.leaf_count(), 5u);
  EXPECT_EQ(part.leaf_count(), 3u) << part.listing();  // small and the region are gone
  for (const Instruction& i : part.code) EXPECT_NE(i.op, OpCode::LocalBlendMinMax) << part.listing();
}

TEST(TapeNarrow, RefusesATapeWithoutSources) {
  Tape bare;
  bare.code.push_back(Instruction::make(OpCode::Zero, 3));
  EXPECT_THROW(narrow_tape(bare, {{0, 0, 0}, {1, 1, 1}}), std::invalid_argument);
}
