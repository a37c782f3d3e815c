// Free-form deformation: the deformed mesh of the child carries the field; a lattice placed
// linearly is an affine map (Bernstein polynomials reproduce linear functions), so volumes scale
// exactly; the tape and the reference evaluator agree on prepared ffd nodes; scenes with ffd
// evaluate and mesh from the command line.
#include "meshers/ffd.hpp"
#include "meshers/mesh_checks.hpp"
#include "meshers/mesh_plan.hpp"
#include "nodes/mesh_leaf.hpp"
#include "meshers/polygonize.hpp"
#include "nodes/primitives.hpp"
#include "nodes/warps.hpp"
#include "runtime/builder.hpp"
#include "runtime/tape_eval.hpp"
#include "runtime/tree_eval.hpp"
#include "tests/support/random_tree.hpp"

#include <gtest/gtest.h>

#include <algorithm>

using namespace ht;
using glm::dvec3;

namespace {

constexpr double kT = 0.5;

// A (l+1)(m+1)(n+1) lattice over [lo, hi] whose points are p -> lo + stretch * (p - lo).
std::vector<dvec3> linear_lattice(dvec3 lo, dvec3 hi, glm::ivec3 dims, dvec3 stretch) {
  std::vector<dvec3> pts;
  for (int k = 0; k <= dims.z; ++k)
    for (int j = 0; j <= dims.y; ++j)
      for (int i = 0; i <= dims.x; ++i) {
        const dvec3 t(double(i) / dims.x, double(j) / dims.y, double(k) / dims.z);
        pts.push_back(lo + stretch * (t * (hi - lo)));
      }
  return pts;
}

double meshed_volume(const Tree& t, double h, MeshChecks* checks = nullptr) {
  PolygonizeOptions o;
  o.precision = h;
  const TriangleMesh m = polygonize(t.graph_ptr(), t.root(), kT, o);
  const MeshChecks c = check_mesh(m);
  if (checks) *checks = c;
  return c.volume;
}

}  // namespace

TEST(Ffd, LinearLatticeStretchesTheVolumeExactly) {
  Builder b(kT);
  const NodeId child = b.segment({-0.3, 0, 0}, {0.3, 0, 0}, {0.6});
  const dvec3 lo(-1, -1, -1), hi(1, 1, 1);
  const NodeId ffd = b.ffd(child, lo, hi, {3, 2, 2}, linear_lattice(lo, hi, {3, 2, 2}, {2.0, 1.0, 1.0}), {0.1, 1.0});
  const Tree raw = b.build(ffd);
  EXPECT_TRUE(needs_ffd_preparation(raw.graph(), ffd));
  const Tree t = prepare_ffd(raw, 0.02);
  EXPECT_FALSE(needs_ffd_preparation(t.graph(), ffd));
  MeshChecks c;
  const double v = meshed_volume(t, 0.02, &c);
  EXPECT_TRUE(c.watertight());
  EXPECT_EQ(c.genus, 0);
  const double v0 = meshed_volume(raw.subtree(child), 0.02);
  EXPECT_NEAR(v / v0, 2.0, 0.06);
  // On the deformed surface the field is T; the deformed mesh is the child's surface stretched.
  const dvec3 tip = dvec3(-1, 0, 0) + dvec3(2, 1, 1) * (dvec3(0.3 + primitive_r0(0.6, 1.0, kT), 0, 0) - dvec3(-1, 0, 0));
  EXPECT_NEAR(t.reference(tip), kT, 0.02);
}

