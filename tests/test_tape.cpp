// The tape against the reference tree evaluator: values and gradients on thousands of random
// trees (every node kind but ffd, every Boolean mode, nested warps, mesh leaves), region
// specialization (equal inside the box, strictly shorter where the box misses supports), and
// interval analysis holding every sampled value.
#include "nodes/mesh_leaf.hpp"
#include "nodes/primitives.hpp"
#include "runtime/builder.hpp"
#include "runtime/scene.hpp"
#include "runtime/tape.hpp"
#include "runtime/tape_eval.hpp"
#include "runtime/tree_eval.hpp"
#include "tests/support/random_tree.hpp"

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <string>

using namespace ht;
using glm::dvec3;

namespace {

constexpr double kT = 0.5;

// A float evaluator may land on the other side of a kink or a jump than the double one (bend's
// branch cut, a min/max switch, a mesh's medial axis). A tape value is accepted when it is within
// tolerance of the tree at p, or within the range the tree takes over a tiny neighbourhood of p
// (float rounding of p itself moves it by about 1e-7).
bool close_to_tree(const Graph& g, NodeId root, const dvec3& p, double tape, double tree, bool& conditioned) {
  const double tol = 1e-4 * std::max(1.0, std::abs(tree));
  conditioned = true;
  if (std::abs(tape - tree) <= tol) return true;
  conditioned = false;
  const double h = 1e-5 * std::max(1.0, glm::length(p));
  double lo = tree, hi = tree;
  for (int axis = 0; axis < 3; ++axis)
    for (double s : {-h, h}) {
      dvec3 q = p;
      q[axis] += s;
      const double f = reference_field(g, root, kT, q);
      lo = std::min(lo, f);
      hi = std::max(hi, f);
    }
  return tape >= lo - tol && tape <= hi + tol;
}

}  // namespace

TEST(Tape, EqualsTheTreeOnRandomTrees) {
  test::Rng rng(51);
  test::RandomTreeOptions opt;
  opt.meshes = test::small_meshes();
  std::size_t points = 0, ill_conditioned = 0;
  constexpr int kTrees = 2000, kPoints = 256;
  for (int trial = 0; trial < kTrees; ++trial) {
    Builder b(kT);
    const NodeId root = test::random_tree(b, rng, opt);
    const Tree t = b.build(root);
    const auto tape = std::make_shared<const Tape>(compile_tape(t.graph_ptr(), root, kT));
    const TapeEvaluator eval(tape);
    std::vector<dvec3> pts(kPoints);
    for (auto& p : pts) p = test::random_point(rng, 2.5);
    std::vector<double> values(pts.size());
    eval.field(pts, values);
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const double tree = reference_field(t.graph(), root, kT, pts[i]);
      bool conditioned = true;
      ASSERT_TRUE(close_to_tree(t.graph(), root, pts[i], values[i], tree, conditioned))
          << "trial " << trial << " point " << pts[i].x << " " << pts[i].y << " " << pts[i].z << ": tape "
          << values[i] << " tree " << tree << "\n"
          << tape->listing();
      ++points;
      ill_conditioned += conditioned ? 0 : 1;
    }
  }
  // Points that needed the neighbourhood rule must stay rare.
  EXPECT_LT(static_cast<double>(ill_conditioned), 1e-3 * static_cast<double>(points)) << ill_conditioned;
}

