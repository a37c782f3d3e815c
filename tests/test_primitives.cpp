// Skeletal primitives: exact distances against brute-force sampling of each skeleton, the
// falloff's contract (0 at and beyond R, T at r0), and values at analytic points.
#include "nodes/primitives.hpp"
#include "runtime/builder.hpp"
#include "tests/support/random_tree.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <numbers>
#include <random>

using namespace ht;
using glm::dvec3;

namespace {

constexpr double kT = 0.5;

// Distance from p to a set given by a sampler over [0,1]^2 (dense grid).
double sampled_distance(const dvec3& p, const std::function<dvec3(double, double)>& at, int n, bool surface) {
  double best = 1e300;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= (surface ? n : 0); ++j) best = std::min(best, glm::length(p - at(double(i) / n, double(j) / n)));
  return best;
}

struct Case {
  const char* name;
  std::function<NodeId(Builder&)> make;
  std::function<dvec3(double, double)> sample;  // the skeleton (for volumes: its boundary)
  std::function<bool(const dvec3&)> inside;     // volumes only
  int n;
};

std::vector<Case> cases() {
  const dvec3 a(0.1, -0.2, 0.3), b(1.1, 0.4, -0.2), c(-0.3, 0.9, 0.5);
  const dvec3 n = glm::normalize(dvec3(0.3, -0.4, 0.85));
  const dvec3 u = glm::normalize(glm::cross(n, dvec3(1, 0, 0))), v = glm::cross(n, u);
  auto never = [](const dvec3&) { return false; };
  std::vector<Case> out;
  out.push_back({"point", [=](Builder& bb) { return bb.point(a, {1.5}); }, [=](double, double) { return a; }, never, 1});
  out.push_back({"segment", [=](Builder& bb) { return bb.segment(a, b, {1.5}); },
                 [=](double s, double) { return a + s * (b - a); }, never, 4000});
  out.push_back({"circle", [=](Builder& bb) { return bb.circle(a, n, 0.7, {1.5}); },
                 [=](double s, double) { const double t = 2 * std::numbers::pi * s; return a + 0.7 * (std::cos(t) * u + std::sin(t) * v); },
                 never, 4000});
  out.push_back({"disc", [=](Builder& bb) { return bb.disc(a, n, 0.7, {1.5}); },
                 [=](double s, double r) { const double t = 2 * std::numbers::pi * s; return a + 0.7 * r * (std::cos(t) * u + std::sin(t) * v); },
                 never, 400});
  out.push_back({"triangle", [=](Builder& bb) { return bb.triangle(a, b, c, {1.5}); },
                 [=](double s, double t) { return a + s * (b - a) + s * t * (c - b); }, never, 400});
  out.push_back({"box", [=](Builder& bb) { return bb.box(dvec3(-0.3, -0.2, -0.1), dvec3(0.5, 0.4, 0.3), {1.5}); },
                 nullptr, [](const dvec3& p) { return p.x >= -0.3 && p.x <= 0.5 && p.y >= -0.2 && p.y <= 0.4 && p.z >= -0.1 && p.z <= 0.3; }, 0});
  return out;
}

}  // namespace

TEST(Primitives, DistanceMatchesDenseSamplingOfTheSkeleton) {
  test::Rng rng(11);
  for (const Case& k : cases()) {
    if (!k.sample) continue;
    Builder b(kT);
    const Tree tree = b.build(k.make(b));
    const Graph& g = tree.graph();
    const double* s = g.skeleton_of(tree.root());
    for (int i = 0; i < 200; ++i) {
      const dvec3 p = test::random_point(rng, 2.0);
      const double exact = skeleton_distance(g.kind[tree.root()], s, p);
      const double sampled = sampled_distance(p, k.sample, k.n, k.n <= 400);
      // Sampling can only overestimate, by at most about half the sample spacing.
      EXPECT_LE(exact, sampled + 1e-12) << k.name;
      EXPECT_NEAR(exact, sampled, 3.0 / k.n + 1e-12) << k.name << " at " << p.x << "," << p.y << "," << p.z;
    }
  }
}

