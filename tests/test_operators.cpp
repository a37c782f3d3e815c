// Blends, Booleans, local blend and crop against the formulas of SCENE_FORMAT.md, written out
// here a second time, and the `auto` context rule.
#include "nodes/operators.hpp"
#include "runtime/builder.hpp"
#include "runtime/tree_eval.hpp"
#include "tests/support/random_tree.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace ht;
using glm::dvec3;

namespace {

constexpr double kT = 0.5;

double ru(double fa, double fb) {
  const double a = fa - kT, b = fb - kT;
  return kT + (a + b + std::sqrt(a * a + b * b)) / (2 - std::sqrt(2.0));
}
double ri(double fa, double fb) {
  const double a = fa - kT, b = fb - kT;
  return kT + (a + b - std::sqrt(a * a + b * b)) / (2 + std::sqrt(2.0));
}

struct Pair {
  Builder b{kT};
  NodeId A, B;
  Tree ta, tb;
  Pair()
      : A(b.segment({-0.5, 0, 0}, {0.3, 0, 0}, {1.0, 1.2})),
        B(b.point({0.4, 0.1, 0}, {0.9, 1.0})),
        ta(b.build(A)),
        tb(b.build(B)) {}
};

}  // namespace

TEST(Operators, BooleanFormulasInEveryMode) {
  test::Rng rng(21);
  Pair p;
  const NodeId u_mm = p.b.unite({p.A, p.B}, BooleanMode::MinMax);
  const NodeId i_mm = p.b.intersect({p.A, p.B}, BooleanMode::MinMax);
  const NodeId d_mm = p.b.subtract({p.A, p.B}, BooleanMode::MinMax);
  const NodeId u_rf = p.b.unite({p.A, p.B}, BooleanMode::RFunction);
  const NodeId i_rf = p.b.intersect({p.A, p.B}, BooleanMode::RFunction);
  const NodeId d_rf = p.b.subtract({p.A, p.B}, BooleanMode::RFunction);
  const NodeId bl = p.b.blend({p.A, p.B});
  const Tree t = p.b.build(bl);
  for (int i = 0; i < 2000; ++i) {
    const dvec3 q = test::random_point(rng, 1.6);
    const double fa = p.ta.reference(q), fb = p.tb.reference(q);
    EXPECT_DOUBLE_EQ(t.subtree(u_mm).reference(q), std::max(fa, fb));
    EXPECT_DOUBLE_EQ(t.subtree(i_mm).reference(q), std::min(fa, fb));
    EXPECT_DOUBLE_EQ(t.subtree(d_mm).reference(q), std::max(0.0, std::min(fa, 2 * kT - fb)));
    EXPECT_NEAR(t.subtree(u_rf).reference(q), ru(fa, fb), 1e-12);
    EXPECT_NEAR(t.subtree(i_rf).reference(q), ri(fa, fb), 1e-12);
    EXPECT_NEAR(t.subtree(d_rf).reference(q), std::max(0.0, ri(fa, 2 * kT - fb)), 1e-12);
    EXPECT_NEAR(t.subtree(bl).reference(q), fa + fb, 1e-12);
  }
}

TEST(Operators, RFunctionsKeepCompactSupportAndTheSurface) {
  // Where both children are 0 the R-function union and intersection are exactly 0; on the
  // surface of either operand they agree in sign with min/max.
  EXPECT_NEAR(ru(0, 0), 0.0, 1e-15);
  EXPECT_NEAR(ri(0, 0), 0.0, 1e-15);
  test::Rng rng(22);
  std::uniform_real_distribution<double> f(0, 1.5);
  for (int i = 0; i < 10000; ++i) {
    const double fa = f(rng), fb = f(rng);
    EXPECT_EQ(ru(fa, fb) > kT, std::max(fa, fb) > kT);
    EXPECT_EQ(ri(fa, fb) > kT, std::min(fa, fb) > kT);
  }
}

TEST(Operators, AutoPicksRFunctionsExactlyUnderABlend) {
  Pair p;
  const NodeId u = p.b.unite({p.A, p.B});  // auto
  const NodeId above = p.b.blend({u});
  const NodeId extra = p.b.point({3, 3, 3}, {0.5});
  const NodeId lb = p.b.local_blend(u, extra, extra);
  const NodeId warped = p.b.affine(u, glm::dmat4(1.0));
  const NodeId warped_blend = p.b.blend({warped});
  const NodeId boolean_above = p.b.intersect({u, u});  // a Boolean is not a blend
  const Tree t = p.b.build(above);
  const dvec3 q(0.35, 0.05, 0.1);
  const double fa = p.ta.reference(q), fb = p.tb.reference(q);
  ASSERT_GT(std::abs(ru(fa, fb) - std::max(fa, fb)), 1e-3);  // the two rules differ here
  EXPECT_DOUBLE_EQ(t.subtree(u).reference(q), std::max(fa, fb));
  EXPECT_NEAR(t.subtree(above).reference(q), ru(fa, fb), 1e-12);
  EXPECT_NEAR(t.subtree(lb).reference(q), ru(fa, fb), 1e-12);  // region and b are 0 here: union only
  EXPECT_NEAR(t.subtree(warped_blend).reference(q), ru(fa, fb), 1e-12);  // through warps too
  EXPECT_DOUBLE_EQ(t.subtree(boolean_above).reference(q), std::max(fa, fb));
}

TEST(Operators, LocalBlendWeighsBlendAgainstUnion) {
  test::Rng rng(23);
  Pair p;
  const NodeId region = p.b.box({0, -1, -1}, {1, 1, 1}, {0.6, 1.0});
  const NodeId lb = p.b.local_blend(p.A, p.B, region, BooleanMode::MinMax);
  const Tree t = p.b.build(lb);
  const Tree tr = t.subtree(region);
  for (int i = 0; i < 2000; ++i) {
    const dvec3 q = test::random_point(rng, 1.6);
    const double fa = p.ta.reference(q), fb = p.tb.reference(q), w = std::clamp(tr.reference(q), 0.0, 1.0);
    EXPECT_NEAR(t.reference(q), w * (fa + fb) + (1 - w) * std::max(fa, fb), 1e-12);
  }
}

TEST(Operators, CropIsContinuousZeroWhereTheChildIsZeroAndCutsAtTheBox) {
  test::Rng rng(24);
  Builder b(kT);
  const NodeId ball = b.point({0, 0, 0}, {1.2, 1.0});
  const NodeId crop = b.crop(ball, {-2, -2, 0}, {2, 2, 2});
  const Tree t = b.build(crop);
  const Tree tb = t.subtree(ball);
  for (int i = 0; i < 5000; ++i) {
    const dvec3 q = test::random_point(rng, 1.5);
    const double f = t.reference(q), fc = tb.reference(q);
    if (fc == 0.0) {
      EXPECT_EQ(f, 0.0);
    }
    EXPECT_GE(f, 0.0);
    EXPECT_LE(f, std::max(fc, 0.0) + 1e-15);
    // Inside the solid: kept above the plane z = 0, gone below it.
    if (fc > kT + 1e-9 && q.z > 1e-6) {
      EXPECT_GT(f, kT);
    }
    if (q.z < -1e-6) {
      EXPECT_LT(f, kT);
    }
    // Continuity: a small step changes f by a small amount.
    const dvec3 dq(1e-7, -1e-7, 1e-7);
    EXPECT_NEAR(t.reference(q + dq), f, 1e-5);
  }
  EXPECT_NEAR(t.reference({0, 0, 0}), kT, 1e-12);  // on the cut plane, inside the ball
}