TEST(Tape, EveryInstructionSetGivesTheSameValues) {
  // Each build (runtime/tape_eval.hpp TapeIsa) this CPU can run: values equal to the tree as
  // above, and values and gradients bit for bit those of the baseline build, since no build
  // contracts or reassociates.
  std::vector<TapeIsa> builds;
  for (const TapeIsa isa : {TapeIsa::Baseline, TapeIsa::Sse4, TapeIsa::Avx2, TapeIsa::Avx512})
    if (tape_isa_supported(isa)) builds.push_back(isa);
  ASSERT_EQ(builds.front(), TapeIsa::Baseline);
  const TapeIsa widest = tape_isa();
  test::Rng rng(53);
  test::RandomTreeOptions opt;
  opt.meshes = test::small_meshes();
  constexpr int kTrees = 400, kPoints = 300;  // 300: a full block and a ragged one
  for (int trial = 0; trial < kTrees; ++trial) {
    Builder b(kT);
    const NodeId root = test::random_tree(b, rng, opt);
    const Tree t = b.build(root);
    const TapeEvaluator eval(std::make_shared<const Tape>(compile_tape(t.graph_ptr(), root, kT)));
    std::vector<dvec3> pts(kPoints);
    for (auto& p : pts) p = test::random_point(rng, 2.5);
    std::vector<double> base(pts.size()), values(pts.size()), grad_values(pts.size());
    std::vector<dvec3> base_grad(pts.size()), grad(pts.size());
    for (const TapeIsa isa : builds) {
      force_tape_isa(isa);
      eval.field(pts, isa == TapeIsa::Baseline ? base : values);
      eval.gradient(pts, grad_values, isa == TapeIsa::Baseline ? base_grad : grad);
      if (isa == TapeIsa::Baseline) continue;
      for (std::size_t i = 0; i < pts.size(); ++i)
        ASSERT_EQ(grad[i], base_grad[i]) << tape_isa_name(isa) << " gradient, trial " << trial << " point " << i;
      for (std::size_t i = 0; i < pts.size(); ++i) {
        bool conditioned = true;
        const double tree = reference_field(t.graph(), root, kT, pts[i]);
        ASSERT_TRUE(close_to_tree(t.graph(), root, pts[i], values[i], tree, conditioned))
            << tape_isa_name(isa) << " trial " << trial << " point " << i;
        ASSERT_EQ(values[i], base[i]) << tape_isa_name(isa) << " trial " << trial << " point " << i;
      }
    }
  }
  force_tape_isa(widest);
  std::printf("builds compared:");
  for (const TapeIsa isa : builds) std::printf(" %s", tape_isa_name(isa));
  std::printf("\n");
  EXPECT_THROW(force_tape_isa(static_cast<TapeIsa>(200)), std::invalid_argument);
}

// A curve's lanes outside every group's ball (runtime/tape.hpp) are 0 without a distance: the
// balls must reach R past the polyline, never less. Points in a thin shell around the support's
// edge and anywhere in its box, on short curves (a tenth of R long, as the snake's) and long ones (R a tenth of their
// length), in blocks of many points: every point nearer than R is nonzero on both the values'
// and the gradients' path, every point farther is 0, and inside both equal the tree.
TEST(Tape, CurvesVanishExactlyWhereTheirSupportEnds) {
  test::Rng rng(57);
  auto uniform = [&rng](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
  std::size_t near = 0, far = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const bool short_curve = trial % 2 == 0;
    const double R = short_curve ? 0.6 : 0.08;
    const double scale = short_curve ? 0.06 : 1.0;
    std::vector<dvec3> control;
    for (int i = 0; i < 3 + trial % 4; ++i) control.push_back(scale * test::random_point(rng, 1.0) + dvec3(0.3, -0.2, 0.1));
    Builder b(kT);
    const NodeId root = b.curve(control, {R, 1.0});
    const Tree t = b.build(root);
    const TapeEvaluator eval(std::make_shared<const Tape>(compile_tape(t.graph_ptr(), root, kT)));
    const double* skeleton = t.graph().skeleton_of(root);
    std::vector<dvec3> pts;
    for (int i = 0; i < 2000; ++i) {
      const std::size_t span = std::size_t(uniform(0.0, double(control.size() - 1) - 1e-9));
      const dvec3 on = catmull_rom(control, span, uniform(0.0, 1.0));
      const dvec3 dir = glm::normalize(test::random_point(rng, 1.0) + dvec3(1e-9));
      pts.push_back(on + R * (1.0 + uniform(-3e-3, 3e-3)) * dir);
    }
    // And anywhere in the support box, where the box's corners lie beyond the balls.
    Aabb box;
    for (const dvec3& c : control) box.grow(c);
    box = box.expanded(1.1 * R);
    for (int i = 0; i < 2000; ++i)
      pts.push_back(box.lo + dvec3(uniform(0, 1), uniform(0, 1), uniform(0, 1)) * box.size());
    std::vector<double> values(pts.size()), grad_values(pts.size());
    std::vector<dvec3> grads(pts.size());
    eval.field(pts, values);
    eval.gradient(pts, grad_values, grads);
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const double d = skeleton_distance(NodeKind::Curve, skeleton, pts[i]);
      const std::string where = "trial " + std::to_string(trial) + " point " + std::to_string(i) + " at " +
                                std::to_string(d / R) + " R";
      if (d < R * (1.0 - 1e-4)) {
        ++near;
        ASSERT_GT(values[i], 0.0) << where;
        ASSERT_GT(grad_values[i], 0.0) << where;
        ASSERT_NEAR(values[i], reference_field(t.graph(), root, kT, pts[i]), 1e-4) << where;
      } else if (d > R * (1.0 + 1e-4)) {
        ++far;
        ASSERT_EQ(values[i], 0.0) << where;
        ASSERT_EQ(grad_values[i], 0.0) << where;
      }
    }
  }
  EXPECT_GT(near, 20000u);
  EXPECT_GT(far, 20000u);
}