TEST(Primitives, VolumeDistancesAreZeroInsideAndExactOutside) {
  test::Rng rng(12);
  // Cylinder: the solid is the union of discs along the axis; its distance is the min over them.
  const dvec3 a(0.2, -0.1, 0.0), b(0.9, 0.6, 0.4);
  const double rho = 0.35;
  const double ra = 0.5, rb = 0.2;
  const double cyl[] = {a.x, a.y, a.z, b.x, b.y, b.z, rho};
  const double cone[] = {a.x, a.y, a.z, b.x, b.y, b.z, ra, rb};
  const dvec3 axis = glm::normalize(b - a);
  for (int i = 0; i < 400; ++i) {
    const dvec3 p = test::random_point(rng, 1.5);
    // Reference for the cylinder: clamp along the axis, then the radial excess.
    const double t = glm::dot(p - a, axis), len = glm::length(b - a);
    const double r = glm::length((p - a) - t * axis);
    const double dx = std::max(r - rho, 0.0), dy = std::max({-t, t - len, 0.0});
    EXPECT_NEAR(skeleton_distance(NodeKind::Cylinder, cyl, p), std::hypot(dx, dy), 1e-12);
    // Reference for the cone-sphere: the hull of two balls is the union of the balls on the
    // segment with linearly varying radius.
    double best = 1e300;
    for (int k = 0; k <= 20000; ++k) {
      const double s = k / 20000.0;
      best = std::min(best, std::max(0.0, glm::length(p - (a + s * (b - a))) - (ra + s * (rb - ra))));
    }
    EXPECT_NEAR(skeleton_distance(NodeKind::ConeSphere, cone, p), best, 2e-5);
  }
  // Nested spheres: the hull is the larger one.
  const double nested[] = {0, 0, 0, 0.1, 0, 0, 1.0, 0.5};
  EXPECT_NEAR(skeleton_distance(NodeKind::ConeSphere, nested, dvec3(2, 0, 0)), 1.0, 1e-12);
  // Box: 0 inside, Euclidean outside, including at an edge region.
  const double box[] = {0, 0, 0, 1, 2, 3};
  EXPECT_EQ(skeleton_distance(NodeKind::Box, box, dvec3(0.5, 1, 1)), 0.0);
  EXPECT_NEAR(skeleton_distance(NodeKind::Box, box, dvec3(2, 3, 1.5)), std::sqrt(2.0), 1e-12);
}

TEST(Primitives, CurvePolylineStaysWithinToleranceOfTheSpline) {
  test::Rng rng(13);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<dvec3> pts;
    const int n = 2 + trial % 5;
    for (int i = 0; i < n; ++i) pts.push_back(test::random_point(rng, 1.0));
    const double R = 0.8;
    Builder b(kT);
    const Tree tree = b.build(b.curve(pts, {R}));
    const double* s = tree.graph().skeleton_of(tree.root());
    // Dense reference samples of the spline, 4000 per span.
    std::vector<dvec3> dense;
    for (std::size_t span = 0; span + 1 < pts.size(); ++span)
      for (int k = 0; k <= 4000; ++k) dense.push_back(catmull_rom(pts, span, k / 4000.0));
    for (int i = 0; i < 50; ++i) {
      const dvec3 p = test::random_point(rng, 1.5);
      double ref = 1e300;
      for (const dvec3& q : dense) ref = std::min(ref, glm::length(p - q));
      EXPECT_NEAR(skeleton_distance(NodeKind::Curve, s, p), ref, 1e-4 * R) << "trial " << trial;
    }
    // The spline passes through its control points.
    EXPECT_NEAR(skeleton_distance(NodeKind::Curve, s, pts[0]), 0.0, 1e-12);
    EXPECT_NEAR(skeleton_distance(NodeKind::Curve, s, pts[1]), 0.0, 1e-12);
  }
}