TEST(Ffd, TapeAndTreeAgreeOnPreparedFfd) {
  test::Rng rng(71);
  Builder b(kT);
  const NodeId child = b.blend({b.point({0, 0, 0}, {0.8}), b.box({0, -0.2, -0.2}, {0.5, 0.2, 0.2}, {0.3})});
  const dvec3 lo(-0.8, -0.8, -0.8), hi(0.8, 0.8, 0.8);
  auto pts = linear_lattice(lo, hi, {2, 2, 2}, {1, 1, 1});
  pts[13] += dvec3(0.3, 0.2, 0.0);  // pull the middle control point
  const NodeId ffd = b.ffd(child, lo, hi, {2, 2, 2}, pts, {0.15, 1.2});
  const NodeId root = b.blend({ffd, b.segment({0, 0, 0.5}, {0, 0, 1}, {0.3})});
  const Tree t = prepare_ffd(b.build(root), 0.03);
  std::vector<dvec3> q(2000);
  for (auto& p : q) p = test::random_point(rng, 1.2);
  std::vector<double> tape(q.size());
  t.field(q, tape);
  for (std::size_t i = 0; i < q.size(); ++i) {
    const double ref = t.reference(q[i]);
    EXPECT_NEAR(tape[i], ref, 1e-4 * std::max(1.0, std::abs(ref))) << q[i].x << " " << q[i].y << " " << q[i].z;
  }
  MeshChecks c;
  meshed_volume(t, 0.03, &c);
  EXPECT_TRUE(c.watertight());
}

// An ffd of a child whose solid is empty (a primitive weaker than the threshold alone) deforms
// nothing: its field is 0 everywhere, so beside another operand the result is that operand's, and
// alone it is empty. The run used to stop ("its child's surface is empty").
TEST(Ffd, AnEmptyChildDeformsToNothing) {
  test::Rng rng(72);
  Builder b(kT);
  const dvec3 lo(-0.8, -0.8, -0.8), hi(0.8, 0.8, 0.8);
  auto pts = linear_lattice(lo, hi, {1, 1, 1}, {1, 1, 1});
  pts[7] += dvec3(0.2, 0.1, 0.0);
  const NodeId ffd = b.ffd(b.point({0, 0, 0}, {0.6, 0.4}), lo, hi, {1, 1, 1}, pts, {0.15, 1.0});
  const NodeId ball = b.point({1.2, 0, 0}, {0.6});
  const Tree both = b.build(b.blend({ffd, ball}));
  const Tree alone = b.build(ffd), ball_alone = b.build(ball);
  const Tree t = prepare_ffd(both, 0.03);
  std::vector<dvec3> q(2000);
  for (auto& p : q) p = test::random_point(rng, 1.5);
  std::vector<double> tape(q.size()), ref(q.size());
  t.field(q, tape);
  ball_alone.field(q, ref);
  for (std::size_t i = 0; i < q.size(); ++i) {
    EXPECT_EQ(tape[i], ref[i]) << i;
    EXPECT_EQ(t.reference(q[i]), ball_alone.reference(q[i])) << i;
  }
  MeshOptions mo;
  mo.precision = 0.03;
  const MeshResult with = mesh_tree(both, mo), ball_only = mesh_tree(ball_alone, mo), none = mesh_tree(alone, mo);
  const MeshChecks c = check_mesh(*with.mesh), c0 = check_mesh(*ball_only.mesh);
  EXPECT_TRUE(c.watertight());
  EXPECT_EQ(c.components, 1u);
  EXPECT_NEAR(c.volume / c0.volume, 1.0, 0.01);
  EXPECT_TRUE(none.mesh->triangles.empty());
}

TEST(Ffd, PointsOutsideTheLatticeDoNotMove) {
  Builder b(kT);
  const dvec3 lo(0, 0, 0), hi(1, 1, 1);
  auto pts = linear_lattice(lo, hi, {1, 1, 1}, {1, 1, 1});
  pts[7] += dvec3(0.5, 0.5, 0.5);
  const NodeId f = b.ffd(b.point({0, 0, 0}, {0.5}), lo, hi, {1, 1, 1}, pts, {0.1});
  const Tree t = b.build(f);
  const double* prm = t.graph().params_of(f).data();
  EXPECT_EQ(warp_forward(NodeKind::Ffd, prm, dvec3(-0.5, 0.3, 2.0)), dvec3(-0.5, 0.3, 2.0));
  EXPECT_NEAR(glm::length(warp_forward(NodeKind::Ffd, prm, dvec3(1, 1, 1)) - dvec3(1.5, 1.5, 1.5)), 0.0, 1e-12);
}

