// Mesh leaves: the field matches SCENE_FORMAT.md on real meshes, the inside test agrees with a
// brute-force generalized winding number, orientation and repair do what the report says, and
// bad input fails with a message that says what is wrong.
#include "meshers/mesh_checks.hpp"
#include "nodes/mesh_leaf.hpp"
#include "nodes/primitives.hpp"
#include "nodes/trimesh.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>
#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

namespace ht {
namespace {

using test::Rng;

using test::seeded;

struct Soup {
  std::vector<glm::dvec3> positions;
  std::vector<glm::uvec3> triangles;
};

// The test's own OFF reader, so the reference does not go through the code under test.
Soup read_off(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::string magic;
  std::size_t nv = 0, nf = 0, ne = 0;
  in >> magic >> nv >> nf >> ne;
  Soup s;
  s.positions.resize(nv);
  for (auto& p : s.positions) in >> p.x >> p.y >> p.z;
  for (std::size_t f = 0; f < nf; ++f) {
    std::size_t n = 0;
    in >> n;
    std::vector<unsigned> idx(n);
    for (auto& i : idx) in >> i;
    for (std::size_t i = 1; i + 1 < n; ++i) s.triangles.emplace_back(idx[0], idx[i], idx[i + 1]);
  }
  EXPECT_TRUE(in.good() || in.eof()) << file;
  return s;
}

// The file's faces, as written (the reference must not depend on the orientation code), on the
// leaf's vertices: OpenMesh's readers parse coordinates as float, so the leaf's positions differ
// from the text by up to a float rounding, which would show in 1e-9 comparisons.
Soup reference_soup(const std::filesystem::path& file, const MeshLeaf& leaf) {
  Soup s = read_off(file);
  EXPECT_EQ(s.positions.size(), leaf.positions().size());
  for (std::size_t i = 0; i < s.positions.size() && i < leaf.positions().size(); ++i)
    EXPECT_LE(glm::length(s.positions[i] - leaf.positions()[i]), 1e-6 * (1 + glm::length(s.positions[i])));
  s.positions = leaf.positions();
  return s;
}

// Generalized winding number: the solid angle of every triangle seen from p (Van Oosterom and
// Strackee's formula) over 4 pi. Integer off the surface of a closed mesh, whatever its shape.
double winding_number(const Soup& s, const glm::dvec3& p) {
  double sum = 0.0;
  for (const auto& t : s.triangles) {
    const glm::dvec3 a = s.positions[t[0]] - p, b = s.positions[t[1]] - p, c = s.positions[t[2]] - p;
    const double la = glm::length(a), lb = glm::length(b), lc = glm::length(c);
    const double num = glm::dot(a, glm::cross(b, c));
    const double den = la * lb * lc + glm::dot(a, b) * lc + glm::dot(b, c) * la + glm::dot(c, a) * lb;
    sum += 2.0 * std::atan2(num, den);
  }
  return sum / (4.0 * std::numbers::pi);
}

// Distance to a triangle by projection onto its plane, falling back to the three segments: a
// different route from the Voronoi-region walk in the implementation.
double segment_distance(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b) {
  const glm::dvec3 ab = b - a;
  const double s = std::clamp(glm::dot(p - a, ab) / glm::dot(ab, ab), 0.0, 1.0);
  return glm::length(p - (a + s * ab));
}
double triangle_distance(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
  const glm::dvec3 n = glm::cross(b - a, c - a);
  const double nn = glm::dot(n, n);
  if (nn > 0) {
    const glm::dvec3 q = p - n * (glm::dot(p - a, n) / nn);
    const bool in = glm::dot(glm::cross(b - a, q - a), n) >= 0 &&
                    glm::dot(glm::cross(c - b, q - b), n) >= 0 && glm::dot(glm::cross(a - c, q - c), n) >= 0;
    if (in) return glm::length(p - q);
  }
  return std::min({segment_distance(p, a, b), segment_distance(p, b, c), segment_distance(p, c, a)});
}
double brute_distance(const Soup& s, const glm::dvec3& p) {
  double d = std::numeric_limits<double>::infinity();
  for (const auto& t : s.triangles)
    d = std::min(d, triangle_distance(p, s.positions[t[0]], s.positions[t[1]], s.positions[t[2]]));
  return d;
}

struct Reference {
  std::vector<glm::dvec3> points;
  std::vector<double> winding, distance;
};
// Winding numbers (and, when asked, distances) for many points: O(points x triangles), so in
// parallel.
Reference reference(const Soup& s, std::vector<glm::dvec3> points, bool distances) {
  Reference r;
  r.points = std::move(points);
  r.winding.resize(r.points.size());
  r.distance.resize(r.points.size(), 0.0);
  tbb::parallel_for(std::size_t(0), r.points.size(), [&](std::size_t i) {
    r.winding[i] = winding_number(s, r.points[i]);
    if (distances) r.distance[i] = brute_distance(s, r.points[i]);
  });
  return r;
}

std::vector<glm::dvec3> random_points(Rng& rng, const Aabb& box, std::size_t n) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<glm::dvec3> pts(n);
  for (auto& p : pts) p = box.lo + glm::dvec3(u(rng), u(rng), u(rng)) * box.size();
  return pts;
}

// Points a small distance off the surface, on either side: where the pseudo-normal decides.
std::vector<glm::dvec3> near_surface_points(Rng& rng, const Soup& s, std::size_t n, double offset) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<glm::dvec3> pts(n);
  for (auto& p : pts) {
    const auto& t = s.triangles[static_cast<std::size_t>(u(rng) * static_cast<double>(s.triangles.size())) %
                                s.triangles.size()];
    double w0 = u(rng), w1 = u(rng);
    if (w0 + w1 > 1) w0 = 1 - w0, w1 = 1 - w1;
    const glm::dvec3 on = s.positions[t[0]] + w0 * (s.positions[t[1]] - s.positions[t[0]]) +
                          w1 * (s.positions[t[2]] - s.positions[t[0]]);
    p = on + offset * glm::normalize(glm::dvec3(g(rng), g(rng), g(rng)));
  }
  return pts;
}

double diagonal(const Aabb& b) { return glm::length(b.size()); }

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const MeshError& e) {
    return e.what();
  }
  return "(no MeshError)";
}

// ---------------------------------------------------------------------------------------------

