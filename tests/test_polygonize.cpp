// The global polygonizer: every mesh closed, manifold, oriented and free of degenerate triangles;
// the right topology (sphere 2, torus 0, eight.off genus 2, refined_elephant genus 3); vertices
// on the surface within a bound that scales with the precision; volumes right; the same mesh at
// any thread count; random trees always watertight.
#include "meshers/mesh_checks.hpp"
#include "meshers/polygonize.hpp"
#include "nodes/mesh_leaf.hpp"
#include "nodes/primitives.hpp"
#include "runtime/builder.hpp"
#include "runtime/tape.hpp"
#include "runtime/tape_eval.hpp"
#include "tests/support/random_tree.hpp"

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <map>
#include <mutex>
#include <numbers>
#include <set>
#include <tuple>

using namespace ht;
using glm::dvec3;

namespace {

constexpr double kT = 0.5;

MeshChecks mesh_and_check(const Tree& t, double h, TriangleMesh* out = nullptr) {
  PolygonizeOptions o;
  o.precision = h;
  const TriangleMesh m = polygonize(t.graph_ptr(), t.root(), kT, o);
  MeshChecks c = check_mesh(m);
  if (!m.triangles.empty()) measure_surface_error(m, t.evaluator(), kT, c);
  if (out) *out = m;
  return c;
}

void expect_watertight(const MeshChecks& c, const std::string& what) {
  EXPECT_TRUE(c.closed()) << what << ": " << c.boundary_edges << " boundary edges";
  EXPECT_TRUE(c.manifold()) << what << ": " << c.nonmanifold_edges << " non-manifold edges, " << c.nonmanifold_vertices
                            << " non-manifold vertices";
  EXPECT_TRUE(c.oriented()) << what << ": " << c.misoriented_edges << " misoriented edges";
  EXPECT_EQ(c.degenerate_triangles, 0u) << what;
  EXPECT_EQ(c.unused_vertices, 0u) << what;
}

// Marching tetrahedra alone (no quality pass, crease step or snapping): outputs that compare
// triangle for triangle.
PolygonizeOptions bare_extraction(double h) {
  PolygonizeOptions o;
  o.precision = h;
  o.quality.enabled = false;
  o.sharp_features = false;
  o.snap = false;
  return o;
}

}  // namespace

TEST(Polygonize, EveryPrimitiveKindIsASphereOrATorus) {
  struct Case {
    const char* name;
    long euler;
    std::function<NodeId(Builder&)> make;
  };
  const std::vector<dvec3> spline = {{-0.6, 0, 0}, {-0.2, 0.3, 0.1}, {0.2, -0.2, 0}, {0.6, 0.1, 0.2}};
  const std::vector<Case> cases = {
      {"point", 2, [](Builder& b) { return b.point({0, 0, 0}, {0.8}); }},
      {"segment", 2, [](Builder& b) { return b.segment({-0.5, 0, 0}, {0.5, 0.2, 0}, {0.6}); }},
      {"circle", 0, [](Builder& b) { return b.circle({0, 0, 0}, {0, 0.3, 1}, 0.6, {0.5}); }},
      {"disc", 2, [](Builder& b) { return b.disc({0, 0, 0}, {0, 0, 1}, 0.5, {0.5}); }},
      {"triangle", 2, [](Builder& b) { return b.triangle({0, 0, 0}, {1, 0, 0}, {0.2, 0.8, 0}, {0.5}); }},
      {"curve", 2, [spline](Builder& b) { return b.curve(spline, {0.5}); }},
      {"box", 2, [](Builder& b) { return b.box({-0.4, -0.3, -0.2}, {0.4, 0.3, 0.2}, {0.5}); }},
      {"cylinder", 2, [](Builder& b) { return b.cylinder({0, 0, -0.4}, {0, 0, 0.4}, 0.3, {0.5}); }},
      {"cone_sphere", 2, [](Builder& b) { return b.cone_sphere({-0.4, 0, 0}, {0.4, 0, 0}, 0.3, 0.1, {0.4}); }},
  };
  for (const Case& k : cases) {
    for (double h : {0.04, 0.02}) {
      Builder b(kT);
      const Tree t = b.build(k.make(b));
      const MeshChecks c = mesh_and_check(t, h);
      const std::string what = std::string(k.name) + " h=" + std::to_string(h);
      expect_watertight(c, what);
      EXPECT_EQ(c.components, 1u) << what;
      EXPECT_EQ(c.euler, k.euler) << what;
      EXPECT_GT(c.volume, 0.0) << what;
      // Vertices on the surface: refined along their edge to a small fraction of the cell.
      EXPECT_LT(c.vertex_error_max, 0.05 * h) << what;
      EXPECT_LT(c.face_error_max, 0.5 * h) << what;
    }
  }
}