TEST(Tape, ChainsOfBlendsHoldTwoRegisters) {
  // 900 points blended two at a time, as a user writes them: nested to the left and to the
  // right. Blends are summed in place, so the tape holds the input frame, the sum and one term
  // (before, the right-deep chain held a register per level).
  for (const bool right : {false, true}) {
    Builder b(kT);
    std::vector<NodeId> points;
    for (int i = 0; i < 900; ++i) points.push_back(b.point({0.01 * i, 0.02 * (i % 7), 0.0}, {0.3}));
    NodeId chain = points[0];
    for (int i = 1; i < 900; ++i) chain = right ? b.blend({points[std::size_t(i)], chain}) : b.blend({chain, points[std::size_t(i)]});
    const Tree t = b.build(chain);
    const Tape tape = compile_tape(t.graph_ptr(), chain, kT, nullptr, false, /*guards=*/false);
    EXPECT_EQ(tape.leaf_count(), 900u);
    EXPECT_EQ(tape.size(), 1799u);
    EXPECT_LE(tape.registers, 5u) << (right ? "right" : "left");
    // With Skip guards the points in order along x make prefixes of the chain that are guarded
    // where their box is under half their parent's: a register more a level, a few levels.
    const Tape guarded = compile_tape(t.graph_ptr(), chain, kT);
    EXPECT_GT(guarded.skips, 0u);
    EXPECT_EQ(guarded.size(), 1799u + guarded.skips);
    EXPECT_LE(guarded.registers, 5u + 2u * guarded.skips) << (right ? "right" : "left");
    const TapeEvaluator eval(std::make_shared<const Tape>(guarded));
    for (const dvec3& p : {dvec3(0.5, 0.05, 0.0), dvec3(4.0, 0.1, 0.05), dvec3(8.95, 0.0, 0.0)}) {
      const double want = reference_field(t.graph(), chain, kT, p);
      EXPECT_NEAR(eval.field(p), want, 1e-4 * std::max(1.0, std::abs(want))) << p.x;
    }
  }
}

TEST(Tape, GradientsEqualTheTreeOnRandomTrees) {
  test::Rng rng(52);
  test::RandomTreeOptions opt;
  opt.meshes = test::small_meshes();
  std::size_t compared = 0, skipped = 0;
  for (int trial = 0; trial < 300; ++trial) {
    Builder b(kT);
    const NodeId root = test::random_tree(b, rng, opt);
    const Tree t = b.build(root);
    const TapeEvaluator eval(std::make_shared<const Tape>(compile_tape(t.graph_ptr(), root, kT)));
    std::vector<dvec3> pts(64);
    for (auto& p : pts) p = test::random_point(rng, 2.5);
    std::vector<double> values(pts.size());
    std::vector<dvec3> grads(pts.size());
    eval.gradient(pts, values, grads);
    for (std::size_t i = 0; i < pts.size(); ++i) {
      // Central differences are only a reference where the field is smooth around p: compare
      // where two step sizes agree.
      const dvec3 g1 = reference_gradient(t.graph(), root, kT, pts[i]);
      dvec3 g2;
      const double h = 1e-4;
      for (int axis = 0; axis < 3; ++axis) {
        dvec3 a = pts[i], c = pts[i];
        a[axis] += h;
        c[axis] -= h;
        g2[axis] = (reference_field(t.graph(), root, kT, a) - reference_field(t.graph(), root, kT, c)) / (2 * h);
      }
      const double scale = std::max(1.0, glm::length(g1));
      if (glm::length(g1 - g2) > 1e-4 * scale) {
        ++skipped;
        continue;
      }
      ++compared;
      EXPECT_NEAR(glm::length(grads[i] - g1), 0.0, 1e-3 * scale)
          << "trial " << trial << " at " << pts[i].x << " " << pts[i].y << " " << pts[i].z;
      EXPECT_NEAR(values[i], reference_field(t.graph(), root, kT, pts[i]), 1e-4 * std::max(1.0, std::abs(values[i])));
    }
  }
  EXPECT_GT(compared, 10u * skipped);
}