// The deformation is the trivariate Bernstein polynomial of the lattice: checked against de
// Casteljau's algorithm (repeated linear interpolation, no powers or binomials) on random lattices
// of every size up to the format's limit, where large binomials and high powers would show.
TEST(Ffd, DeformationIsDeCasteljauOfTheLattice) {
  test::Rng rng = test::seeded();
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto casteljau = [](std::vector<dvec3> q, double t) {
    for (std::size_t n = q.size(); n > 1; --n)
      for (std::size_t i = 0; i + 1 < n; ++i) q[i] = (1.0 - t) * q[i] + t * q[i + 1];
    return q[0];
  };
  const glm::ivec3 sizes[] = {{1, 1, 1}, {3, 2, 5}, {8, 2, 2}, {kFfdMaxDim, 1, 2}, {2, kFfdMaxDim, 1}, {1, 3, kFfdMaxDim}};
  for (const glm::ivec3 dims : sizes) {
    Builder b(kT);
    const dvec3 lo(-1.0, -0.5, 0.0), hi(1.0, 0.5, 2.0);
    auto pts = linear_lattice(lo, hi, dims, {1, 1, 1});
    for (dvec3& p : pts) p += 0.2 * test::random_point(rng, 1.0);
    const NodeId f = b.ffd(b.point({0, 0, 0}, {0.5}), lo, hi, dims, pts, {0.1});
    const Tree t = b.build(f);
    const double* prm = t.graph().params_of(f).data();
    for (int trial = 0; trial < 20; ++trial) {
      const dvec3 u(unit(rng), unit(rng), unit(rng));
      // Along x first, then y, then z, as the points are stored.
      std::vector<dvec3> in_z;
      for (int k = 0; k <= dims.z; ++k) {
        std::vector<dvec3> in_y;
        for (int j = 0; j <= dims.y; ++j) {
          const auto row = pts.begin() + (dims.x + 1) * (j + (dims.y + 1) * k);
          in_y.push_back(casteljau(std::vector<dvec3>(row, row + dims.x + 1), u.x));
        }
        in_z.push_back(casteljau(in_y, u.y));
      }
      const dvec3 expected = casteljau(in_z, u.z);
      const dvec3 got = warp_forward(NodeKind::Ffd, prm, lo + u * (hi - lo));
      EXPECT_LT(glm::length(got - expected), 1e-12) << dims.x << " " << dims.y << " " << dims.z;
    }
  }
}

// A lattice that pushes one ball through the other: the shells cross and unfolding cannot undo
// that. The deformed mesh becomes a winding leaf (a closed leaf would refuse crossing shells),
// the pairs left are reported, and the node's surface is polygonized from that leaf's field:
// closed, and crossing nothing. The mesh leaf built while the search runs (taking it to find
// nothing) must not be what comes back.
TEST(Ffd, CrossingShellsTheLatticeMakesArePolygonized) {
  Builder b(kT);
  const NodeId child = b.unite({b.point({-0.5, 0, 0}, {0.6}), b.point({0.5, 0, 0}, {0.6})});
  const dvec3 lo(-1, -1, -1), hi(1, 1, 1);
  auto pts = linear_lattice(lo, hi, {2, 1, 1}, {1, 1, 1});
  for (std::size_t i = 0; i < pts.size(); i += 3) pts[i + 1].x = 1.0, pts[i + 2].x = -1.0;  // x folds back at 0
  const NodeId ffd = b.ffd(child, lo, hi, {2, 1, 1}, pts, {0.1, 1.0});
  const Tree t = b.build(ffd);
  PolygonizeOptions o;
  o.precision = 0.05;
  const TriangleMesh balls = polygonize(t.graph_ptr(), child, kT, o);
  ASSERT_EQ(check_mesh(balls).components, 2u);
  std::size_t crossing = 0;
  const auto leaf = deform_child_mesh(t.graph_ptr(), ffd, balls, 0.0, kT, &crossing);
  EXPECT_GT(crossing, 0u);
  EXPECT_EQ(leaf->report().inside, MeshInside::Winding);
  MeshOptions mo;
  mo.precision = 0.05;
  const MeshResult r = mesh_tree(t, mo);
  const NodeReport& root = *std::find_if(r.nodes.begin(), r.nodes.end(), [&](const NodeReport& n) { return n.node == ffd; });
  EXPECT_EQ(root.reason, JobReason::Fallback);
  EXPECT_NE(root.fallback_cause.find("the deformed mesh overlaps itself"), std::string::npos) << root.fallback_cause;
  const MeshChecks c = check_mesh(*r.mesh);
  EXPECT_TRUE(c.watertight());
  EXPECT_EQ(c.self_intersecting_pairs, 0u);
  EXPECT_GT(c.triangles, 0u);
  // Meshed again from the prepared tree, whose ffd carries the winding leaf: polygonized again,
  // not the crossing mesh as a shared leaf.
  const MeshResult again = mesh_tree(*r.tree, mo);
  EXPECT_EQ(again.nodes.back().strategy, JobStrategy::Global);
  EXPECT_EQ(check_mesh(*again.mesh).self_intersecting_pairs, 0u);
}

