// The paper's local strategies, through the mesh plan: trimmed Booleans, blends and crops on
// primitives and real meshes come out closed, oriented, manifold, free of self-intersections,
// with the expected genus; they agree with the global polygonizer (Hausdorff distance within the
// precision, volume within 1%), keep the untouched mesh-leaf vertices bit for bit, and give the
// same bytes at any thread count.
#include "meshers/local_parts.hpp"
#include "meshers/mesh_checks.hpp"
#include "meshers/sweep.hpp"
#include "meshers/warp_mesh.hpp"
#include "meshers/mesh_plan.hpp"
#include "nodes/mesh_leaf.hpp"
#include "runtime/builder.hpp"
#include "runtime/scene.hpp"
#include "tests/support/random_tree.hpp"

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <tbb/global_control.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <functional>
#include <set>

using namespace ht;
using glm::dvec3;

namespace {

constexpr double kT = 0.5;

MeshOptions at(double h, MeshStrategy s = MeshStrategy::Auto) { return test::mesh_options(h, s); }

std::shared_ptr<const MeshLeaf> bunny() {
  static const auto leaf = MeshLeaf::load(test::cgal_mesh("bunny00.off"));
  return leaf;
}
std::shared_ptr<const MeshLeaf> eight() {
  static const auto leaf = MeshLeaf::load(test::cgal_mesh("eight.off"));
  return leaf;
}
std::shared_ptr<const MeshLeaf> armadillo() {
  static const auto leaf = MeshLeaf::load(test::cgal_mesh("armadillo.off"));
  return leaf;
}

// The largest distance from samples of `a` (vertices and face centres) to the surface of `b`.
double one_sided(const TriangleMesh& a, const TriangleMesh& b) {
  const auto leaf = MeshLeaf::from_triangles(b.positions, b.triangles, "reference");
  double worst = 0;
  for (const dvec3& p : a.positions) worst = std::max(worst, leaf->query(p, 1e9).distance);
  for (const auto& t : a.triangles)
    worst = std::max(worst, leaf->query((a.positions[t[0]] + a.positions[t[1]] + a.positions[t[2]]) / 3.0, 1e9).distance);
  return worst;
}

const NodeReport& report_of(const MeshResult& r, NodeId n) {
  for (const NodeReport& e : r.nodes)
    if (e.node == n) return e;
  throw std::runtime_error("no job for the node");
}

// Meshes `root` locally and globally and holds the local result to the global one.
struct Case {
  const char* name;
  long genus;
  std::function<NodeId(Builder&)> make;
  JobStrategy expect;
};

// A local result: the strategy asked for, closed, oriented, manifold, no self-intersection, the
// expected genus, face centres on the surface, every vertex of the global result
// within the precision of it, and the same volume to 1%. (The other direction of the Hausdorff
// distance is not held to the precision: the global polygonizer chamfers the creases that the
// local Booleans keep exact, by up to 1.4 h on "segment - sphere".)
void expect_local(const MeshResult& r, const Tree& t, NodeId root, const Case& c, double h) {
  const NodeReport& job = report_of(r, root);
  EXPECT_EQ(job.strategy, c.expect) << c.name << ": " << to_string(job.strategy) << ", " << job.fallback_cause;
  MeshChecks k = check_mesh(*r.mesh);
  measure_surface_error(*r.mesh, t.evaluator(), kT, k);
  EXPECT_TRUE(k.watertight()) << c.name << ": boundary " << k.boundary_edges << " non-manifold " << k.nonmanifold_edges
                              << "/" << k.nonmanifold_vertices << " misoriented " << k.misoriented_edges << " degenerate "
                              << k.degenerate_triangles;
  EXPECT_EQ(k.self_intersecting_pairs, 0u) << c.name;
  EXPECT_EQ(k.genus, c.genus) << c.name;
  // Face centres: at a mesh leaf's own vertices the tape's gradient is not yet the one the scene
  // format defines (issue 14), so |f - T| / |grad f| is no distance estimate there.
  EXPECT_LT(k.face_error_max, 0.25 * h) << c.name;
  const MeshResult g = mesh_tree(t, at(h, MeshStrategy::Global));
  const MeshChecks kg = check_mesh(*g.mesh);
  EXPECT_NEAR(k.volume, kg.volume, 0.01 * std::abs(kg.volume)) << c.name;
  EXPECT_LE(one_sided(*g.mesh, *r.mesh), h) << c.name;
}

void run_cases(const std::vector<Case>& cases, double h) {
  for (const Case& c : cases) {
    Builder b(kT);
    const NodeId root = c.make(b);
    const Tree t = b.build(root);
    const MeshResult r = mesh_tree(t, at(h));
    expect_local(r, t, root, c, h);
  }
}

// A ball of radius 0.5 in 80 triangles (an icosahedron split once): every edge many precisions long.
std::shared_ptr<const MeshLeaf> coarse_ball() {
  static const auto leaf = [] {
    const double g = (1.0 + std::sqrt(5.0)) / 2.0;
    std::vector<dvec3> p = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                            {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
    std::vector<glm::uvec3> t = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                                 {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    auto middle = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      p.push_back(0.5 * (p[a] + p[b]));
      return mid[key] = std::uint32_t(p.size() - 1);
    };
    std::vector<glm::uvec3> split;
    for (const glm::uvec3& f : t) {
      const std::uint32_t ab = middle(f[0], f[1]), bc = middle(f[1], f[2]), ca = middle(f[2], f[0]);
      split.insert(split.end(), {{f[0], ab, ca}, {ab, f[1], bc}, {ca, bc, f[2]}, {ab, bc, ca}});
    }
    for (dvec3& q : p) q = 0.5 * glm::normalize(q);
    return MeshLeaf::from_triangles(std::move(p), std::move(split), "coarse ball");
  }();
  return leaf;
}

// eight.off pushed into bunny00's flank, and armadillo at a third of bunny00's size on its back.
NodeId shifted_eight(Builder& b) {
  return b.affine(b.mesh(eight(), {0.05}), glm::translate(glm::dmat4(1.0), dvec3(0.35, 0.1, 0.0)));
}
NodeId small_armadillo(Builder& b) {
  glm::dmat4 m = glm::translate(glm::dmat4(1.0), dvec3(0.3, 0.3, 0.0));
  return b.affine(b.mesh(armadillo(), {10.0}), glm::scale(m, dvec3(0.004)));
}

// bunny00's left ear tip is near (-0.005, 0.494, -0.12).
constexpr dvec3 kEar{-0.005, 0.5, -0.12};

// Above the middle of the coarse ball's fourth triangle (the middle one of the first
// icosahedron face), 0.06 off the sphere it is inscribed in.
dvec3 face_middle() {
  const auto& p = coarse_ball()->positions();
  const glm::uvec3 t = coarse_ball()->triangles()[3];
  return 0.56 * glm::normalize(p[t[0]] + p[t[1]] + p[t[2]]);
}

}  // namespace

// A Boolean operand's refined mesh, dropped between cuts and made again by replaying its
// refinements, is the same mesh byte for byte as refining a kept copy step by step: a coarse
// sphere refined in two boxes at two edge lengths, dropped before, between and after.
TEST(LocalBooleans, RefinedOperandsAreMadeAgainExactly) {
  Builder b(kT);
  const Tree t = b.build(b.point({0, 0, 0}, {1.0}));
  const TriangleMesh sphere = sweep_mesh(t.graph(), t.root(), kT, 0.4);
  const auto surface = std::make_shared<const TapeEvaluator>(std::make_shared<const Tape>(compile_tape(t.graph_ptr(), t.root(), kT)));
  const Aabb first{{-1, -1, 0}, {1, 1, 1}}, second{{0, -1, -1}, {1, 1, 1}};
  auto step = [&](const TriangleMesh& m, const Aabb& box, double edge) {
    return warp_mesh(m, [](const glm::dvec3& p) { return p; }, surface.get(), kT, edge, nullptr, &box);
  };
  const TriangleMesh once = step(sphere, first, 0.3), twice = step(once, second, 0.15);
  ASSERT_GT(once.triangles.size(), sphere.triangles.size());
  ASSERT_GT(twice.triangles.size(), once.triangles.size());
  auto same = [](const TriangleMesh& x, const TriangleMesh& y) {
    return x.triangles == y.triangles && x.positions.size() == y.positions.size() &&
           std::memcmp(x.positions.data(), y.positions.data(), x.positions.size() * sizeof(glm::dvec3)) == 0;
  };
  local::RefinedMesh r(sphere, surface, kT);
  r.refine(first, 0.3);
  EXPECT_TRUE(same(r.mesh(), once));
  r.drop();
  EXPECT_TRUE(same(r.mesh(), once));
  r.drop();
  r.refine(second, 0.15);
  EXPECT_TRUE(same(r.mesh(), twice));
  r.drop();
  EXPECT_TRUE(same(r.mesh(), twice));
  EXPECT_TRUE(same(std::move(r).release(), twice));
  // An owned mesh (an earlier step's result) is refined in place and survives a drop.
  local::RefinedMesh owned(TriangleMesh(once), kT);
  owned.drop();
  EXPECT_TRUE(same(owned.mesh(), once));
  // A refinement past its triangle cap says so, and stops there.
  local::RefinedMesh capped(sphere, surface, kT);
  EXPECT_TRUE(capped.refine(first, 0.3, once.triangles.size()));
  EXPECT_FALSE(capped.refine(second, 0.15, once.triangles.size() + 1));
  EXPECT_LT(capped.mesh().triangles.size(), twice.triangles.size());
}

// Operands that lie on each other: their cuts keep both copies of the shared surface, whose
// triangles cross in thousands of pairs. Untangling and halving the edges only multiplied them
// (a random scene of the stress run held 15 GB for two minutes); the Boolean is polygonized at
// once instead, and says why.
TEST(LocalBooleans, OperandsLyingOnEachOtherArePolygonizedAtOnce) {
  const Tree stress = load_scene(std::filesystem::path(HYBRIDTREE_SOURCE_DIR) / "tests/data/stress/coincident_operands_4gb.json");
  Builder b(kT);
  const Tree twins = b.build(b.intersect({b.point({0, 0, 0}, {1.0}), b.point({0, 0, 0}, {1.0})}));
  for (const auto& [tree, h] : {std::pair{&stress, stress.mesher_settings().precision}, std::pair{&twins, 0.02}}) {
    const MeshResult r = mesh_tree(*tree, at(h));
    const NodeReport& job = report_of(r, r.tree->root());
    EXPECT_EQ(job.reason, JobReason::Fallback);
    EXPECT_NE(job.fallback_cause.find("the operands lie on each other"), std::string::npos) << job.fallback_cause;
    const MeshChecks c = check_mesh(*r.mesh);
    EXPECT_TRUE(c.watertight());
    EXPECT_EQ(c.self_intersecting_pairs, 0u);
  }
}

TEST(LocalBooleans, PrimitivesAndMeshLeaves) {
  const std::vector<Case> cases = {
      {"sphere u sphere", 0, [](Builder& b) { return b.unite({b.point({0, 0, 0}, {1.0}), b.point({0.5, 0.1, 0}, {0.8})}); },
       JobStrategy::TrimBoolean},
      {"sphere n segment", 0,
       [](Builder& b) { return b.intersect({b.point({0, 0, 0}, {1.0}), b.segment({-1, 0, 0}, {1, 0, 0}, {0.5})}); },
       JobStrategy::TrimBoolean},
      {"segment - sphere", 0,
       [](Builder& b) { return b.subtract({b.segment({-0.6, 0, 0}, {0.6, 0, 0}, {0.6}), b.point({0.6, 0, 0}, {0.7})}); },
       JobStrategy::TrimBoolean},
      {"bunny u sphere", 0, [](Builder& b) { return b.unite({b.mesh(bunny(), {0.05}), b.point(kEar, {0.12})}); },
       JobStrategy::TrimBoolean},
      {"bunny - sphere", 0, [](Builder& b) { return b.subtract({b.mesh(bunny(), {0.05}), b.point({0.1, 0.1, 0.3}, {0.35})}); },
       JobStrategy::TrimBoolean},
      {"eight u sphere", 2, [](Builder& b) { return b.unite({b.mesh(eight(), {0.05}), b.point({0.2, 0, 0.1}, {0.2})}); },
       JobStrategy::TrimBoolean},
      {"bunny u eight", 2, [](Builder& b) { return b.unite({b.mesh(bunny(), {0.05}), shifted_eight(b)}); },
       JobStrategy::TrimBoolean},
      {"bunny - eight", 0, [](Builder& b) { return b.subtract({b.mesh(bunny(), {0.05}), shifted_eight(b)}); },
       JobStrategy::TrimBoolean},
      {"three balls and a bunny, united", 0,
       [](Builder& b) {
         return b.unite({b.point({0, 0, 0}, {1.0}), b.point({0.5, 0, 0}, {1.0}), b.point({0.25, 0.45, 0}, {1.0}),
                         b.mesh(bunny(), {0.05})});
       },
       JobStrategy::TrimBoolean},
      {"bunny carved three times", 1,
       [](Builder& b) {
         return b.subtract({b.mesh(bunny(), {0.05}), b.point({0.1, 0.1, 0.35}, {0.35}),
                            b.segment({-0.6, -0.2, 0}, {0.6, -0.2, 0}, {0.15}), b.point({-0.005, 0.5, -0.12}, {0.1})});
       },
       JobStrategy::TrimBoolean},
      {"bunny n box", 0,
       [](Builder& b) { return b.intersect({b.mesh(bunny(), {0.05}), b.box({-0.3, -0.6, -0.5}, {0.6, 0.2, 0.5}, {0.1})}); },
       JobStrategy::TrimBoolean},
      {"bunny n eight", 0, [](Builder& b) { return b.intersect({b.mesh(bunny(), {0.05}), shifted_eight(b)}); },
       JobStrategy::TrimBoolean},
      {"bunny u armadillo", 0, [](Builder& b) { return b.unite({b.mesh(bunny(), {0.05}), small_armadillo(b)}); },
       JobStrategy::TrimBoolean},
  };
  run_cases(cases, 0.01);
}

TEST(LocalBlends, PrimitivesAndMeshLeaves) {
  const std::vector<Case> cases = {
      {"segment + sphere", 0, [](Builder& b) { return b.blend({b.segment({-1, 0, 0}, {0, 0, 0}, {0.5}), b.point({0.6, 0.2, 0}, {0.5})}); },
       JobStrategy::TrimBlend},
      {"bunny + sphere", 0, [](Builder& b) { return b.blend({b.mesh(bunny(), {0.05}), b.point(kEar, {0.12})}); },
       JobStrategy::TrimBlend},
      {"bunny + carving", 0,
       [](Builder& b) { return b.blend({b.mesh(bunny(), {0.05}), b.point({0.0, 0.1, 0.3}, {0.2, -1.5})}); },
       JobStrategy::TrimBlend},
      {"bunny + eight", 2, [](Builder& b) { return b.blend({b.mesh(bunny(), {0.05}), shifted_eight(b)}); },
       JobStrategy::TrimBlend},
      {"bunny + armadillo", 0, [](Builder& b) { return b.blend({b.mesh(bunny(), {0.05}), small_armadillo(b)}); },
       JobStrategy::TrimBlend},
      {"eight + segment", 2,
       [](Builder& b) { return b.blend({b.mesh(eight(), {0.05}), b.segment({0.2, 0, -0.3}, {0.5, 0, -0.3}, {0.12})}); },
       JobStrategy::TrimBlend},
      // The small ball acts in the middle of one face, where no corner of the coarse mesh sees it:
      // the face is refined all the same (its edges are coarse), or the seam would be cut short.
      {"coarse ball + sphere", 0,
       [](Builder& b) { return b.blend({b.mesh(coarse_ball(), {0.05}), b.point(face_middle(), {0.1})}); },
       JobStrategy::TrimBlend},
  };
  run_cases(cases, 0.01);
}

// Where a local strategy cannot make a sound mesh, the node is polygonized globally and the
// report says why. The cases known to need that today: operands on each other's surface (they
// cut each other away entirely), and a crop whose cap has a hole (a ring cut through its
// middle: planar caps close simple polygons). When one starts to succeed, move it to the lists
// above.
TEST(LocalStrategies, FallBackWhereTheyCannot) {
  const std::vector<Case> cases = {
      {"a ball united with itself", 0, [](Builder& b) { return b.unite({b.point({0, 0, 0}, {1.0}), b.point({0, 0, 0}, {1.0})}); },
       JobStrategy::TrimBoolean},
      {"half a ring", 0,
       [](Builder& b) { return b.crop(b.circle({0, 0, 0}, {0, 0, 1}, 0.5, {0.3}), {-1, -1, -1}, {1, 1, 0}); },
       JobStrategy::TrimCrop},
  };
  for (const Case& c : cases) {
    Builder b(kT);
    const NodeId root = c.make(b);
    const MeshResult r = mesh_tree(b.build(root), at(0.01));
    const NodeReport& job = report_of(r, root);
    EXPECT_EQ(job.strategy, JobStrategy::Global) << c.name;
    EXPECT_EQ(job.reason, JobReason::Fallback) << c.name;
    EXPECT_FALSE(job.fallback_cause.empty()) << c.name;
    EXPECT_TRUE(check_mesh(*r.mesh).watertight()) << c.name;
  }
}

// A stress run's local blend (a crop of a curve, a difference, a doubly twisted cylinder as the
// region; tests/data/stress) whose bands kept a triangle folded over the union's crease: such
// a result is no longer returned; the node is polygonized, with no fold.
TEST(LocalBlends, AFoldLeftInTheBandsFallsBack) {
  const Tree tree = load_scene(std::filesystem::path(HYBRIDTREE_SOURCE_DIR) / "tests/data/stress/folded_local_blend.json");
  const double h = tree.mesher_settings().precision;
  const MeshResult r = mesh_tree(tree, at(h));
  const NodeReport& job = report_of(r, r.tree->root());
  EXPECT_EQ(job.reason, JobReason::Fallback);
  EXPECT_NE(job.fallback_cause.find("folded over in the bands"), std::string::npos) << job.fallback_cause;
  const MeshChecks c = test::checks_with_surface(r, tree.threshold());  // folded triangles counted
  EXPECT_TRUE(c.watertight());
  EXPECT_EQ(c.self_intersecting_pairs, 0u);
  EXPECT_EQ(c.folded_triangles, 0u);
}

// A ring whose inside grazes bunny00's chest, blended with it only where R reaches (elsewhere):
// the union's crease there crossed itself in 10 pairs, outside the region the trim local blend
// searched (where R acts), and the default strategy returned them. Crossings are looked for
// along the union's crease too now; what untangling leaves sends the node to global.
TEST(LocalBlends, CrossingsAlongTheUnionsCreaseAreFound) {
  const Tree tree = load_scene(std::filesystem::path(HYBRIDTREE_SOURCE_DIR) / "tests/data/stress/local_blend_grazing_ring.json");
  const MeshResult r = mesh_tree(tree, at(tree.mesher_settings().precision));
  const MeshChecks c = check_mesh(*r.mesh);
  EXPECT_TRUE(c.watertight());
  EXPECT_EQ(c.self_intersecting_pairs, 0u) << report_of(r, r.tree->root()).fallback_cause;
}

// Two local blends of a campaign of 110 (docs/robustness.md) that fell back to global for one
// or two triangles folded beside the union's crease: a thick ring through bunny00 (the fold on
// the crease, where R does not reach) and a disc through a sphere's equator (at the crease's
// end, where R fades). The union's seam is followed through the bands as a crease now, and the
// folds are mended as a trim Boolean's are: both stay local, closed, uncrossed and unfolded.
TEST(LocalBlends, FoldsBesideTheUnionsCreaseAreMended) {
  struct Scene {
    const char* name;
    std::function<NodeId(Builder&)> make;
  };
  const std::vector<Scene> scenes = {
      {"ring through bunny00",
       [](Builder& b) {
         return b.local_blend(b.mesh(bunny(), {0.03}), b.circle({0, -0.15, 0}, {0, 1, 0}, 0.45, {0.22}),
                              b.point({-0.35, -0.15, 0.27}, {0.2}));
       }},
      {"disc through a sphere's equator",
       [](Builder& b) {
         return b.local_blend(b.mesh(MeshLeaf::load(test::cgal_mesh("sphere.off")), {0.05}),
                              b.disc({0, 0, 0}, {0, 1, 0}, 0.75, {0.08}), b.box({0, -0.1, -1}, {1, 0.1, 1}, {0.1}));
       }},
  };
  for (const Scene& s : scenes) {
    Builder b(kT);
    const NodeId root = s.make(b);
    const MeshResult r = mesh_tree(b.build(root), at(0.01));
    const NodeReport& job = report_of(r, root);
    EXPECT_EQ(job.strategy, JobStrategy::TrimLocalBlend) << s.name << ": " << job.fallback_cause;
    const MeshChecks c = test::checks_with_surface(r, kT);
    EXPECT_TRUE(c.watertight()) << s.name;
    EXPECT_EQ(c.self_intersecting_pairs, 0u) << s.name;
    EXPECT_EQ(c.folded_triangles, 0u) << s.name;
  }
}

// examples/local_blend.json with its region at half strength (the same campaign): the union's
// open boundary, where R acts, touched itself at a vertex, which bridge() cannot pair, and the
// node fell back to global (2.7 s against 0.3). The fans at such vertices are dropped now.
TEST(LocalBlends, APinchedBoundaryOfTheUnionIsBridged) {
  Builder b(kT);
  const NodeId ring = b.circle({0, -0.15, 0}, {0, 1, 0}, 0.44, {0.1});
  const NodeId region = b.unite({b.segment({-0.41, -0.09, 0.21}, {-0.29, -0.09, 0.33}, {0.14, 0.5}),
                                 b.segment({-0.41, -0.21, 0.21}, {-0.29, -0.21, 0.33}, {0.14, 0.5})});
  const NodeId root = b.local_blend(b.mesh(bunny(), {0.03}), ring, region);
  const MeshResult r = mesh_tree(b.build(root), at(0.008));
  const NodeReport& job = report_of(r, root);
  EXPECT_EQ(job.strategy, JobStrategy::TrimLocalBlend) << job.fallback_cause;
  const MeshChecks c = test::checks_with_surface(r, kT);
  EXPECT_TRUE(c.watertight());
  EXPECT_EQ(c.genus, 2);
  EXPECT_EQ(c.self_intersecting_pairs, 0u);
  EXPECT_EQ(c.folded_triangles, 0u);
}

TEST(LocalCrops, PrimitivesAndMeshLeaves) {
  const std::vector<Case> cases = {
      {"cropped bunny", 0, [](Builder& b) { return b.crop(b.mesh(bunny(), {0.05}), {-0.6, -0.1, -0.5}, {0.6, 0.6, 0.5}); },
       JobStrategy::TrimCrop},
      {"sphere, a corner kept", 0, [](Builder& b) { return b.crop(b.point({0, 0, 0}, {1.0}), {-1, -1, -0.2}, {1, 0.3, 1}); },
       JobStrategy::TrimCrop},
      {"bunny, a corner cut off", 0,
       [](Builder& b) { return b.crop(b.mesh(bunny(), {0.05}), {-0.6, -0.6, -0.5}, {0.3, 0.25, 0.2}); }, JobStrategy::TrimCrop},
      {"sphere, top cut off", 0, [](Builder& b) { return b.crop(b.point({0, 0, 0}, {1.0}), {-1, -1, -1}, {1, 1, 0.2}); },
       JobStrategy::TrimCrop},
      {"eight, both ends cut off", 0,
       [](Builder& b) { return b.crop(b.mesh(eight(), {0.05}), {-1, -1, -0.35}, {1, 1, 0.35}); }, JobStrategy::TrimCrop},
      {"armadillo's arms", 0,
       [](Builder& b) {
         const NodeId arm = b.affine(b.mesh(armadillo(), {10.0}), glm::scale(glm::dmat4(1.0), dvec3(0.005)));
         return b.crop(arm, {-0.4, 0.1, -0.4}, {0.4, 0.6, 0.4});
       },
       JobStrategy::TrimCrop},
  };
  run_cases(cases, 0.01);
}

// The paper's Figure 5: a union, blended only where the region reaches.
// A blend's patch is polygonized at its operands' median edge length there, but never finer than
// half the precision: bunny00's edges near the ear (median about 0.0075) set it at h = 0.008,
// the clamp at h = 0.04 (at h / 4, the old clamp, 0.01 there: four times the cells of h / 2 for
// a surface finer than asked).
TEST(LocalBlends, PatchIsAtMostTwiceFinerThanThePrecision) {
  for (const double h : {0.008, 0.04}) {
    Builder b(kT);
    const NodeId root = b.blend({b.mesh(bunny(), {0.05}), b.point(kEar, {0.12})});
    const Tree t = b.build(root);
    const MeshResult r = mesh_tree(t, at(h, MeshStrategy::Local));
    const NodeReport& e = report_of(r, root);
    ASSERT_EQ(e.strategy, JobStrategy::TrimBlend) << h;
    EXPECT_TRUE(check_mesh(*r.mesh).watertight()) << h;
    if (h == 0.04) EXPECT_DOUBLE_EQ(e.local.patch_precision, 0.5 * h);
    else EXPECT_TRUE(e.local.patch_precision > 0.5 * h && e.local.patch_precision < h) << e.local.patch_precision;
  }
}

TEST(LocalBlends, LocalBlendIsAUnionOutsideItsRegion) {
  const std::vector<Case> cases = {
      {"crossed capsules", 0,
       [](Builder& b) {
         return b.local_blend(b.segment({-1, 0, 0}, {1, 0, 0}, {0.5}), b.segment({0, -1, 0}, {0, 1, 0}, {0.4}),
                              b.point({0.25, 0.25, 0}, {0.4}));
       },
       JobStrategy::TrimLocalBlend},
      {"bunny on a perch", 0,
       [](Builder& b) {
         return b.local_blend(b.mesh(bunny(), {0.05}), b.segment({-0.6, -0.45, -0.1}, {0.6, -0.45, -0.1}, {0.25}),
                              b.point({0.3, -0.4, 0.0}, {0.3}));
       },
       JobStrategy::TrimLocalBlend},
  };
  run_cases(cases, 0.01);
}

TEST(LocalStrategies, UntouchedMeshLeafVerticesAreBitIdentical) {
  Builder b(kT);
  const NodeId sphere = b.point(kEar, {0.12});
  const NodeId root = b.blend({b.mesh(bunny(), {0.05}), sphere});
  const Tree t = b.build(root);
  const MeshResult r = mesh_tree(t, at(0.01));
  ASSERT_EQ(report_of(r, root).strategy, JobStrategy::TrimBlend);
  auto key = [](const dvec3& p) {
    std::array<std::uint64_t, 3> k;
    std::memcpy(k.data(), &p, sizeof p);
    return k;
  };
  std::set<std::array<std::uint64_t, 3>> out;
  for (const dvec3& p : r.mesh->positions) out.insert(key(p));
  const Aabb& reach = t.graph().support(sphere, true);
  std::size_t outside = 0, kept = 0;
  for (const dvec3& p : bunny()->positions()) {
    if (reach.expanded(0.02).contains(p)) continue;
    ++outside;
    kept += out.count(key(p));
  }
  EXPECT_GT(outside, 30000u);
  EXPECT_EQ(kept, outside);
}

TEST(LocalStrategies, SameBytesAtOneAndTwoThreads) {
  Builder b(kT);
  const NodeId wing = b.crop(b.affine(b.mesh(armadillo(), {10.0}), glm::scale(glm::dmat4(1.0), dvec3(0.005))),
                             {-0.35, 0.0, -0.3}, {0.35, 0.5, 0.3});
  const NodeId root = b.blend({b.mesh(bunny(), {0.05}), b.unite({wing, b.point(kEar, {0.12})})});
  const Tree t = b.build(root);
  std::shared_ptr<const TriangleMesh> one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = mesh_tree(t, at(0.01)).mesh;
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = mesh_tree(t, at(0.01)).mesh;
  }
  ASSERT_EQ(one->positions.size(), two->positions.size());
  ASSERT_EQ(one->triangles.size(), two->triangles.size());
  EXPECT_EQ(0, std::memcmp(one->positions.data(), two->positions.data(), one->positions.size() * sizeof(dvec3)));
  EXPECT_EQ(0, std::memcmp(one->triangles.data(), two->triangles.data(), one->triangles.size() * sizeof(glm::uvec3)));
}