TEST(Tape, SpecializedTapeEqualsFullTapeInsideItsBox) {
  test::Rng rng(53);
  test::RandomTreeOptions opt;
  opt.meshes = test::small_meshes();
  std::size_t shorter = 0, trials = 0;
  for (int trial = 0; trial < 600; ++trial) {
    Builder b(kT);
    const NodeId root = test::random_tree(b, rng, opt);
    const Tree t = b.build(root);
    const auto full = std::make_shared<const Tape>(compile_tape(t.graph_ptr(), root, kT));
    const dvec3 lo = test::random_point(rng, 2.5);
    const double size = std::uniform_real_distribution<double>(0.05, 1.5)(rng);
    const Aabb box{lo, lo + dvec3(size)};
    const auto part = std::make_shared<const Tape>(compile_tape(t.graph_ptr(), root, kT, &box));
    ASSERT_LE(part->size(), full->size());
    const TapeEvaluator ef(full), ep(part);
    std::vector<dvec3> pts(128);
    for (auto& p : pts)
      p = lo + size * dvec3(std::uniform_real_distribution<double>(0, 1)(rng), std::uniform_real_distribution<double>(0, 1)(rng),
                            std::uniform_real_distribution<double>(0, 1)(rng));
    std::vector<double> vf(pts.size()), vp(pts.size());
    ef.field(pts, vf);
    ep.field(pts, vp);
    for (std::size_t i = 0; i < pts.size(); ++i)
      ASSERT_NEAR(vp[i], vf[i], 1e-5 * std::max(1.0, std::abs(vf[i]))) << "trial " << trial << "\nfull\n"
                                                                         << full->listing() << "part\n"
                                                                         << part->listing();
    ++trials;
    shorter += part->size() < full->size() ? 1 : 0;
  }
  EXPECT_GT(shorter, trials / 10);
}

TEST(Tape, SpecializationDropsPrimitivesWhoseSupportMissesTheBox) {
  // A row of 100 points 1 apart with radius 0.6: a box around one of them keeps only it.
  Builder b(kT);
  std::vector<NodeId> parts;
  for (int i = 0; i < 100; ++i) parts.push_back(b.point({i, 0, 0}, {0.6}));
  const NodeId root = b.blend(parts);
  const Tree t = b.build(root);
  const Tape full = compile_tape(t.graph_ptr(), root, kT);
  EXPECT_EQ(full.leaf_count(), 100u);
  const Aabb box{{41.8, -0.2, -0.2}, {42.2, 0.2, 0.2}};
  const Tape part = compile_tape(t.graph_ptr(), root, kT, &box);
  EXPECT_EQ(part.leaf_count(), 1u);
  EXPECT_EQ(part.size(), 1u);
  const Aabb nowhere{{500, 500, 500}, {501, 501, 501}};
  const Tape none = compile_tape(t.graph_ptr(), root, kT, &nowhere);
  EXPECT_EQ(none.leaf_count(), 0u);
  EXPECT_EQ(none.size(), 1u);  // Zero
}