TEST(MeshFieldParams, FollowTheFormat) {
  const MeshFieldParams m = mesh_field_params(2.0, 1.0, 0.5);
  const double c = std::sqrt(1.0 - std::cbrt(0.5));
  EXPECT_DOUBLE_EQ(m.kernel_radius, 2.0 / (1.0 - c));
  EXPECT_DOUBLE_EQ(m.r0, c * m.kernel_radius);
  EXPECT_DOUBLE_EQ(m.query_radius, std::max(2.0, m.r0));
  // On the surface d = r0 and f = F (1 - c^2)^3 = T; at distance R outside, d = R' and f = 0.
  EXPECT_NEAR(std::pow(1.0 - c * c, 3.0), 0.5, 1e-15);
  EXPECT_NEAR(m.R + m.r0, m.kernel_radius, 1e-12);
  EXPECT_THROW(mesh_field_params(1.0, 0.5, 0.5), std::invalid_argument);
  EXPECT_THROW(mesh_field_params(1.0, -0.4, 0.5), std::invalid_argument);
  EXPECT_THROW(mesh_field_params(0.0, 1.0, 0.5), std::invalid_argument);
  EXPECT_NO_THROW(mesh_field_params(1.0, -2.0, 0.5));
}

class MeshFieldOnMesh : public ::testing::TestWithParam<const char*> {};

TEST_P(MeshFieldOnMesh, ThresholdOnSurfaceZeroBeyondRStrengthDeepInside) {
  Rng rng = seeded();
  const auto file = test::cgal_mesh(GetParam());
  const auto leaf = MeshLeaf::load(file);
  const Soup soup = reference_soup(file, *leaf);
  const Aabb box = leaf->bounds();
  const double R = 0.05 * diagonal(box);

  // Surface samples: every vertex and face centres (all of them, or 5000 at random).
  std::vector<glm::dvec3> surface = leaf->positions();
  const auto& tris = leaf->triangles();
  const std::size_t centres = std::min<std::size_t>(tris.size(), 5000);
  for (std::size_t i = 0; i < centres; ++i) {
    const auto& t = tris[tris.size() == centres ? i : rng() % tris.size()];
    surface.push_back((leaf->positions()[t[0]] + leaf->positions()[t[1]] + leaf->positions()[t[2]]) / 3.0);
  }
  // Points farther than R outside: corners, edge midpoints and face centres of the grown box.
  std::vector<glm::dvec3> far;
  const Aabb grown = box.expanded(1.01 * R);
  for (int i = 0; i < 27; ++i) {
    if (i == 13) continue;  // the centre
    const glm::dvec3 w(i % 3 * 0.5, i / 3 % 3 * 0.5, i / 9 * 0.5);
    far.push_back(grown.lo + w * grown.size());
  }
  // Deep-interior candidates, judged by the reference.
  const Reference deep =
      reference(soup, random_points(rng, box, soup.triangles.size() > 20000 ? 300 : 2000), true);

  for (double T : {0.3, 0.5, 0.7}) {
    SCOPED_TRACE("T = " + std::to_string(T));
    const MeshFieldParams m = mesh_field_params(R, 1.0, T);
    for (const auto& p : surface)
      ASSERT_NEAR(mesh_field(*leaf, m, p), T, 1e-6) << p.x << " " << p.y << " " << p.z;
    for (const auto& p : far) ASSERT_EQ(mesh_field(*leaf, m, p), 0.0);
    std::size_t checked = 0;
    for (std::size_t i = 0; i < deep.points.size(); ++i) {
      if (std::abs(deep.winding[i] - 1.0) > 1e-6 || deep.distance[i] <= m.r0 * (1 + 1e-9)) continue;
      ++checked;
      ASSERT_EQ(mesh_field(*leaf, m, deep.points[i]), 1.0);
    }
    EXPECT_GT(checked, 10u);
  }
}

// Test names from the file stem ("bunny00"), so ctest's names stay stable.
std::string mesh_test_name(const std::string& file) { return file.substr(0, file.find('.')); }

INSTANTIATE_TEST_SUITE_P(Meshes, MeshFieldOnMesh, ::testing::Values("bunny00.off", "eight.off"),
                         [](const auto& param_info) { return mesh_test_name(param_info.param); });

TEST(MeshField, MatchesTheFormulaAwayFromTheSurface) {
  // Between the surface and the support: d from the brute-force distance and the winding number.
  Rng rng = seeded();
  const auto file = test::cgal_mesh("eight.off");
  const auto leaf = MeshLeaf::load(file);
  const Soup soup = reference_soup(file, *leaf);
  const double R = 0.1 * diagonal(leaf->bounds());
  const MeshFieldParams m = mesh_field_params(R, 1.5, 0.5);
  const Reference ref = reference(soup, random_points(rng, leaf->bounds().expanded(R), 3000), true);
  for (std::size_t i = 0; i < ref.points.size(); ++i) {
    const bool in = ref.winding[i] > 0.5;
    double d = in ? std::max(0.0, m.r0 - ref.distance[i]) : ref.distance[i] + m.r0;
    const double u = 1.0 - d * d / (m.kernel_radius * m.kernel_radius);
    const double expected = d < m.kernel_radius ? 1.5 * u * u * u : 0.0;
    ASSERT_NEAR(mesh_field(*leaf, m, ref.points[i]), expected, 1e-9) << i;
  }
}

// ---------------------------------------------------------------------------------------------

class InsideOnMesh : public ::testing::TestWithParam<std::pair<const char*, std::size_t>> {};

