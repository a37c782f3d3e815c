#include "meshers/mesh_checks.hpp"

#include "meshers/union_find.hpp"

#include "meshers/self_intersections.hpp"
#include "meshers/surface_field.hpp"
#include "runtime/tape_eval.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <vector>

namespace ht {
namespace {

constexpr std::uint32_t kNoIndex = ~0u;

}  // namespace

MeshChecks check_mesh(const TriangleMesh& mesh, bool self_intersections) {
  MeshChecks c;
  const auto& P = mesh.positions;
  const auto& T = mesh.triangles;
  c.vertices = P.size();
  c.triangles = T.size();

  // Half-edges sorted by their undirected edge: count how many triangles use each edge and in
  // which direction.
  struct HalfEdge {
    std::uint32_t lo, hi, tri;
    bool forward;  // from lo to hi
  };
  std::vector<HalfEdge> he;
  he.reserve(3 * T.size());
  for (std::uint32_t t = 0; t < T.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = T[t][k], b = T[t][(k + 1) % 3];
      he.push_back({std::min(a, b), std::max(a, b), t, a < b});
    }
  std::sort(he.begin(), he.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return x.lo != y.lo ? x.lo < y.lo : x.hi != y.hi ? x.hi < y.hi : x.tri < y.tri;
  });
  UnionFind tris(T.size());
  for (std::size_t i = 0; i < he.size();) {
    std::size_t j = i;
    while (j < he.size() && he[j].lo == he[i].lo && he[j].hi == he[i].hi) ++j;
    ++c.edges;
    const std::size_t uses = j - i;
    if (uses == 1) ++c.boundary_edges;
    if (uses > 2) ++c.nonmanifold_edges;
    if (uses == 2 && he[i].forward == he[i + 1].forward) ++c.misoriented_edges;
    const std::uint32_t first = he[i].tri;
    for (auto it = he.begin() + std::ptrdiff_t(i) + 1; it != he.begin() + std::ptrdiff_t(j); ++it) tris.unite(first, it->tri);
    i = j;
  }