TEST(Tape, DecidedMinMaxBranchesAreDropped) {
  Builder b(kT);
  const NodeId big = b.point({0, 0, 0}, {2.0, 3.0});
  const NodeId small = b.point({0.3, 0, 0}, {0.5, 0.6});
  const NodeId u = b.unite({big, small}, BooleanMode::MinMax);
  const Tree t = b.build(u);
  const Aabb near_centre{{-0.05, -0.05, -0.05}, {0.05, 0.05, 0.05}};  // big ~ 3 here, small <= 0.6
  const Tape part = compile_tape(t.graph_ptr(), u, kT, &near_centre);
  EXPECT_EQ(part.leaf_count(), 1u);
  EXPECT_EQ(compile_tape(t.graph_ptr(), u, kT).leaf_count(), 2u);
}

TEST(Tape, IntervalsHoldEverySampledValue) {
  test::Rng rng(54);
  test::RandomTreeOptions opt;
  opt.meshes = test::small_meshes();
  for (int trial = 0; trial < 300; ++trial) {
    Builder b(kT);
    const NodeId root = test::random_tree(b, rng, opt);
    const Tree t = b.build(root);
    const dvec3 lo = test::random_point(rng, 2.5);
    const double size = std::uniform_real_distribution<double>(0.05, 1.5)(rng);
    const Aabb box{lo, lo + dvec3(size)};
    for (NodeId n = 0; n < t.graph().size(); ++n)
      for (bool blended : {false, true}) {
        const Interval iv = field_interval(t.graph(), n, kT, box, blended);
        for (int i = 0; i < 16; ++i) {
          const dvec3 p = lo + size * dvec3(std::uniform_real_distribution<double>(0, 1)(rng),
                                            std::uniform_real_distribution<double>(0, 1)(rng),
                                            std::uniform_real_distribution<double>(0, 1)(rng));
          const double f = reference_field(t.graph(), n, kT, p, blended);
          ASSERT_GE(f, iv.lo - 1e-9) << t.graph().label(n) << " trial " << trial;
          ASSERT_LE(f, iv.hi + 1e-9) << t.graph().label(n) << " trial " << trial;
        }
      }
  }
}

TEST(Tape, DeepInsideAMeshTheLeafIsAConstant) {
  Builder b(kT);
  const auto leaf = MeshLeaf::load(test::cgal_mesh("sphere.off"));  // radius 0.5 about the origin
  const NodeId m = b.mesh(leaf, {0.05, 1.3});
  const NodeId root = b.blend({m, b.point({2, 0, 0}, {0.5})});
  const Tree t = b.build(root);
  const Aabb inside{{-0.1, -0.1, -0.1}, {0.1, 0.1, 0.1}};
  const auto tape = std::make_shared<const Tape>(compile_tape(t.graph_ptr(), root, kT, &inside));
  EXPECT_EQ(tape->leaf_count(), 0u);
  ASSERT_EQ(tape->size(), 1u);
  EXPECT_EQ(tape->code[0].op, OpCode::Constant);
  EXPECT_FLOAT_EQ(TapeEvaluator(tape).field({0.05, 0, 0}), 1.3f);
}

TEST(Tape, FfdCannotCompileYet) {
  Builder b(kT);
  const NodeId p = b.point({0, 0, 0}, {1});
  std::vector<dvec3> lattice;
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) lattice.push_back({i, j, k});
  const NodeId f = b.ffd(p, {0, 0, 0}, {1, 1, 1}, {1, 1, 1}, lattice, {0.1});
  const Tree t = b.build(f);
  EXPECT_THROW(compile_tape(t.graph_ptr(), f, kT), CompileError);
}