TEST(LocalStrategies, RandomTreesWithMeshLeavesStayClosed) {
  test::Rng rng(0x10ca1);
  test::RandomTreeOptions o;
  o.max_depth = 3;
  o.meshes = {eight(), MeshLeaf::load(test::cgal_mesh("sphere.off"))};
  std::size_t jobs = 0, fallbacks = 0, local = 0;
  std::map<std::string, int> causes;
  for (int i = 0; i < 24; ++i) {
    Builder b(kT);
    const NodeId root = test::random_tree(b, rng, o);
    const Tree t = b.build(root);
    for (MeshStrategy s : {MeshStrategy::Auto, MeshStrategy::Local}) {
      MeshResult r;
      try {
        r = mesh_tree(t, at(0.06, s));
      } catch (const PolygonizeError& e) {
        continue;  // unbounded solids (blends over R-function differences) are refused
      }
      const MeshChecks k = check_mesh(*r.mesh);
      EXPECT_TRUE(k.watertight()) << "tree " << i;
      EXPECT_EQ(k.self_intersecting_pairs, 0u) << "tree " << i;
      for (const NodeReport& e : r.nodes) {
        ++jobs;
        if (e.reason == JobReason::Fallback)
          ++fallbacks, ++causes[std::string(kind_name(t.graph().kind[e.node])) + ": " + e.fallback_cause.substr(0, 60)];
        if (e.strategy == JobStrategy::TrimBlend || e.strategy == JobStrategy::TrimBoolean || e.strategy == JobStrategy::TrimCrop)
          ++local;
      }
    }
  }
  std::printf("random trees: %zu jobs, %zu local results, %zu fallbacks\n", jobs, local, fallbacks);
  for (const auto& [cause, n] : causes) std::printf("  %3d  %s\n", n, cause.c_str());
  EXPECT_GT(local, 0u);
}