TEST_P(InsideOnMesh, AgreesWithWindingNumber) {
  // Uniform points in the grown box, plus points 0.1% of the diagonal off the surface (where the
  // pseudo-normal answers). The reference winding number is an integer off the surface; points
  // where it is not within 1e-3 of one lie on the surface and are skipped (none are expected).
  Rng rng = seeded();
  const auto file = test::cgal_mesh(GetParam().first);
  const auto leaf = MeshLeaf::load(file);
  const Soup soup = reference_soup(file, *leaf);
  const double diag = diagonal(leaf->bounds());
  auto pts = random_points(rng, leaf->bounds().expanded(0.1 * diag), GetParam().second);
  const auto near = near_surface_points(rng, soup, GetParam().second / 5, 1e-3 * diag);
  pts.insert(pts.end(), near.begin(), near.end());
  const Reference ref = reference(soup, pts, false);
  std::size_t skipped = 0, inside = 0;
  const double R = 0.05 * diag;
  for (std::size_t i = 0; i < ref.points.size(); ++i) {
    const double w = ref.winding[i];
    if (std::abs(w - std::round(w)) > 1e-3) {
      ++skipped;
      continue;
    }
    const bool expected = std::lround(std::abs(w)) % 2 == 1;
    inside += expected;
    const glm::dvec3& p = ref.points[i];
    ASSERT_EQ(leaf->inside(p), expected) << "point " << i << " w=" << w;
    ASSERT_EQ(leaf->query(p, R).inside, expected) << "point " << i << " w=" << w;
    ASSERT_EQ(leaf->query(p, 1e-3 * R).inside, expected)
        << "point " << i << " w=" << w << " d=" << leaf->query(p, R).distance << " "
        << brute_distance(soup, p);
  }
  EXPECT_EQ(skipped, 0u);
  EXPECT_GT(inside, ref.points.size() / 20);
}

INSTANTIATE_TEST_SUITE_P(Meshes, InsideOnMesh,
                         ::testing::Values(std::pair<const char*, std::size_t>{"bunny00.off", 2000},
                                           std::pair<const char*, std::size_t>{"eight.off", 10000},
                                           std::pair<const char*, std::size_t>{"knot2.off", 10000}),
                         [](const auto& param_info) { return mesh_test_name(param_info.param.first); });

TEST(MeshQuery, DistanceMatchesBruteForceWithinRadius) {
  Rng rng = seeded();
  for (const char* name : {"eight.off", "knot2.off"}) {
    SCOPED_TRACE(name);
    const auto file = test::cgal_mesh(name);
    const auto leaf = MeshLeaf::load(file);
    const Soup soup = reference_soup(file, *leaf);
    const double R = 0.05 * diagonal(leaf->bounds());
    const Reference ref = reference(soup, random_points(rng, leaf->bounds().expanded(R), 2000), true);
    std::size_t within = 0;
    for (std::size_t i = 0; i < ref.points.size(); ++i) {
      const auto q = leaf->query(ref.points[i], R);
      if (ref.distance[i] < R * (1 - 1e-9)) {
        ++within;
        ASSERT_NEAR(q.distance, ref.distance[i], 1e-12 * diagonal(leaf->bounds())) << i;
      } else if (ref.distance[i] > R * (1 + 1e-9)) {
        ASSERT_TRUE(std::isinf(q.distance)) << i;
      }
      ASSERT_NEAR(leaf->query(ref.points[i], std::numeric_limits<double>::infinity()).distance,
                  ref.distance[i], 1e-12 * diagonal(leaf->bounds()));
    }
    EXPECT_GT(within, 100u);
  }
}

TEST(MeshQuery, BatchAgreesWithSingle) {
  Rng rng = seeded();
  const auto leaf = MeshLeaf::load(test::cgal_mesh("knot2.off"));
  const double diag = diagonal(leaf->bounds());
  const auto pts = random_points(rng, leaf->bounds().expanded(0.1 * diag), 4000);
  std::vector<float> xs, ys, zs;
  for (const auto& p : pts) {
    xs.push_back(static_cast<float>(p.x));
    ys.push_back(static_cast<float>(p.y));
    zs.push_back(static_cast<float>(p.z));
  }
  const float radius = static_cast<float>(0.05 * diag);
  std::vector<float> dist(pts.size());
  std::vector<std::uint8_t> in(pts.size());
  leaf->query_batch(xs.data(), ys.data(), zs.data(), pts.size(), radius, dist.data(), in.data());
  std::size_t finite = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const auto q = leaf->query(glm::dvec3(xs[i], ys[i], zs[i]), static_cast<double>(radius));
    ASSERT_EQ(in[i] != 0, q.inside) << i;
    if (std::isinf(q.distance)) {
      ASSERT_TRUE(std::isinf(dist[i])) << i;
    } else {
      ++finite;
      ASSERT_EQ(dist[i], static_cast<float>(q.distance)) << i;
    }
  }
  EXPECT_GT(finite, 100u);
}

// A bound on the nearest distance (a neighbour's nearest point, or the distance itself, the
// tightest a caller can know) only speeds the search up: the answer is the same bit for bit,
// on a real scan with its needles (bunny00) and on points a cell apart as bricks sample them.
TEST(MeshQuery, BoundChangesNothing) {
  Rng rng = seeded();
  const auto leaf = MeshLeaf::load(test::cgal_mesh("bunny00.off"));
  const double diag = diagonal(leaf->bounds()), R = 0.05 * diag, h = 0.005 * diag;
  std::vector<glm::dvec3> pts;
  for (const glm::dvec3& start : random_points(rng, leaf->bounds().expanded(R), 40))  // rows a cell apart
    for (int i = 0; i < 16; ++i) pts.push_back(start + glm::dvec3(h * i, 0.0, 0.0));
  const auto more = random_points(rng, leaf->bounds().expanded(R), 400);
  pts.insert(pts.end(), more.begin(), more.end());
  auto same = [](const MeshLeaf::Closest& a, const MeshLeaf::Closest& b) {
    return (a.distance == b.distance || (std::isinf(a.distance) && std::isinf(b.distance))) && a.inside == b.inside &&
           (std::isinf(a.distance) || (a.point == b.point && a.normal == b.normal));
  };
  std::size_t bounded = 0;
  for (std::size_t i = 1; i < pts.size(); ++i) {
    const MeshLeaf::Closest free = leaf->query(pts[i], R), prev = leaf->query(pts[i - 1], R);
    if (std::isfinite(free.distance)) {
      ASSERT_TRUE(same(free, leaf->query(pts[i], R, free.distance))) << i;
      ++bounded;
    }
    if (std::isfinite(prev.distance)) {
      ASSERT_TRUE(same(free, leaf->query(pts[i], R, glm::length(pts[i] - prev.point)))) << i;
    }
  }
  EXPECT_GT(bounded, 200u);
  // The batch, which bounds each point by the one before, against single queries.
  std::vector<float> xs, ys, zs;
  for (const auto& p : pts) xs.push_back(float(p.x)), ys.push_back(float(p.y)), zs.push_back(float(p.z));
  std::vector<float> dist(pts.size());
  std::vector<std::uint8_t> in(pts.size());
  for (std::size_t at = 0; at < pts.size(); at += 256) {
    const std::size_t n = std::min<std::size_t>(256, pts.size() - at);
    leaf->query_batch(&xs[at], &ys[at], &zs[at], n, float(R), &dist[at], &in[at]);
  }
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const auto q = leaf->query(glm::dvec3(xs[i], ys[i], zs[i]), double(float(R)));
    ASSERT_EQ(in[i] != 0, q.inside) << i;
    ASSERT_EQ(dist[i], std::isfinite(q.distance) ? float(q.distance) : std::numeric_limits<float>::infinity()) << i;
  }
}