// The tape computes in floats: a parameter past their range became infinite there, and a ball
// twisted at a rate of 4e38 was 0 in the tape and 1 in the tree (meshed as empty). Such a tree is
// refused by the compiler, naming the node; just inside the range it compiles and agrees.
TEST(Tape, NumbersPastTheFloatRangeAreRefused) {
  for (double rate : {3e38, 4e38, -1e39}) {
    Builder b(kT);
    const Tree t = b.build(b.twist(b.point({0, 0, 0}, {1}), Axis::Z, {0, 0, 0}, rate));
    if (std::abs(rate) < 3.4e38) {
      const TapeEvaluator e(std::make_shared<const Tape>(compile_tape(t.graph_ptr(), t.root(), kT)));
      EXPECT_FLOAT_EQ(e.field({0, 0, 0}), float(t.reference({0, 0, 0})));
      continue;
    }
    try {
      (void)compile_tape(t.graph_ptr(), t.root(), kT);
      ADD_FAILURE() << "rate " << rate << " compiled";
    } catch (const FloatRangeError& e) {
      EXPECT_NE(std::string(e.what()).find("node twist #1: its field needs the number"), std::string::npos) << e.what();
    }
  }
  // A ball's radius whose square passes the range.
  Builder b(kT);
  const Tree t = b.build(b.point({0, 0, 0}, {1e20}));
  EXPECT_THROW(compile_tape(t.graph_ptr(), t.root(), kT), FloatRangeError);
  // A scale whose inverse underflows: every point of space went to the child's origin.
  const Tree huge = b.build(b.affine(b.point({0, 0, 0}, {1}), glm::scale(glm::dmat4(1.0), dvec3(1e45))));
  EXPECT_THROW(compile_tape(huge.graph_ptr(), huge.root(), kT), FloatRangeError);
  const Tree large = b.build(b.affine(b.point({0, 0, 0}, {1}), glm::scale(glm::dmat4(1.0), dvec3(1e30))));
  const TapeEvaluator e(std::make_shared<const Tape>(compile_tape(large.graph_ptr(), large.root(), kT)));
  for (const dvec3 p : {dvec3(0, 0, 0), dvec3(3e29, 0, 0), dvec3(0, 6e29, 1e29)})
    EXPECT_NEAR(e.field(p), large.reference(p), 1e-5) << p.x << " " << p.y;
}

// A collinear triangle of small, ordinary coordinates: the rounding residue of its normal's
// cross product made 1/|n|^2 = 1.8e47, refused as past the float range. A squared length whose
// inverse no float holds is degenerate to the tape, as an exact 0 is (its edges alone), and the
// tape agrees with the tree.
TEST(Tape, NearlyDegenerateSkeletonsAreTheirEdges) {
  const Tree t = load_scene(std::filesystem::path(HYBRIDTREE_SOURCE_DIR) / "tests/data/stress/collinear_triangle_small.json");
  const TapeEvaluator e(std::make_shared<const Tape>(compile_tape(t.graph_ptr(), t.root(), kT)));
  test::Rng rng(35);
  for (int i = 0; i < 2000; ++i) {
    const dvec3 p = 3e-4 * test::random_point(rng, 1.0);
    EXPECT_NEAR(e.field(p), t.reference(p), 1e-4) << p.x << " " << p.y << " " << p.z;
  }
  // Degenerate is measured against the skeleton's own scale: a right triangle 1e-10 wide is no
  // set of edges (its 1/|n|^2, 1e40, is past the float range: refused, not silently wrong).
  Builder b(kT);
  const Tree tiny = b.build(b.triangle({0, 0, 0}, {1e-10, 0, 0}, {0, 1e-10, 0}, {1e-10}));
  EXPECT_THROW(compile_tape(tiny.graph_ptr(), tiny.root(), kT), FloatRangeError);
  const Tree seg = b.build(b.segment({0, 0, 0}, {1e-21, 0, 0}, {0.5}));
  const TapeEvaluator es(std::make_shared<const Tape>(compile_tape(seg.graph_ptr(), seg.root(), kT)));
  EXPECT_NEAR(es.field({0.2, 0, 0}), seg.reference({0.2, 0, 0}), 1e-6);
}

TEST(Tape, ResultsDoNotDependOnBlockBoundariesOrThreads) {
  test::Rng rng(55);
  Builder b(kT);
  const NodeId root = test::random_tree(b, rng, {});
  const Tree t = b.build(root);
  const TapeEvaluator eval(std::make_shared<const Tape>(compile_tape(t.graph_ptr(), root, kT)));
  std::vector<dvec3> pts(3 * kBlock + 17);
  for (auto& p : pts) p = test::random_point(rng, 2.5);
  std::vector<double> all(pts.size());
  eval.field(pts, all);
  for (std::size_t i = 0; i < pts.size(); i += 7) EXPECT_EQ(all[i], static_cast<double>(eval.field(pts[i])));
}