TEST(Polygonize, SphereVolumeAndAreaConverge) {
  Builder b(kT);
  const double R = 1.0, r0 = primitive_r0(R, 1.0, kT);
  const Tree t = b.build(b.point({0.1, 0.2, 0.3}, {R}));
  double previous = 1e9;
  for (double h : {0.08, 0.04, 0.02}) {
    const MeshChecks c = mesh_and_check(t, h);
    const double exact = 4.0 / 3.0 * std::numbers::pi * r0 * r0 * r0;
    const double error = std::abs(c.volume - exact) / exact;
    EXPECT_LT(error, 0.02) << h;
    EXPECT_LT(error, previous) << "halving h must shrink the volume error";
    previous = error;
    EXPECT_NEAR(c.area, 4.0 * std::numbers::pi * r0 * r0, 0.03 * 4.0 * std::numbers::pi * r0 * r0);
  }
}

TEST(Polygonize, EveryWarpStaysWatertight) {
  for (int kind = 0; kind < 4; ++kind) {
    Builder b(kT);
    const NodeId child = b.box({-0.6, -0.2, -0.5}, {0.6, 0.2, 0.5}, {0.4});
    NodeId w;
    if (kind == 0)
      w = b.affine(child, glm::scale(glm::rotate(glm::dmat4(1.0), 0.7, dvec3(1, 1, 0)), dvec3(1.5, 0.7, 1.0)));
    else if (kind == 1)
      w = b.twist(child, Axis::Z, {0, 0, 0}, 2.0);
    else if (kind == 2)
      w = b.taper(child, Axis::Z, {0, 0, 0}, -0.5, 0.5, 1.2, 0.4);
    else
      w = b.bend(child, Axis::X, {0, 0, 0}, -0.6, 0.6, 0.8);
    const Tree t = b.build(w);
    const MeshChecks c = mesh_and_check(t, 0.03);
    expect_watertight(c, "warp " + std::to_string(kind));
    EXPECT_EQ(c.euler, 2) << kind;
    EXPECT_LT(c.vertex_error_max, 0.02 * 0.03) << kind;
  }
}

TEST(Polygonize, RealMeshesKeepTheirGenus) {
  struct Case {
    const char* file;
    long genus;
    double precision;
  };
  for (const Case& k : {Case{"eight.off", 2, 0.01}, Case{"refined_elephant.off", 3, 0.01}, Case{"knot2.off", 2, 0.01}}) {
    Builder b(kT);
    const auto leaf = MeshLeaf::load(test::cgal_mesh(k.file));
    const Tree t = b.build(b.mesh(leaf, {0.05}));
    const MeshChecks c = mesh_and_check(t, k.precision);
    expect_watertight(c, k.file);
    EXPECT_EQ(c.genus, k.genus) << k.file;
    EXPECT_EQ(c.components, leaf->report().components) << k.file;
  }
}

