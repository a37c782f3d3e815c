// Warps: w^-1(w(p)) = p, the right-hand rule, support boxes that hold the warped support, and
// f(p) = f_child(w^-1(p)).
#include "nodes/warps.hpp"
#include "runtime/builder.hpp"
#include "tests/support/random_tree.hpp"

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

using namespace ht;
using glm::dvec3;

namespace {

double uniform(test::Rng& rng, double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }

// A random warp of each kind as a parameter block.
std::vector<double> random_params(NodeKind k, test::Rng& rng) {
  const double axis = double(std::uniform_int_distribution<int>(0, 2)(rng));
  const dvec3 c = test::random_point(rng, 0.5);
  switch (k) {
    case NodeKind::Affine: {
      glm::dmat4 m = glm::translate(glm::dmat4(1.0), test::random_point(rng, 1));
      m = glm::rotate(m, uniform(rng, -3, 3), glm::normalize(test::random_point(rng, 1) + dvec3(0, 0, 2)));
      m = glm::scale(m, dvec3(uniform(rng, 0.3, 2), uniform(rng, 0.3, 2), uniform(rng, 0.3, 2)));
      double fwd[12], out[kAffineParams];
      for (int r = 0; r < 3; ++r)
        for (int col = 0; col < 4; ++col) fwd[4 * r + col] = m[col][r];
      EXPECT_TRUE(affine_from_matrix(fwd, out));
      return {out, out + kAffineParams};
    }
    case NodeKind::Twist: return {axis, c.x, c.y, c.z, uniform(rng, -2, 2)};
    case NodeKind::Taper: {
      const double h0 = uniform(rng, -1, 0);
      return {axis, c.x, c.y, c.z, h0, h0 + uniform(rng, 0.1, 2), uniform(rng, 0.3, 2), uniform(rng, 0.3, 2)};
    }
    default: {
      const double h0 = uniform(rng, -1, 0);
      return {axis, c.x, c.y, c.z, h0, h0 + uniform(rng, 0.1, 2), uniform(rng, -0.3, 0.3)};
    }
  }
}

}  // namespace

TEST(Warps, InverseUndoesForwardOnRandomPoints) {
  test::Rng rng(31);
  for (NodeKind k : {NodeKind::Affine, NodeKind::Twist, NodeKind::Taper, NodeKind::Bend}) {
    for (int trial = 0; trial < 200; ++trial) {
      const auto prm = random_params(k, rng);
      for (int i = 0; i < 50; ++i) {
        // Bend is one-to-one nearer to the axis than its radius of curvature (1/|rate| >= 2).
        const dvec3 p = test::random_point(rng, 1.5);
        const dvec3 there = warp_forward(k, prm.data(), p);
        const dvec3 back = warp_inverse(k, prm.data(), there);
        EXPECT_NEAR(glm::length(back - p), 0.0, 1e-9 * (1 + glm::length(p)))
            << kind_name(k) << " trial " << trial;
        const dvec3 back2 = warp_forward(k, prm.data(), warp_inverse(k, prm.data(), p));
        EXPECT_NEAR(glm::length(back2 - p), 0.0, 1e-9 * (1 + glm::length(p))) << kind_name(k);
      }
    }
  }
}

TEST(Warps, TurnsFollowTheRightHandRule) {
  // twist about z by a quarter turn at h = 1: x turns toward y.
  const double twist[] = {2, 0, 0, 0, std::numbers::pi / 2};
  const dvec3 q = warp_forward(NodeKind::Twist, twist, {1, 0, 1});
  EXPECT_NEAR(q.x, 0.0, 1e-12);
  EXPECT_NEAR(q.y, 1.0, 1e-12);
  EXPECT_NEAR(q.z, 1.0, 1e-12);
  // about x: y turns toward z.
  const double twist_x[] = {0, 0, 0, 0, std::numbers::pi / 2};
  const dvec3 r = warp_forward(NodeKind::Twist, twist_x, {1, 1, 0});
  EXPECT_NEAR(r.z, 1.0, 1e-12);
  // Taper halves the slice at the far end of its range and keeps h.
  const double taper[] = {2, 0, 0, 0, 0, 1, 1, 0.5};
  const dvec3 t = warp_forward(NodeKind::Taper, taper, {1, 1, 2});
  EXPECT_NEAR(t.x, 0.5, 1e-12);
  EXPECT_NEAR(t.z, 2.0, 1e-12);
  // Bend along z with curvature k over [0, pi/(2k)]: the axis ends a quarter circle away,
  // pointing along +x, and the part beyond goes on straight.
  const double k = 0.5, h1 = std::numbers::pi / (2 * k);
  const double bend[] = {2, 0, 0, 0, 0, h1, k};
  const dvec3 end = warp_forward(NodeKind::Bend, bend, {0, 0, h1});
  EXPECT_NEAR(end.x, 1 / k, 1e-12);
  EXPECT_NEAR(end.z, 1 / k, 1e-12);
  const dvec3 beyond = warp_forward(NodeKind::Bend, bend, {0, 0, h1 + 1});
  EXPECT_NEAR(beyond.x, 1 / k + 1, 1e-12);
  EXPECT_NEAR(beyond.z, 1 / k, 1e-12);
  // Arc length is kept along the axis.
  const dvec3 mid = warp_forward(NodeKind::Bend, bend, {0, 0, h1 / 2});
  EXPECT_NEAR(glm::length(mid - dvec3(1 / k, 0, 0)), 1 / k, 1e-12);
}