// The query's sphere and disc tests keep their centre in float: placed far from the origin
// (where a float centre is off by a good part of a small triangle), the mesh is asked at points
// hugging its triangles near their corners, just above and below them, where the nearest
// triangle beats its neighbours by less than that rounding. The answer is the exact minimum
// over every triangle (the same closest-point routine), bit for bit: a test that rejected a
// triangle it should not would give a larger distance.
TEST(MeshQuery, FloatRejectionTestsLoseNoTriangle) {
  Rng rng = seeded();
  const auto src = MeshLeaf::load(test::cgal_mesh("eight.off"));
  const glm::dvec3 shift(3000.0, -1700.0, 2300.0);
  std::vector<glm::dvec3> pos = src->positions();
  const double scale = 0.01;  // triangles about 1e-3 across, 3000 from the origin
  for (glm::dvec3& p : pos) p = shift + scale * p;
  const auto leaf = MeshLeaf::from_triangles(pos, src->triangles(), "far eight");
  const auto& P = leaf->positions();
  const auto& T = leaf->triangles();
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::size_t checked = 0;
  for (int i = 0; i < 3000; ++i) {
    const glm::uvec3 t = T[rng() % T.size()];
    const int k = int(rng() % 3);
    const glm::dvec3 a = P[t[k]], b = P[t[(k + 1) % 3]], c = P[t[(k + 2) % 3]];
    const glm::dvec3 n = glm::normalize(glm::cross(b - a, c - a));
    const double edge = glm::length(b - a);
    const double s = 1e-3 * u(rng), r = 1e-3 * u(rng);
    const glm::dvec3 p = a + s * (b - a) + r * (c - a) + (u(rng) - 0.5) * 1e-4 * edge * n;
    double best2 = std::numeric_limits<double>::infinity();
    for (const glm::uvec3& q : T) {
      const glm::dvec3 d = p - closest_on_triangle(p, P[q[0]], P[q[1]], P[q[2]]).point;
      best2 = std::min(best2, glm::dot(d, d));
    }
    ASSERT_EQ(leaf->query(p, 0.1 * edge).distance, std::sqrt(best2)) << i;
    ++checked;
  }
  EXPECT_EQ(checked, 3000u);
}

TEST(MeshQuery, ConcurrentQueriesAgreeWithSerial) {
  // No shared mutable state: the same answers from many threads at once.
  Rng rng = seeded();
  const auto leaf = MeshLeaf::load(test::cgal_mesh("knot2.off"));
  const double diag = diagonal(leaf->bounds());
  const auto pts = random_points(rng, leaf->bounds().expanded(0.05 * diag), 20000);
  std::vector<MeshLeaf::Closest> serial(pts.size()), parallel(pts.size());
  std::vector<std::uint8_t> in_serial(pts.size()), in_parallel(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    serial[i] = leaf->query(pts[i], 0.03 * diag);
    in_serial[i] = leaf->inside(pts[i]);
  }
  tbb::parallel_for(std::size_t(0), pts.size(), [&](std::size_t i) {
    parallel[i] = leaf->query(pts[i], 0.03 * diag);
    in_parallel[i] = leaf->inside(pts[i]);
  });
  for (std::size_t i = 0; i < pts.size(); ++i) {
    ASSERT_EQ(serial[i].distance, parallel[i].distance) << i;
    ASSERT_EQ(serial[i].inside, parallel[i].inside) << i;
    ASSERT_EQ(in_serial[i], in_parallel[i]) << i;
  }
}

// ---------------------------------------------------------------------------------------------

TEST(MeshOrientation, InwardFacingMeshIsTheSameSolid) {
  Rng rng = seeded();
  for (const char* name : {"eight.off", "sphere.off"}) {
    SCOPED_TRACE(name);
    const auto outward = MeshLeaf::load(test::cgal_mesh(name));
    EXPECT_FALSE(outward->report().inverted);
    EXPECT_EQ(outward->report().reoriented_faces, 0u);
    EXPECT_EQ(outward->report().components, 1u);
    auto tris = outward->triangles();
    for (auto& t : tris) std::swap(t[1], t[2]);
    const auto inward = MeshLeaf::from_triangles(outward->positions(), tris, "inward");
    EXPECT_TRUE(inward->report().inverted);
    EXPECT_EQ(inward->report().reoriented_faces, 0u);
    EXPECT_EQ(inward->triangles(), outward->triangles());
    const double diag = diagonal(outward->bounds());
    for (const auto& p : random_points(rng, outward->bounds().expanded(0.1 * diag), 2000)) {
      ASSERT_EQ(inward->inside(p), outward->inside(p));
      const auto a = inward->query(p, 0.05 * diag), b = outward->query(p, 0.05 * diag);
      ASSERT_EQ(a.inside, b.inside);
      ASSERT_EQ(a.distance, b.distance);
    }
  }
}

TEST(MeshOrientation, InconsistentFacesAreFlipped) {
  Rng rng = seeded();
  const auto good = MeshLeaf::load(test::cgal_mesh("eight.off"));
  auto tris = good->triangles();
  std::size_t flipped = 0;
  for (auto& t : tris)
    if (rng() % 3 == 0) std::swap(t[1], t[2]), ++flipped;
  const auto fixed = MeshLeaf::from_triangles(good->positions(), tris, "scrambled");
  EXPECT_EQ(fixed->report().reoriented_faces, flipped);
  EXPECT_FALSE(fixed->report().inverted);
  EXPECT_EQ(fixed->triangles(), good->triangles());
}