  // Vertex fans: the triangles around a vertex, linked through the edges at the vertex, must
  // form one group.
  std::vector<std::uint32_t> start(P.size() + 1, 0);
  for (const auto& t : T)
    for (int k = 0; k < 3; ++k) ++start[t[k] + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<std::uint32_t> incident(start.back()), fill(start.begin(), start.end() - 1);
  for (std::uint32_t t = 0; t < T.size(); ++t)
    for (int k = 0; k < 3; ++k) incident[fill[T[t][k]]++] = t;
  std::vector<std::uint32_t> group;
  for (std::uint32_t v = 0; v < P.size(); ++v) {
    const std::uint32_t b = start[v], e = start[v + 1];
    if (b == e) {
      ++c.unused_vertices;
      continue;
    }
    // Small fans: a quadratic link is cheaper than any structure.
    group.assign(e - b, 0);
    std::iota(group.begin(), group.end(), 0u);
    auto root = [&](std::uint32_t x) {
      while (group[x] != x) x = group[x];
      return x;
    };
    for (std::uint32_t i = b; i < e; ++i)
      for (std::uint32_t j = i + 1; j < e; ++j) {
        const auto& ti = T[incident[i]];
        const auto& tj = T[incident[j]];
        int shared = 0;  // vertices shared besides v: an edge at v when there is one
        for (int x = 0; x < 3; ++x)
          for (int y = 0; y < 3; ++y) shared += (ti[x] == tj[y] && ti[x] != v) ? 1 : 0;
        if (shared > 0) group[root(i - b)] = root(j - b);
      }
    std::size_t roots = 0;
    for (std::uint32_t i = 0; i < e - b; ++i) roots += root(i) == i ? 1 : 0;
    if (roots > 1) ++c.nonmanifold_vertices;
  }

  // Components, Euler characteristic and genus.
  std::vector<long> comp_v, comp_e, comp_f;
  std::vector<std::uint32_t> comp_of(T.size()), comp_id(T.size(), kNoIndex);
  for (std::uint32_t t = 0; t < T.size(); ++t) {
    const std::uint32_t r = tris.find(t);
    if (comp_id[r] == kNoIndex) {
      comp_id[r] = static_cast<std::uint32_t>(comp_f.size());
      comp_v.push_back(0);
      comp_e.push_back(0);
      comp_f.push_back(0);
    }
    comp_of[t] = comp_id[r];
    ++comp_f[comp_of[t]];
  }
  c.components = comp_f.size();
  for (std::uint32_t v = 0; v < P.size(); ++v)
    if (start[v] != start[v + 1]) ++comp_v[comp_of[incident[start[v]]]];
  for (std::size_t i = 0; i < he.size();) {
    std::size_t j = i;
    while (j < he.size() && he[j].lo == he[i].lo && he[j].hi == he[i].hi) ++j;
    ++comp_e[comp_of[he[i].tri]];
    i = j;
  }
  for (std::size_t k = 0; k < comp_f.size(); ++k) {
    const long chi = comp_v[k] - comp_e[k] + comp_f[k];
    c.euler += chi;
    c.genus += (2 - chi) / 2;
  }

  // Geometry.
  glm::dvec3 lo(0.0), hi(0.0);
  if (!P.empty()) lo = hi = P[0];
  for (const auto& p : P) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  const double scale = std::max(glm::length(hi - lo), 1e-300);
  c.min_angle = T.empty() ? 0.0 : 180.0;
  std::vector<float> smallest;  // each triangle's smallest angle, for the percentile
  smallest.reserve(T.size());
  for (const auto& t : T) {
    const glm::dvec3 a = P[t[0]], b = P[t[1]], d = P[t[2]];
    const glm::dvec3 n = glm::cross(b - a, d - a);
    const double area2 = glm::length(n);
    c.area += 0.5 * area2;
    c.volume += glm::dot(a, glm::cross(b, d)) / 6.0;
    if (area2 <= 1e-14 * scale * scale) ++c.degenerate_triangles;
    double amin = 180.0;
    const glm::dvec3 v[3] = {a, b, d};
    for (int k = 0; k < 3; ++k) {
      const glm::dvec3 e1 = v[(k + 1) % 3] - v[k], e2 = v[(k + 2) % 3] - v[k];
      const double ang = std::atan2(glm::length(glm::cross(e1, e2)), glm::dot(e1, e2)) * 180.0 / std::numbers::pi;
      amin = std::min(amin, ang);
    }
    c.min_angle = std::min(c.min_angle, amin);
    ++c.min_angle_histogram[std::min<std::size_t>(5, static_cast<std::size_t>(amin / 10.0))];
    smallest.push_back(float(amin));
  }
  if (!smallest.empty()) {
    const auto at = smallest.begin() + std::ptrdiff_t(smallest.size() / 100);
    std::nth_element(smallest.begin(), at, smallest.end());
    c.min_angle_p1 = *at;
  }
  if (!T.empty() && self_intersections) c.self_intersecting_pairs = find_self_intersections(mesh, 0).pairs;
  return c;
}

namespace {

// f and grad f come from `gradient(points, values, gradients)`.
template <class Gradient>
void surface_error(const TriangleMesh& mesh, Gradient&& gradient, double T, MeshChecks& c) {
  std::vector<double> f;
  std::vector<glm::dvec3> g;
  auto measure = [&](const std::vector<glm::dvec3>& pts, double& max, double& mean) {
    if (pts.empty()) return;
    f.resize(pts.size());
    g.resize(pts.size());
    gradient(pts, f, g);
    double sum = 0;
    max = 0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const double gl = glm::length(g[i]);
      const double e = gl > 0 ? std::abs(f[i] - T) / gl : (std::abs(f[i] - T) > 0 ? 1e300 : 0.0);
      max = std::max(max, e);
      sum += e;
    }
    mean = sum / double(pts.size());
  };
  measure(mesh.positions, c.vertex_error_max, c.vertex_error_mean);
  std::vector<glm::dvec3> centres(mesh.triangles.size());
  for (std::size_t t = 0; t < centres.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    centres[t] = (mesh.positions[tri[0]] + mesh.positions[tri[1]] + mesh.positions[tri[2]]) / 3.0;
  }
  measure(centres, c.face_error_max, c.face_error_mean);
  // The field grows inward, so an outward face normal points against grad f.
  c.inverted_faces = 0;
  c.inverted_area = 0;
  for (std::size_t t = 0; t < centres.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    const auto& P = mesh.positions;
    const glm::dvec3 n = glm::cross(P[tri[1]] - P[tri[0]], P[tri[2]] - P[tri[0]]);
    if (glm::dot(n, g[t]) > 0) {
      ++c.inverted_faces;
      c.inverted_area += 0.5 * glm::length(n);
    }
  }
}

}  // namespace

void measure_surface_error(const TriangleMesh& mesh, const TapeEvaluator& tape, double T, MeshChecks& c) {
  surface_error(mesh, [&](const auto& p, auto& f, auto& g) { tape.gradient(p, f, g); }, T, c);
}

void measure_surface_error(const TriangleMesh& mesh, SurfaceField& field, MeshChecks& c) {
  surface_error(mesh, [&](const auto& p, auto& f, auto& g) { field.gradient(p, f, g); }, field.threshold(), c);
}

}  // namespace ht