TEST(Warps, BoundsHoldTheImageOfTheBox) {
  test::Rng rng(32);
  for (NodeKind k : {NodeKind::Affine, NodeKind::Twist, NodeKind::Taper, NodeKind::Bend}) {
    for (int trial = 0; trial < 100; ++trial) {
      const auto prm = random_params(k, rng);
      const dvec3 lo = test::random_point(rng, 1.0);
      const Aabb box{lo, lo + dvec3(uniform(rng, 0.1, 1.5), uniform(rng, 0.1, 1.5), uniform(rng, 0.1, 1.5))};
      const Aabb image = warp_bounds(k, prm.data(), box);
      for (int i = 0; i < 200; ++i) {
        const dvec3 s(uniform(rng, 0, 1), uniform(rng, 0, 1), uniform(rng, 0, 1));
        const dvec3 q = warp_forward(k, prm.data(), box.lo + s * box.size());
        EXPECT_TRUE(image.expanded(1e-9).contains(q)) << kind_name(k) << " trial " << trial;
      }
    }
  }
}

// A bend's bounds listed every quarter turn its range makes: at a rate of 1e9 over a range of 2,
// 1.3e9 of them (2 GB, then std::bad_alloc while the scene loaded). Past a whole turn, or at
// angles doubles no longer step finely along, the bent part is bounded by its annulus.
TEST(Warps, BendBoundsAtExtremeRatesHoldTheImageOfTheBox) {
  test::Rng rng(34);
  const Aabb box{{-0.7, -0.4, -1.0}, {0.5, 0.6, 1.0}};
  for (double k : {3.0, 50.0, 1e3, 1e9, 1e15, 1e300, -1e9}) {
    const double bend[] = {2, 0.1, -0.2, 0, -1, 1, k};  // about z, range [-1, 1]
    const Aabb image = warp_bounds(NodeKind::Bend, bend, box);
    ASSERT_TRUE(image.finite()) << k;
    EXPECT_LT(glm::length(image.size()), 10.0) << k;  // the annulus: radii within the box's
    for (int i = 0; i < 2000; ++i) {
      const dvec3 s(uniform(rng, 0, 1), uniform(rng, 0, 1), uniform(rng, 0, 1));
      const dvec3 q = warp_forward(NodeKind::Bend, bend, box.lo + s * box.size());
      EXPECT_TRUE(image.expanded(1e-9).contains(q)) << "rate " << k;
    }
  }
}

TEST(Warps, WarpedFieldIsTheChildAtTheInverse) {
  test::Rng rng(33);
  Builder b(0.5);
  const NodeId child = b.segment({-0.5, 0, 0}, {0.5, 0.2, 0.3}, {0.8});
  const NodeId tw = b.twist(child, Axis::X, {0.1, 0, 0}, 1.3);
  const NodeId tp = b.taper(child, Axis::Y, {0, 0, 0}, -0.5, 0.5, 0.6, 1.4);
  const NodeId bd = b.bend(child, Axis::Z, {0, 0, 0}, -0.5, 0.5, 0.3);
  const Tree t = b.build(tw);
  for (NodeId w : {tw, tp, bd}) {
    const auto prm = t.graph().params_of(w);
    for (int i = 0; i < 500; ++i) {
      const dvec3 p = test::random_point(rng, 1.5);
      EXPECT_DOUBLE_EQ(t.subtree(w).reference(p), t.subtree(child).reference(warp_inverse(t.graph().kind[w], prm.data(), p)));
    }
  }
}