// A UV sphere, outward.
Soup sphere(const glm::dvec3& c, double r, unsigned rings = 12, unsigned segments = 16) {
  Soup s;
  s.positions.push_back(c + glm::dvec3(0, 0, r));
  for (unsigned i = 1; i < rings; ++i)
    for (unsigned j = 0; j < segments; ++j) {
      const double th = std::numbers::pi * i / rings, ph = 2 * std::numbers::pi * j / segments;
      s.positions.push_back(
          c + r * glm::dvec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)));
    }
  s.positions.push_back(c - glm::dvec3(0, 0, r));
  const unsigned south = static_cast<unsigned>(s.positions.size() - 1);
  auto at = [&](unsigned i, unsigned j) { return 1 + (i - 1) * segments + j % segments; };
  for (unsigned j = 0; j < segments; ++j) {
    s.triangles.emplace_back(0, at(1, j), at(1, j + 1));
    s.triangles.emplace_back(south, at(rings - 1, j + 1), at(rings - 1, j));
    for (unsigned i = 1; i + 1 < rings; ++i) {
      s.triangles.emplace_back(at(i, j), at(i + 1, j), at(i + 1, j + 1));
      s.triangles.emplace_back(at(i, j), at(i + 1, j + 1), at(i, j + 1));
    }
  }
  return s;
}

Soup merged(const Soup& a, const Soup& b) {
  Soup s = a;
  const auto base = static_cast<unsigned>(a.positions.size());
  s.positions.insert(s.positions.end(), b.positions.begin(), b.positions.end());
  for (const auto& t : b.triangles) s.triangles.push_back(t + glm::uvec3(base));
  return s;
}

TEST(MeshOrientation, NestedShellBoundsACavity) {
  // A hollow ball given with both spheres facing out: the inner one must end up facing in.
  const Soup outer = sphere(glm::dvec3(0.0), 2.0), inner = sphere(glm::dvec3(0.1, 0.0, 0.0), 1.0);
  const Soup s = merged(outer, inner);
  const auto leaf = MeshLeaf::from_triangles(s.positions, s.triangles, "hollow");
  EXPECT_EQ(leaf->report().components, 2u);
  EXPECT_EQ(leaf->report().reoriented_faces, inner.triangles.size());
  EXPECT_FALSE(leaf->report().inverted);
  EXPECT_FALSE(leaf->inside(glm::dvec3(0.1, 0.0, 0.0)));
  EXPECT_TRUE(leaf->inside(glm::dvec3(0.0, 0.0, 1.5)));
  EXPECT_FALSE(leaf->inside(glm::dvec3(0.0, 0.0, 2.5)));
  EXPECT_FALSE(leaf->query(glm::dvec3(0.1, 0.0, 0.2), 1.0).inside);
  EXPECT_TRUE(leaf->query(glm::dvec3(0.1, 0.0, 1.2), 1.0).inside);
  // Two disjoint balls given inward: both flipped, and that is an inverted mesh.
  Soup two = merged(sphere(glm::dvec3(0.0), 1.0), sphere(glm::dvec3(3.0, 0.0, 0.0), 1.0));
  for (auto& t : two.triangles) std::swap(t[1], t[2]);
  const auto pair = MeshLeaf::from_triangles(two.positions, two.triangles, "pair");
  EXPECT_EQ(pair->report().components, 2u);
  EXPECT_TRUE(pair->report().inverted);
  EXPECT_TRUE(pair->inside(glm::dvec3(3.0, 0.1, 0.0)));
}

// A caller that has searched the triangles itself (the ffd node, before unfolding its folds)
// says so, and the crossing-shells search is not made again: the leaf answers the same, bit for
// bit; and the search is indeed skipped (crossing shells given as intersection-free are taken on
// the caller's word, where without the flag they are refused).
TEST(MeshOrientation, IntersectionFreeSkipsOnlyTheShellSearch) {
  const Soup apart = merged(sphere(glm::dvec3(0.0), 1.0), sphere(glm::dvec3(3.0, 0.0, 0.0), 1.0));
  const auto searched = MeshLeaf::from_triangles(apart.positions, apart.triangles, "searched");
  const auto vouched = MeshLeaf::from_triangles(apart.positions, apart.triangles, "vouched", false, MeshInside::Closed, true);
  EXPECT_EQ(vouched->report().components, searched->report().components);
  Rng rng = seeded();
  std::uniform_real_distribution<double> u(-1.5, 4.5);
  for (int i = 0; i < 2000; ++i) {
    const glm::dvec3 p(u(rng), 0.5 * u(rng) - 0.75, 0.5 * u(rng) - 0.75);
    const MeshLeaf::Closest a = searched->query(p, 0.5), b = vouched->query(p, 0.5);
    ASSERT_EQ(a.inside, b.inside);
    ASSERT_TRUE(a.distance == b.distance || (std::isinf(a.distance) && std::isinf(b.distance)));
  }
  const Soup crossing = merged(sphere(glm::dvec3(0.0), 1.0), sphere(glm::dvec3(1.0, 0.0, 0.0), 1.0));
  EXPECT_THROW(MeshLeaf::from_triangles(crossing.positions, crossing.triangles, "crossing"), MeshError);
  EXPECT_NO_THROW(MeshLeaf::from_triangles(crossing.positions, crossing.triangles, "crossing", false, MeshInside::Closed, true));
}