// The polyline against the spline both ways (Hausdorff): every point of the spline (dense
// samples) near the polyline, every point of the polyline near the spline, within the tolerance,
// on the curves whose chords the across-the-chord bound makes long: nearly straight ones with
// uneven control points (the spline runs unevenly along them), short ones beside their radius
// (the snake's), and wild ones. A straight stretch takes one chord a span.
TEST(Primitives, CurvePolylineIsWithinToleranceBothWays) {
  test::Rng rng(17);
  auto uniform = [&rng](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
  auto to_segment = [](const dvec3& p, const dvec3& a, const dvec3& b) {
    const dvec3 ab = b - a;
    const double len2 = glm::dot(ab, ab);
    const double t = len2 > 0 ? std::clamp(glm::dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
    return glm::length(p - (a + t * ab));
  };
  std::size_t chords = 0, parametric = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const int kind = trial % 3;  // 0 nearly straight, 1 short, 2 wild
    const dvec3 origin = test::random_point(rng, 1.0), dir = glm::normalize(test::random_point(rng, 1.0) + dvec3(1e-9));
    std::vector<dvec3> pts;
    double along = 0;
    for (int i = 0; i < 3 + trial % 4; ++i) {
      if (kind == 2) {
        pts.push_back(test::random_point(rng, 1.0));
        continue;
      }
      along += uniform(0.05, 1.0);
      const dvec3 wobble = (kind == 0 ? 1e-3 : 0.02) * test::random_point(rng, 1.0);
      pts.push_back(origin + (kind == 1 ? 0.1 : 1.0) * (along * dir + wobble));
    }
    const double tolerance = kCurveTolerance * 0.8;
    const std::vector<dvec3> poly = curve_polyline(pts, tolerance);
    if (kind != 2) {
      chords += poly.size() - 1;
      for (std::size_t i = 0; i + 1 < pts.size(); ++i) {  // the parametric bound alone: n = sqrt(max|C''| / 8 tol)
        const dvec3 p0 = pts[i == 0 ? 0 : i - 1], p1 = pts[i], p2 = pts[i + 1], p3 = pts[std::min(i + 2, pts.size() - 1)];
        const dvec3 c2 = 2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3, c3 = 3.0 * (-p0 + 3.0 * p1 - 3.0 * p2 + p3);
        parametric += std::size_t(std::ceil(std::sqrt(std::max(glm::length(c2), glm::length(c2 + c3)) / (8.0 * tolerance))));
      }
    }
    auto to_poly = [&](const dvec3& p) {
      double d = 1e300;
      for (std::size_t i = 0; i + 1 < poly.size(); ++i) d = std::min(d, to_segment(p, poly[i], poly[i + 1]));
      return d;
    };
    std::vector<dvec3> dense;
    for (std::size_t span = 0; span + 1 < pts.size(); ++span)
      for (int k = 0; k <= 4000; ++k) dense.push_back(catmull_rom(pts, span, k / 4000.0));
    double spline_to_poly = 0, poly_to_spline = 0;
    for (std::size_t i = 0; i < dense.size(); i += 3) spline_to_poly = std::max(spline_to_poly, to_poly(dense[i]));
    for (std::size_t i = 0; i + 1 < poly.size(); ++i)
      for (int k = 0; k < 4; ++k) {
        const dvec3 q = poly[i] + (k / 4.0) * (poly[i + 1] - poly[i]);
        double d = 1e300;
        for (std::size_t j = 0; j + 1 < dense.size(); ++j) d = std::min(d, to_segment(q, dense[j], dense[j + 1]));
        poly_to_spline = std::max(poly_to_spline, d);
      }
    EXPECT_LE(spline_to_poly, tolerance * 1.001) << "trial " << trial;
    EXPECT_LE(poly_to_spline, tolerance * 1.001) << "trial " << trial;
  }
  // The straight and short curves: a few chords a span, not the parametric bound's dozens.
  EXPECT_LT(3 * chords, parametric) << chords << " chords where the parametric bound takes " << parametric;
  std::printf("straight and short curves: %zu chords where the parametric bound takes %zu\n", chords, parametric);
  const std::vector<dvec3> straight = {{0, 0, 0}, {0.1, 0, 0}, {1, 0, 0}, {1.2, 0, 0}};
  bool forward = true;
  for (const dvec3& p : curve_polyline(straight, 1e-6)) forward &= p.y == 0.0 && p.z == 0.0;
  EXPECT_TRUE(forward);
}

TEST(Primitives, FalloffContract) {
  const double R = 1.3, F = 1.7;
  EXPECT_EQ(falloff(R, R, F), 0.0);
  EXPECT_EQ(falloff(R * 1.0000001, R, F), 0.0);
  EXPECT_EQ(falloff(0.0, R, F), F);
  const double r0 = primitive_r0(R, F, kT);
  EXPECT_NEAR(falloff(r0, R, F), kT, 1e-12);
  EXPECT_NEAR(falloff(0.5 * R, R, F), F * std::pow(0.75, 3), 1e-15);
  EXPECT_EQ(primitive_r0(R, 0.4, kT), 0.0);  // F <= T: not visible alone
}

TEST(Primitives, FieldAtAnalyticPointsForEveryKind) {
  // For each kind: a point on the skeleton (f = F), a point at distance r0 (f = T), a point at
  // distance R and beyond (f = 0), each placed where the distance is known in closed form.
  const double R = 1.0, F = 1.0, r0 = primitive_r0(R, F, kT);
  Builder b(kT);
  struct Probe {
    NodeId node;
    dvec3 on, dir;  // a skeleton point with a direction in which the distance grows linearly
  };
  const dvec3 z(0, 0, 1);
  std::vector<dvec3> curve_pts = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  std::vector<Probe> probes = {
      {b.point({0, 0, 0}, {R, F}), {0, 0, 0}, z},
      {b.segment({0, 0, 0}, {1, 0, 0}, {R, F}), {0.5, 0, 0}, z},
      {b.circle({0, 0, 0}, z, 0.5, {R, F}), {0.5, 0, 0}, z},
      {b.disc({0, 0, 0}, z, 0.5, {R, F}), {0.2, 0, 0}, z},
      {b.triangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {R, F}), {0.2, 0.2, 0}, z},
      {b.curve(curve_pts, {R, F}), {1, 0, 0}, z},
      {b.box({0, 0, 0}, {1, 1, 1}, {R, F}), {0.5, 0.5, 1}, z},
      {b.cylinder({0, 0, 0}, {0, 0, 1}, 0.3, {R, F}), {0, 0.3, 0.5}, {0, 1, 0}},
      {b.cone_sphere({0, 0, 0}, {2, 0, 0}, 0.5, 0.5, {R, F}), {1, 0.5, 0}, {0, 1, 0}},
  };
  const Tree whole = b.build(probes.back().node);
  for (const Probe& pr : probes) {
    const Tree t = whole.subtree(pr.node);
    const std::string kind(kind_name(t.graph().kind[pr.node]));
    EXPECT_NEAR(t.reference(pr.on), F, 1e-12) << kind;
    EXPECT_NEAR(t.reference(pr.on + r0 * pr.dir), kT, 1e-9) << kind;
    EXPECT_EQ(t.reference(pr.on + R * pr.dir), 0.0) << kind;
    EXPECT_EQ(t.reference(pr.on + 1.5 * R * pr.dir), 0.0) << kind;
    EXPECT_NEAR(t.reference(pr.on + 0.5 * R * pr.dir), F * std::pow(0.75, 3), 1e-9) << kind;
  }
}

TEST(Primitives, NegativeStrengthCarves) {
  Builder b(kT);
  const NodeId carve = b.point({0, 0, 0}, {1.0, -0.8});
  const Tree t = b.build(carve);
  EXPECT_NEAR(t.reference({0, 0, 0}), -0.8, 1e-15);
  EXPECT_EQ(t.reference({1, 0, 0}), 0.0);
}

TEST(Primitives, ZeroAreaTriangleIsItsEdges) {
  test::Rng rng(14);
  const dvec3 a(0.1, 0.2, 0.3), b(1.1, 0.7, -0.2);
  const dvec3 c = a + 0.37 * (b - a);  // exactly on the segment: zero area
  for (int i = 0; i < 1000; ++i) {
    const dvec3 p = test::random_point(rng, 2.0);
    EXPECT_NEAR(distance_to_triangle(p, a, b, c), distance_to_segment(p, a, b), 1e-12);
  }
}
