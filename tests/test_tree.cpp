// The graph and the reference evaluator on random trees: supports hold every non-zero value,
// the signs they promise hold, gradients match the analytic ones, and batch == point queries.
#include "runtime/builder.hpp"
#include "runtime/tree_eval.hpp"
#include "tests/support/random_tree.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

using namespace ht;
using glm::dvec3;

TEST(Tree, FieldIsZeroOutsideEverySupportBox) {
  test::Rng rng(41);
  test::RandomTreeOptions opt;
  int checked = 0;
  for (int trial = 0; trial < 300; ++trial) {
    Builder b(0.5);
    const NodeId root = test::random_tree(b, rng, opt);
    const Tree t = b.build(root);
    const Graph& g = t.graph();
    for (NodeId n = 0; n < g.size(); ++n) {
      for (int i = 0; i < 20; ++i) {
        const dvec3 p = test::random_point(rng, 4.0);
        for (bool blended : {false, true}) {
          const double f = reference_field(g, n, 0.5, p, blended);
          if (!g.support(n, blended).contains(p)) {
            EXPECT_EQ(f, 0.0) << "node " << g.label(n) << " blended " << blended << " trial " << trial;
            ++checked;
          }
          if (g.nonnegative[n]) {
            EXPECT_GE(f, -1e-12) << g.label(n);
          }
        }
      }
    }
  }
  EXPECT_GT(checked, 10000);
}

TEST(Tree, GradientMatchesTheAnalyticGradientOfAPrimitive) {
  Builder b(0.5);
  const double R = 1.5, F = 1.2;
  const Tree t = b.build(b.point({0.2, -0.1, 0.3}, {R, F}));
  test::Rng rng(42);
  for (int i = 0; i < 500; ++i) {
    const dvec3 p = test::random_point(rng, 1.5);
    const dvec3 q = p - dvec3(0.2, -0.1, 0.3);
    const double d2 = glm::dot(q, q);
    // f = F (1 - d^2/R^2)^3  =>  grad f = -6 F (1 - d^2/R^2)^2 q / R^2
    const double u = 1 - d2 / (R * R);
    const dvec3 expected = d2 < R * R ? -6.0 * F * u * u * q / (R * R) : dvec3(0.0);
    const dvec3 got = t.reference_gradient(p);
    EXPECT_NEAR(glm::length(got - expected), 0.0, 1e-6) << i;
  }
}

TEST(Tree, BatchQueriesEqualPointQueries) {
  test::Rng rng(43);
  Builder b(0.5);
  const Tree t = b.build(test::random_tree(b, rng, {}));
  std::vector<dvec3> pts;
  for (int i = 0; i < 4000; ++i) pts.push_back(test::random_point(rng, 2.5));
  std::vector<double> values(pts.size());
  std::vector<dvec3> grads(pts.size());
  t.reference(pts, values);
  t.reference_gradient(pts, grads);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    EXPECT_EQ(values[i], t.reference(pts[i]));
    EXPECT_EQ(grads[i], t.reference_gradient(pts[i]));
  }
  std::vector<double> wrong(3);
  EXPECT_THROW(t.reference(pts, wrong), std::invalid_argument);
}

TEST(Tree, TwoHundredFiftyPrimitivesFitInUnder64KB) {
  // The paper stores its 250-primitive snake-woman in under 64 KB.
  Builder b(0.5);
  std::vector<NodeId> parts;
  test::Rng rng(44);
  for (int i = 0; i < 250; ++i) {
    std::vector<dvec3> pts;
    for (int k = 0; k < 4; ++k) pts.push_back(test::random_point(rng, 0.3) + dvec3(0.05 * i, 0, 0));
    parts.push_back(b.curve(pts, {0.5}));
  }
  const Tree t = b.build(b.blend(parts));
  EXPECT_LT(t.graph().bytes(), 64u * 1024u);
}