TEST(MeshOrientation, ShellsTouchingAtAVertex) {
  // Two tetrahedra meeting tip to tip: edges are manifold but the shared vertex is not. It is
  // accepted; OpenMesh's form duplicates the vertex, and near it the inside test still agrees
  // with ray parity (outside both cones, each fan's normal sum points away from both).
  Rng rng = seeded();
  const std::vector<glm::dvec3> pos = {{0, 0, 0},    {1, 0, 1},       {-0.5, 0.9, 1},    {-0.5, -0.9, 1},
                                       {0.3, 0, -1}, {-0.2, 1, -0.6}, {-0.9, -0.4, -1.2}};
  const std::vector<glm::uvec3> tris = {{0, 1, 2}, {0, 2, 3}, {0, 3, 1}, {1, 3, 2},
                                        {0, 5, 4}, {0, 6, 5}, {0, 4, 6}, {4, 5, 6}};
  const auto leaf = MeshLeaf::from_triangles(pos, tris, "hourglass");
  EXPECT_EQ(leaf->report().components, 2u);
  EXPECT_EQ(leaf->report().pinched_vertices, 1u);
  EXPECT_EQ(leaf->openmesh().mesh.n_faces(), 8u);
  // What is written out gives each cone its own tip (the mesh as it is failed at the end as a
  // non-manifold output): the same triangles, a copy of vertex 0 for the second fan.
  const TriangleMesh& out = *leaf->manifold_surface();
  EXPECT_EQ(out.triangles.size(), 8u);
  ASSERT_EQ(out.positions.size(), 8u);
  EXPECT_EQ(out.positions[7], out.positions[0]);
  for (std::size_t t = 0; t < 8; ++t)
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(out.triangles[t][k], leaf->triangles()[t][k] == 0 && t >= 4 ? 7u : leaf->triangles()[t][k]) << t;
  const MeshChecks c = check_mesh(out);
  EXPECT_TRUE(c.watertight());
  EXPECT_EQ(c.nonmanifold_vertices, 0u);
  EXPECT_EQ(c.self_intersecting_pairs, 0u);
  const auto one = MeshLeaf::from_triangles({pos.begin(), pos.begin() + 4}, {tris.begin(), tris.begin() + 4}, "one");
  EXPECT_EQ(one->report().pinched_vertices, 0u);
  EXPECT_EQ(one->manifold_surface(), one->surface());
  std::normal_distribution<double> g(0.0, 1.0);
  std::size_t in = 0;
  for (int i = 0; i < 20000; ++i) {
    const glm::dvec3 p = 0.05 * glm::dvec3(g(rng), g(rng), g(rng));
    const bool expected = leaf->inside(p);
    in += expected;
    ASSERT_EQ(leaf->query(p, 1.0).inside, expected) << p.x << " " << p.y << " " << p.z;
  }
  EXPECT_GT(in, 100u);
}

// ---------------------------------------------------------------------------------------------

const std::vector<glm::dvec3> kTetra = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
const std::vector<glm::uvec3> kTetraFaces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};

TEST(MeshErrors, InMemory) {
  auto open = kTetraFaces;
  open.pop_back();
  std::string m = message_of([&] { MeshLeaf::from_triangles(kTetra, open, "open-tet"); });
  EXPECT_NE(m.find("open-tet: 3 open boundary edges"), std::string::npos) << m;
  EXPECT_NE(m.find("repair"), std::string::npos) << m;

  const std::vector<glm::dvec3> fan = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  m = message_of([&] { MeshLeaf::from_triangles(fan, {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}}, "fan"); });
  EXPECT_NE(m.find("fan: 1 non-manifold edges"), std::string::npos) << m;
  EXPECT_NE(m.find("between vertices 0 and 1"), std::string::npos) << m;
  // Repair does not fix non-manifold edges.
  m = message_of([&] { MeshLeaf::from_triangles(fan, {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}}, "fan", true); });
  EXPECT_NE(m.find("non-manifold"), std::string::npos) << m;

  // A shell is flat when its volume's terms cancel to rounding, whatever its proportions: a
  // tetrahedron stretched a million times along x was called flat against its box's diagonal
  // cubed (so was that ffd's deformed sphere, "remove it from the file", of a mesh with no file).
  std::vector<glm::dvec3> needle = kTetra;
  for (glm::dvec3& p : needle) p.x *= 1e6;
  EXPECT_EQ(MeshLeaf::from_triangles(needle, kTetraFaces, "needle")->report().components, 1u);
  std::vector<glm::dvec3> flat = needle;
  flat[3] = {0.25e6, 0.25, 0.0};  // the apex in the base's plane
  m = message_of([&] { MeshLeaf::from_triangles(flat, kTetraFaces, "flat"); });
  EXPECT_NE(m.find("flat: the mesh (4 triangles, "), std::string::npos) << m;
  EXPECT_NE(m.find("encloses no volume"), std::string::npos) << m;
  // A flat parallelogram through its box's centre: every term of its volume is rounding noise.
  const std::vector<glm::dvec3> plane = {{1.1, 1.2, 1.3}, {1.3, 0.9, 1.7}, {0.9, 0.8, 0.7}, {0.7, 1.1, 0.3}};
  m = message_of([&] { MeshLeaf::from_triangles(plane, kTetraFaces, "plane"); });
  EXPECT_NE(m.find("encloses no volume"), std::string::npos) << m;

  m = message_of([&] { MeshLeaf::from_triangles(kTetra, {}, "empty"); });
  EXPECT_NE(m.find("empty: no triangles"), std::string::npos) << m;

  auto nan = kTetra;
  nan[2].y = std::numeric_limits<double>::quiet_NaN();
  m = message_of([&] { MeshLeaf::from_triangles(nan, kTetraFaces, "nan"); });
  EXPECT_NE(m.find("nan: vertex 2 has a non-finite coordinate"), std::string::npos) << m;

  m = message_of([&] { MeshLeaf::from_triangles(kTetra, {{0, 2, 1}, {0, 1, 7}}, "oob"); });
  EXPECT_NE(m.find("oob: face 1 has an out-of-range vertex index"), std::string::npos) << m;

  m = message_of([&] { MeshLeaf::from_triangles(kTetra, {{0, 2, 1}, {0, 1, 1}}, "rep"); });
  EXPECT_NE(m.find("rep: face 1 repeats vertex 1"), std::string::npos) << m;

  // Closed, but bounding no solid: every corner at one point (Embree's builder aborted the
  // process on its boxes), and a flat pillow of two faces. A winding leaf takes them (empty).
  const std::vector<glm::dvec3> point(4, glm::dvec3(0.25, 0.5, 0.75));
  m = message_of([&] { MeshLeaf::from_triangles(point, kTetraFaces, "point"); });
  EXPECT_NE(m.find("point: the mesh (4 triangles, 0 across) encloses no volume"), std::string::npos) << m;
  m = message_of([&] { MeshLeaf::from_triangles(kTetra, {{0, 1, 2}, {0, 2, 1}}, "pillow"); });
  EXPECT_NE(m.find("pillow: the mesh (2 triangles"), std::string::npos) << m;
  EXPECT_NE(m.find("encloses no volume"), std::string::npos) << m;
  EXPECT_NO_THROW(MeshLeaf::from_triangles(point, kTetraFaces, "point", false, MeshInside::Winding));

  // A Moebius strip has one boundary loop; with repair on, orientation fails first.
  std::vector<glm::dvec3> strip;
  std::vector<glm::uvec3> quads;
  const unsigned n = 8;
  for (unsigned i = 0; i < n; ++i) {
    const double a = 2 * std::numbers::pi * i / n, twist = a / 2;
    const glm::dvec3 centre(std::cos(a), std::sin(a), 0.0);
    const glm::dvec3 across = 0.3 * (std::cos(twist) * centre + std::sin(twist) * glm::dvec3(0, 0, 1));
    strip.push_back(centre + across);
    strip.push_back(centre - across);
  }
  for (unsigned i = 0; i < n; ++i) {
    const unsigned t0 = 2 * i, b0 = 2 * i + 1;
    // The last quad closes the strip with a half twist: top meets bottom.
    const unsigned t1 = i + 1 < n ? 2 * i + 2 : 1, b1 = i + 1 < n ? 2 * i + 3 : 0;
    quads.emplace_back(t0, b0, b1);
    quads.emplace_back(t0, b1, t1);
  }
  m = message_of([&] { MeshLeaf::from_triangles(strip, quads, "moebius", true); });
  EXPECT_NE(m.find("moebius: the faces cannot be oriented consistently"), std::string::npos) << m;
  m = message_of([&] { MeshLeaf::from_triangles(strip, quads, "moebius"); });
  EXPECT_NE(m.find("moebius: 16 open boundary edges"), std::string::npos) << m;
}