TEST(Polygonize, RandomTreesAreAlwaysWatertight) {
  test::Rng rng(61);
  test::RandomTreeOptions opt;
  opt.meshes = {MeshLeaf::load(test::cgal_mesh("eight.off")), MeshLeaf::load(test::cgal_mesh("sphere.off"))};
  int meshed = 0, unbounded = 0;
  for (int trial = 0; trial < 120; ++trial) {
    Builder b(kT);
    const NodeId root = test::random_tree(b, rng, opt);
    const Tree t = b.build(root);
    try {
      const MeshChecks c = mesh_and_check(t, 0.06);
      expect_watertight(c, "trial " + std::to_string(trial));
      EXPECT_EQ(c.euler % 2, 0) << trial;
      if (::testing::Test::HasFailure()) return;
      ++meshed;
    } catch (const PolygonizeError& e) {
      // Only an unbounded solid may refuse (a blend over R-function differences).
      EXPECT_NE(std::string(e.what()).find("unbounded"), std::string::npos) << e.what();
      ++unbounded;
    }
  }
  EXPECT_GT(meshed, 100);
}

TEST(Polygonize, SameMeshAtAnyThreadCount) {
  test::Rng rng(62);
  Builder b(kT);
  const NodeId root = test::random_tree(b, rng, {});
  const NodeId both = b.blend({root, b.segment({-1, 0, 0}, {1, 0, 0}, {0.6})});
  const Tree t = b.build(both);
  TriangleMesh one, two;
  tbb::task_arena(1).execute([&] { mesh_and_check(t, 0.03, &one); });
  tbb::task_arena(2).execute([&] { mesh_and_check(t, 0.03, &two); });
  EXPECT_EQ(one.positions, two.positions);
  EXPECT_EQ(one.triangles, two.triangles);
}