// A lattice whose outer control points are moved tears the child where it leaves the lattice
// box (points outside it are unmoved): edges across the tear stay long however often they are
// halved, and refining them for ten passes filled the tear with slivers
// (tests/data/stress/ffd_timeout_noroot.json ran past two minutes). An edge 32 times shorter than
// the limit in the child's space is no longer split; the torn band's crossings make the node's
// surface a polygonization.
TEST(Ffd, ALatticeThatTearsTheChildEndsAndCrossesNothing) {
  Builder b(kT);
  const NodeId child = b.segment({-0.2, -0.2, -0.7}, {0.2, 0.2, 0.7}, {0.5, 1.0});
  const dvec3 lo(-0.6, -0.6, -0.6), hi(1, 1, 1);
  auto pts = linear_lattice(lo, hi, {1, 1, 1}, {1, 1, 1});
  for (dvec3& p : pts) p += dvec3(-0.1, -0.08, -0.09);  // the whole lattice shifted: a jump at its faces
  const NodeId ffd = b.ffd(child, lo, hi, {1, 1, 1}, pts, {0.1, 1.0});
  const Tree t = b.build(ffd);
  const double h = 0.05;
  PolygonizeOptions o;
  o.precision = h;
  const TriangleMesh capsule = polygonize(t.graph_ptr(), child, kT, o);
  std::size_t crossing = 0;
  const auto leaf = deform_child_mesh(t.graph_ptr(), ffd, capsule, 1.5 * h, kT, &crossing);
  // Unbounded: 49,794 triangles from 5,508, slivers across the tear whose boxes overlap by the
  // thousand (the search for their crossings took 35 s).
  EXPECT_LT(leaf->report().triangles, 4 * capsule.triangles.size());
  EXPECT_GT(crossing, 0u);
  MeshOptions mo;
  mo.precision = h;
  const MeshResult r = mesh_tree(t, mo);
  const MeshChecks c = check_mesh(*r.mesh);
  EXPECT_TRUE(c.watertight());
  EXPECT_EQ(c.self_intersecting_pairs, 0u);
  EXPECT_GT(c.triangles, 0u);
}

// A lattice that stretches its child a million times along x (the second stress run): the
// deformed mesh's refinement asked for billions of triangles and filled memory for 71 s. It stops
// where the budget would run out and says so, naming the node.
TEST(Ffd, ALatticeStretchingPastTheBudgetStopsAndSaysSo) {
  Builder b(kT);
  const NodeId child = b.point({0, 0, 0}, {1.0});
  const dvec3 lo(-1.2), hi(1.2);
  auto pts = linear_lattice(lo, hi, {1, 1, 1}, {1, 1, 1});
  for (dvec3& p : pts) p.x *= 1e6;
  const Tree t = b.build(b.ffd(child, lo, hi, {1, 1, 1}, pts, {0.1, 1.0}));
  MeshOptions o;
  o.precision = 0.05;
  MemoryBudget budget(std::size_t(64) << 20);
  o.polygonize.budget = &budget;
  try {
    mesh_tree(t, o);
    ADD_FAILURE() << "a sphere stretched to 2.4e6 meshed in 64 MiB";
  } catch (const MemoryBudgetError& e) {
    EXPECT_NE(std::string(e.what()).find("the deformed mesh of ffd node"), std::string::npos) << e.what();
  }
}