TEST(MeshErrors, Files) {
  const auto dir = test::temp_dir("mesh-errors");
  test::write_file(dir / "open.off", "OFF\n4 3 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n");
  std::string m = message_of([&] { MeshLeaf::load(dir / "open.off"); });
  EXPECT_NE(m.find("open.off: 3 open boundary edges"), std::string::npos) << m;

  test::write_file(dir / "fan.obj",
                   "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nf 1 2 3\nf 2 1 4\nf 1 2 5\n");
  m = message_of([&] { MeshLeaf::load(dir / "fan.obj"); });
  EXPECT_NE(m.find("fan.obj: 1 non-manifold edges"), std::string::npos) << m;

  test::write_file(dir / "empty.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n");
  m = message_of([&] { MeshLeaf::load(dir / "empty.off"); });
  EXPECT_NE(m.find("empty.off: no triangles"), std::string::npos) << m;

  test::write_file(dir / "oob.off",
                   "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 9\n3 0 3 2\n3 1 2 3\n");
  m = message_of([&] { MeshLeaf::load(dir / "oob.off"); });
  EXPECT_NE(m.find("oob.off: face 1 has an out-of-range vertex index"), std::string::npos) << m;

  test::write_file(dir / "rep.off",
                   "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 1\n3 0 3 2\n3 1 2 3\n");
  m = message_of([&] { MeshLeaf::load(dir / "rep.off"); });
  EXPECT_NE(m.find("rep.off: face 1 repeats vertex 1"), std::string::npos) << m;

  test::write_file(dir / "mesh.xyz", "0 0 0\n");
  m = message_of([&] { MeshLeaf::load(dir / "mesh.xyz"); });
  EXPECT_NE(m.find("mesh.xyz: cannot read"), std::string::npos) << m;

  m = message_of([&] { MeshLeaf::load(dir / "missing.off"); });
  EXPECT_NE(m.find("missing.off: cannot read"), std::string::npos) << m;

  test::write_file(dir / "garbage.ply", "this is not a ply file\n");
  m = message_of([&] { MeshLeaf::load(dir / "garbage.ply"); });
  EXPECT_NE(m.find("garbage.ply: "), std::string::npos) << m;
  std::filesystem::remove_all(dir);
}