TEST(Polygonize, RefusesWhatItCannotDo) {
  Builder b(kT);
  const Tree t = b.build(b.point({0, 0, 0}, {1.0}));
  PolygonizeOptions o;
  o.precision = 1e-5;  // 10^5 cells a side
  o.memory_budget = std::size_t(1) << 30;
  try {
    polygonize(t.graph_ptr(), t.root(), kT, o);
    ADD_FAILURE() << "a 1e-5 precision fitted in 1 GiB";
  } catch (const MemoryBudgetError& e) {
    EXPECT_NE(std::string(e.what()).find("needs"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("GiB"), std::string::npos) << e.what();
    EXPECT_GT(e.needed, e.limit);
  }
  o.precision = 0.0;
  EXPECT_THROW(polygonize(t.graph_ptr(), t.root(), kT, o), PolygonizeError);
  // An invisible primitive (F <= T) has an empty surface: an empty mesh, no error.
  Builder b2(kT);
  const Tree weak = b2.build(b2.point({0, 0, 0}, {1.0, 0.4}));
  o.precision = 0.05;
  EXPECT_TRUE(polygonize(weak.graph_ptr(), weak.root(), kT, o).triangles.empty());
}

// Vertex placement starts from a polynomial through the brick's values on each crossing edge's
// line and probes once past a value that is exactly T: on smooth fields it takes about one and a
// half values a vertex (a vertex on a brick face is placed by both bricks), where the linear
// guess took over two; and every vertex still meets the refinement's tolerance.
TEST(Polygonize, VertexPlacementTakesFewValuesOnSmoothFields) {
  Builder b(kT);
  struct Case {
    const char* name;
    NodeId node;
  };
  const std::vector<Case> cases = {
      {"point", b.point({0, 0, 0}, {0.8})},
      {"segment", b.segment({-0.5, 0, 0}, {0.5, 0.2, 0}, {0.6})},
      {"blend", b.blend({b.point({0, 0, 0}, {0.8}), b.point({0.5, 0.2, 0}, {0.6}), b.segment({-0.5, 0, 0}, {0.5, 0.2, 0}, {0.4})})}};
  const double h = 0.02;
  for (const Case& c : cases) {
    const Tree t = b.build(c.node);
    PolygonizeOptions o;
    o.precision = h;
    o.quality.enabled = false;  // the extracted vertices themselves
    o.snap = false;
    o.sharp_features = false;
    PolygonizeStats st;
    const TriangleMesh m = polygonize(t.graph_ptr(), t.root(), kT, o, &st);
    ASSERT_FALSE(m.positions.empty()) << c.name;
    EXPECT_LE(double(st.refine_evaluations), 1.6 * double(m.positions.size())) << c.name;
    MeshChecks checks = check_mesh(m);
    measure_surface_error(m, t.evaluator(), kT, checks);
    // The tolerance: |f - T| within 1e-3 of f's change along the edge (at most sqrt(3) h long).
    EXPECT_LE(checks.vertex_error_max, 2e-3 * h) << c.name;
  }
}

// A brick filter naming octants (PolygonizeOptions::brick_filter): no triangle comes from outside
// the named octants, and deep inside them (2.5 cells from their faces, where the grid points a
// vertex's first guess reads were sampled too) the triangles are those of the unfiltered run, on
// random trees with random octant masks.
TEST(Polygonize, AnOctantFilterMeshesOnlyItsOctants) {
  test::Rng rng(63);
  const double h = 0.05;
  int compared = 0;
  for (int trial = 0; trial < 12; ++trial) {
    Builder b(kT);
    const Tree t = b.build(b.blend({test::random_tree(b, rng, {}), b.segment({-1, 0, 0}, {1, 0, 0}, {0.6})}));
    PolygonizeOptions o = bare_extraction(h);
    const TriangleMesh whole = polygonize(t.graph_ptr(), t.root(), kT, o);
    // The mask of a brick: a hash of its corner, so that each brick gets its own.
    const std::uint64_t salt = rng();
    std::mutex mutex;
    std::vector<Aabb> named;  // the octants the filter named, as boxes
    o.brick_filter = [&](const Aabb& brick) {
      std::uint64_t k = salt;
      for (int a = 0; a < 3; ++a) k = (k ^ std::uint64_t(std::llround(brick.lo[a] / h))) * 0x9e3779b97f4a7c15ull;
      const auto mask = std::uint8_t((k >> 56) | (k >> 48) | (k >> 40));  // 7 octants in 8, on average
      const std::lock_guard lock(mutex);
      for (int q = 0; q < 8; ++q)
        if ((mask >> q) & 1) named.push_back(octants::of(brick, q));
      return mask;
    };
    const TriangleMesh part = polygonize(t.graph_ptr(), t.root(), kT, o);
    if (named.empty()) continue;
    // The named octants as cells of their lattice (4 cells a side); a point on a face is in both.
    const double side = 4.0 * h;
    const glm::dvec3 origin = named.front().lo;
    std::set<std::array<std::int64_t, 3>> cells;
    for (const Aabb& box : named) {
      const glm::dvec3 c = glm::round((box.lo - origin) / side);
      cells.insert({std::int64_t(c.x), std::int64_t(c.y), std::int64_t(c.z)});
    }
    auto in_named_at = [&](const glm::dvec3& p) {
      const glm::dvec3 q = (p - origin) / side;
      for (int k = 0; k < 8; ++k) {
        std::array<std::int64_t, 3> c{};
        for (int a = 0; a < 3; ++a) c[std::size_t(a)] = std::int64_t(std::floor(q[a] + (((k >> a) & 1) ? 1e-9 : -1e-9)));
        if (cells.count(c)) return true;
      }
      return false;
    };
    // Inset by r: the cube of half side r around p is named (27 points spaced under a cell of
    // the lattice meet every one it touches).
    auto in_named = [&](const glm::dvec3& p, double r) {
      for (int k = 0; k < 27; ++k)
        if (!in_named_at(p + r * glm::dvec3(k % 3 - 1, (k / 3) % 3 - 1, k / 9 - 1))) return false;
      return true;
    };
    auto deep = [&](const TriangleMesh& m, const glm::uvec3& tri) {
      return in_named(m.positions[tri[0]], 2.5 * h) && in_named(m.positions[tri[1]], 2.5 * h) &&
             in_named(m.positions[tri[2]], 2.5 * h);
    };
    for (const glm::uvec3& tri : part.triangles)
      for (int k = 0; k < 3; ++k) ASSERT_TRUE(in_named_at(part.positions[tri[k]])) << "trial " << trial;
    // Deep triangles by their corners, compared as sorted lists.
    auto deep_corners = [&](const TriangleMesh& m) {
      std::vector<std::array<double, 9>> out;
      for (const glm::uvec3& tri : m.triangles)
        if (deep(m, tri)) {
          std::array<glm::dvec3, 3> c{m.positions[tri[0]], m.positions[tri[1]], m.positions[tri[2]]};
          std::sort(c.begin(), c.end(), [](const glm::dvec3& x, const glm::dvec3& y) {
            return std::tie(x.x, x.y, x.z) < std::tie(y.x, y.y, y.z);
          });
          out.push_back({c[0].x, c[0].y, c[0].z, c[1].x, c[1].y, c[1].z, c[2].x, c[2].y, c[2].z});
        }
      std::sort(out.begin(), out.end());
      return out;
    };
    const auto a = deep_corners(whole), p = deep_corners(part);
    ASSERT_EQ(a.size(), p.size()) << "trial " << trial;
    for (std::size_t i = 0; i < a.size(); ++i)
      for (int k = 0; k < 9; ++k) ASSERT_NEAR(a[i][std::size_t(k)], p[i][std::size_t(k)], 1e-9 * h) << "trial " << trial;
    compared += int(a.size());
  }
  EXPECT_GT(compared, 1000);
}

// Leaving out the octants that interval analysis, one cell wider, puts on one side of T (as blend
// patches do, meshers/local_blends.cpp) changes no triangle: the same triangles on the same vertex
// numbers, each vertex within the refinement's tolerance of where the unfiltered run put it.
TEST(Polygonize, LeavingOutOneSidedOctantsChangesNoTriangle) {
  test::Rng rng(64);
  const double h = 0.05;
  std::size_t left_out = 0, triangles = 0;
  for (int trial = 0; trial < 12; ++trial) {
    Builder b(kT);
    const Tree t = b.build(b.blend({test::random_tree(b, rng, {}), b.segment({-1, 0, 0}, {1, 0, 0}, {0.6})}));
    PolygonizeOptions o = bare_extraction(h);
    const TriangleMesh whole = polygonize(t.graph_ptr(), t.root(), kT, o);
    std::atomic<std::size_t> dropped{0};
    o.brick_filter = [&](const Aabb& brick) {
      std::uint8_t mask = 0;
      for (int k = 0; k < 8; ++k) {
        const Interval iv = field_interval(t.graph(), t.root(), kT, octants::of(brick, k).expanded(h), false);
        if (iv.lo < kT && iv.hi >= kT) mask = std::uint8_t(mask | (1u << k));
      }
      if (mask != 0) dropped += std::size_t(8 - std::popcount(mask));
      return mask;
    };
    const TriangleMesh part = polygonize(t.graph_ptr(), t.root(), kT, o);
    ASSERT_EQ(whole.triangles, part.triangles) << "trial " << trial;
    ASSERT_EQ(whole.positions.size(), part.positions.size()) << "trial " << trial;
    for (std::size_t v = 0; v < whole.positions.size(); ++v)
      ASSERT_LT(glm::length(whole.positions[v] - part.positions[v]), 5e-3 * h) << "trial " << trial << " vertex " << v;
    left_out += dropped;
    triangles += whole.triangles.size();
  }
  EXPECT_GT(triangles, 10000u);
  EXPECT_GT(left_out, 100u);  // octants of active bricks left out: the filter did work
}

// A blend's patch sampled operand by operand (PolygonizeOptions::region_operands) leaves out
// only triangles far from where two operands act: every triangle of the unfiltered run with a
// corner where the operands' |f| but the largest reach eps is there too (the same place), and
// the filter leaves out a good part of the rest.
TEST(Polygonize, ARegionFilterKeepsEveryTriangleWhereTwoOperandsAct) {
  test::Rng rng(65);
  const double h = 0.05, eps = 1e-3 * kT;
  std::size_t needed = 0, whole_count = 0, part_count = 0;
  for (int trial = 0; trial < 10; ++trial) {
    Builder b(kT);
    const NodeId first = test::random_tree(b, rng, {});
    const NodeId second = b.segment({-1, 0, 0}, {1, 0.2, 0}, {0.5});
    const Tree t = b.build(b.blend({first, second}));
    const auto ops = t.graph().children_of(t.root());
    PolygonizeOptions o = bare_extraction(h);
    o.brick_filter = [](const Aabb&) { return octants::kAll; };
    const TriangleMesh whole = polygonize(t.graph_ptr(), t.root(), kT, o);
    o.region_operands.assign(ops.begin(), ops.end());
    const TriangleMesh part = polygonize(t.graph_ptr(), t.root(), kT, o);
    whole_count += whole.triangles.size();
    part_count += part.triangles.size();
    // The operands' |f| but the largest at the unfiltered run's vertices.
    std::vector<double> region(whole.positions.size(), 0.0), largest(whole.positions.size(), 0.0);
    for (NodeId op : ops) {
      const TapeEvaluator eval(std::make_shared<const Tape>(compile_tape(t.graph_ptr(), op, kT, nullptr, true)));
      std::vector<double> f(whole.positions.size());
      eval.field(whole.positions, f);
      for (std::size_t v = 0; v < f.size(); ++v) region[v] += std::abs(f[v]), largest[v] = std::max(largest[v], std::abs(f[v]));
    }
    // The filtered run's triangles by centroid, in buckets a quarter cell wide.
    auto bucket = [&](const dvec3& c) {
      const glm::i64vec3 q(glm::floor(c / (0.25 * h)));
      return std::tuple(q.x, q.y, q.z);
    };
    auto centroid = [](const TriangleMesh& m, const glm::uvec3& tri) {
      return (m.positions[tri[0]] + m.positions[tri[1]] + m.positions[tri[2]]) / 3.0;
    };
    std::multimap<std::tuple<std::int64_t, std::int64_t, std::int64_t>, dvec3> at;
    for (const glm::uvec3& tri : part.triangles) at.emplace(bucket(centroid(part, tri)), centroid(part, tri));
    for (const glm::uvec3& tri : whole.triangles) {
      if (!(std::max({region[tri[0]] - largest[tri[0]], region[tri[1]] - largest[tri[1]], region[tri[2]] - largest[tri[2]]}) >= eps))
        continue;
      ++needed;
      const dvec3 c = centroid(whole, tri);
      const auto [x, y, z] = bucket(c);
      bool found = false;
      for (std::int64_t dx = -1; dx <= 1 && !found; ++dx)
        for (std::int64_t dy = -1; dy <= 1 && !found; ++dy)
          for (std::int64_t dz = -1; dz <= 1 && !found; ++dz) {
            const auto [lo, hi] = at.equal_range(std::tuple(x + dx, y + dy, z + dz));
            for (auto it = lo; it != hi && !found; ++it) found = glm::length(it->second - c) < 1e-3 * h;
          }
      ASSERT_TRUE(found) << "trial " << trial << ": a triangle where two operands act went, at " << c.x << " " << c.y << " " << c.z;
    }
  }
  EXPECT_GT(needed, 2000u);                   // the region was met
  EXPECT_LT(part_count, whole_count * 9 / 10);  // and the filter left out triangles away from it
}