TEST(MeshErrors, NonFiniteCoordinateInFile) {
  // OpenMesh's readers would fail on "nan" quietly (OFF reads zeros from there on, OBJ drops the
  // vertex); the text is searched first, so the message names the vertex.
  const auto dir = test::temp_dir("mesh-nan");
  const std::string tet_faces = "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
  test::write_file(dir / "nan.off", "OFF\n4 4 0\n0 0 0\n1 nan 0\n0 1 0\n0 0 1\n" + tet_faces);
  test::write_file(dir / "nan.obj",
                   "v 0 0 0\nv 1 NaN 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  test::write_file(
      dir / "nan.ply",
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 4\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 -inf 0\n0 1 0\n0 0 1\n" +
          tet_faces);
  for (const char* name : {"nan.off", "nan.obj", "nan.ply"}) {
    const std::string m = message_of([&] { MeshLeaf::load(dir / name); });
    EXPECT_NE(m.find(std::string(name) + ": vertex 1 has a non-finite coordinate"), std::string::npos) << m;
  }
  // Words that merely contain "nan" or "inf" (comments, names) are not numbers.
  test::write_file(dir / "ok.obj",
                   "# info: nanometres\nmtllib nan.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                   "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  EXPECT_EQ(MeshLeaf::load(dir / "ok.obj")->report().triangles, 4u);
  std::filesystem::remove_all(dir);
}

TEST(MeshLoad, OffWithCommentsAndCountsOnTheKeywordLine) {
  // Both are valid OFF that OpenMesh's reader does not take as they are.
  const auto dir = test::temp_dir("mesh-off");
  test::write_file(dir / "a.off",
                   "OFF 4 4 0\n# a comment\n0 0 0\n1 0 0 # trailing\n0 1 0\n0 0 1\n"
                   "3 0 2 1\n3 0 1 3\n\n3 0 3 2\n3 1 2 3\n");
  const auto leaf = MeshLeaf::load(dir / "a.off");
  EXPECT_EQ(leaf->report().triangles, 4u);
  EXPECT_EQ(leaf->positions()[1], glm::dvec3(1, 0, 0));
  EXPECT_TRUE(leaf->inside(glm::dvec3(0.1)));
  std::filesystem::remove_all(dir);
}

// ---------------------------------------------------------------------------------------------

TEST(MeshRepair, ClosesTheMissingTetrahedronFace) {
  auto open = kTetraFaces;
  open.erase(open.begin() + 1);
  const auto leaf = MeshLeaf::from_triangles(kTetra, open, "open-tet", true);
  EXPECT_EQ(leaf->report().holes_closed, 1u);
  EXPECT_EQ(leaf->report().triangles_added, 1u);
  EXPECT_EQ(leaf->triangles().size(), 4u);
  EXPECT_EQ(leaf->triangles().back(), kTetraFaces[1]);
  EXPECT_TRUE(leaf->inside(glm::dvec3(0.2)));
  EXPECT_FALSE(leaf->inside(glm::dvec3(0.5)));
  EXPECT_NEAR(leaf->query(glm::dvec3(0.2, 0.2, -0.5), 1.0).distance, 0.5, 1e-12);
}

TEST(MeshRepair, FansLargerHolesAndRefusesHuge) {
  // A sphere missing the faces around its north pole: a 16-edge hole closed by a fan.
  Soup s = sphere(glm::dvec3(0.0), 1.0);
  const std::size_t before = s.triangles.size();
  std::erase_if(s.triangles, [](const glm::uvec3& t) { return t[0] == 0; });
  const auto leaf = MeshLeaf::from_triangles(s.positions, s.triangles, "capless", true);
  EXPECT_EQ(leaf->report().holes_closed, 1u);
  EXPECT_EQ(leaf->report().triangles_added, 16u);
  EXPECT_EQ(leaf->triangles().size(), before);
  EXPECT_EQ(leaf->positions().size(), s.positions.size() + 1);
  EXPECT_TRUE(leaf->inside(glm::dvec3(0.0, 0.0, 0.9)));
  EXPECT_FALSE(leaf->inside(glm::dvec3(0.0, 0.0, 0.99)));

  // With 80 segments the hole has 80 edges: too many.
  Soup big = sphere(glm::dvec3(0.0), 1.0, 8, 80);
  std::erase_if(big.triangles, [](const glm::uvec3& t) { return t[0] == 0; });
  const std::string m =
      message_of([&] { MeshLeaf::from_triangles(big.positions, big.triangles, "big", true); });
  EXPECT_NE(m.find("big: a hole of 80 boundary edges"), std::string::npos) << m;
}

// ---------------------------------------------------------------------------------------------

TEST(MeshLoad, FormatsAndReport) {
  const auto dir = test::temp_dir("mesh-formats");
  // A unit cube with quads (OBJ) counts 6 input faces and 12 triangles.
  test::write_file(dir / "cube.obj",
                   "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                   "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n");
  const auto cube = MeshLeaf::load(dir / "cube.obj");
  EXPECT_EQ(cube->report().input_faces, 6u);
  EXPECT_EQ(cube->report().triangles, 12u);
  EXPECT_EQ(cube->report().vertices, 8u);
  EXPECT_EQ(cube->report().components, 1u);
  EXPECT_TRUE(cube->inside(glm::dvec3(0.5)));
  EXPECT_NEAR(cube->query(glm::dvec3(0.5, 0.5, 0.9), 1.0).distance, 0.1, 1e-12);
  EXPECT_TRUE(cube->query(glm::dvec3(0.5, 0.5, 0.9), 1.0).inside);
  EXPECT_EQ(cube->openmesh().mesh.n_faces(), 12u);
  EXPECT_EQ(cube->openmesh().mesh.n_vertices(), 8u);
  EXPECT_GT(cube->bytes(), 12u * 12u);

  // The same tetrahedron as ASCII STL (vertices merged by position) and ASCII PLY.
  std::string stl = "solid t\n";
  for (const auto& f : kTetraFaces) {
    stl += "facet normal 0 0 0\nouter loop\n";
    for (int k = 0; k < 3; ++k) {
      const auto& p = kTetra[f[k]];
      stl += "vertex " + std::to_string(p.x) + " " + std::to_string(p.y) + " " + std::to_string(p.z) + "\n";
    }
    stl += "endloop\nendfacet\n";
  }
  test::write_file(dir / "tet.stl", stl + "endsolid t\n");
  test::write_file(
      dir / "tet.ply",
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 4\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
  for (const char* name : {"tet.stl", "tet.ply"}) {
    SCOPED_TRACE(name);
    const auto tet = MeshLeaf::load(dir / name);
    EXPECT_EQ(tet->report().triangles, 4u);
    EXPECT_EQ(tet->report().vertices, 4u);
    EXPECT_TRUE(tet->inside(glm::dvec3(0.1)));
    EXPECT_NEAR(tet->query(glm::dvec3(0.1, 0.1, -1.0), 2.0).distance, 1.0, 1e-6);
  }
  std::filesystem::remove_all(dir);

  for (const char* name : {"spot.obj", "igea-67k.ply"}) {
    const auto file = test::shared_mesh(name);
    if (file.empty()) continue;
    const auto leaf = MeshLeaf::load(file);
    EXPECT_GT(leaf->report().triangles, 1000u) << name;
    EXPECT_EQ(leaf->report().components, 1u) << name;
    EXPECT_FALSE(leaf->report().inverted) << name;
    // The two inside tests (pseudo-normal near the surface, ray parity) agree.
    Rng rng = seeded();
    const double diag = diagonal(leaf->bounds());
    for (const auto& p : random_points(rng, leaf->bounds(), 500)) {
      const auto q = leaf->query(p, 0.05 * diag);
      if (std::isfinite(q.distance) && q.distance > 1e-6 * diag) {
        ASSERT_EQ(q.inside, leaf->inside(p)) << name;
      }
    }
  }
}

TEST(MeshCache, LoadsEachFileOnce) {
  const auto abs = std::filesystem::absolute(test::cgal_mesh("sphere.off"));
  const auto rel = std::filesystem::relative(abs, std::filesystem::current_path());
  const auto dotted = abs.parent_path() / ".." / abs.parent_path().filename() / abs.filename();
  MeshCache cache;
  const auto a = cache.get(abs, false);
  EXPECT_EQ(cache.get(rel, false), a);
  EXPECT_EQ(cache.get(dotted, false), a);
  EXPECT_EQ(cache.size(), 1u);
  const auto repaired = cache.get(abs, true);
  EXPECT_NE(repaired, a);
  EXPECT_EQ(cache.size(), 2u);
  EXPECT_THROW(cache.get(abs.parent_path() / "missing.off", false), MeshError);
  EXPECT_EQ(cache.size(), 2u);
}

}  // namespace
}  // namespace ht
