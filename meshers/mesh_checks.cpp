#include "meshers/mesh_checks.hpp"

#include "meshers/union_find.hpp"

#include "meshers/self_intersections.hpp"
#include "meshers/surface_field.hpp"
#include "meshers/unfold.hpp"
#include "nodes/edge_keys.hpp"
#include "nodes/mesh_leaf.hpp"
#include "nodes/warps.hpp"
#include "runtime/graph.hpp"
#include "runtime/tape_eval.hpp"

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <span>
#include <tuple>
#include <vector>

namespace ht {
namespace {

constexpr std::uint32_t kNoIndex = ~0u;

// Degrees.
double smallest_angle(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& d) {
  double amin = 180.0;
  const glm::dvec3 v[3] = {a, b, d};
  for (int k = 0; k < 3; ++k) {
    const glm::dvec3 e1 = v[(k + 1) % 3] - v[k], e2 = v[(k + 2) % 3] - v[k];
    const double ang = std::atan2(glm::length(glm::cross(e1, e2)), glm::dot(e1, e2)) * 180.0 / std::numbers::pi;
    amin = std::min(amin, ang);
  }
  return amin;
}

// The smallest value and the first percentile of `angles` (reordered); zeros when empty.
std::pair<double, double> min_and_p1(std::vector<float>& angles) {
  if (angles.empty()) return {0.0, 0.0};
  const auto at = angles.begin() + std::ptrdiff_t(angles.size() / 100);
  std::nth_element(angles.begin(), at, angles.end());
  const double p1 = *at;
  return {*std::min_element(angles.begin(), at + 1), p1};
}


// Each edge's sides (EdgeKeys file every edge under its lower vertex) as f(v, keys), for the
// vertices in [from, to).
template <class F>
void for_each_edge(const EdgeKeys& e, std::size_t from, std::size_t to, F&& f) {
  for (std::size_t v = from; v < to; ++v)
    e.for_each_edge(std::uint32_t(v), [&](std::span<const std::uint64_t> run) { f(std::uint32_t(v), run); });
}

// Edges by use and direction; vertex fans; with `tris`, the triangles joined across each edge
// into components. Blocks of vertices (whole edges each) run in parallel, their counts summed in
// block order, their unions into sets whose representatives (each set's smallest member) do not
// depend on the order (meshers/union_find.hpp ConcurrentUnionFind).
//
// Vertex fans: the triangles around a vertex, linked through the edges at the vertex, must form
// one group. Each triangle's corner stands for the triangle at that vertex; the sides of an edge
// join their corners at each end, so each group of corners left is one fan.
void edge_and_fan_census(const std::vector<glm::uvec3>& T, const EdgeKeys& ek, std::size_t vertices,
                         ConcurrentUnionFind* tris, MeshChecks& c) {
  ConcurrentUnionFind corners(3 * T.size());
  // Side s runs from corner s % 3 of triangle s / 3 to the next; forward when it starts at `lo`.
  auto forward = [&](std::uint64_t key, std::uint32_t lo) { const std::uint32_t s = EdgeKeys::side(key); return T[s / 3][s % 3] == lo; };
  // The corner of a side's triangle at the edge's lower (or upper) vertex.
  auto at = [&](std::uint64_t key, std::uint32_t lo, bool lower) {
    const std::uint32_t s = EdgeKeys::side(key);
    return 3 * (s / 3) + (forward(key, lo) == lower ? s % 3 : (s % 3 + 1) % 3);
  };
  constexpr std::size_t kBlocks = 64;
  std::vector<std::array<std::size_t, 4>> counts(kBlocks, {0, 0, 0, 0});
  tbb::parallel_for(std::size_t(0), kBlocks, [&](std::size_t block) {
    std::array<std::size_t, 4>& k = counts[block];
    for_each_edge(ek, vertices * block / kBlocks, vertices * (block + 1) / kBlocks, [&](std::uint32_t lo, std::span<const std::uint64_t> run) {
      ++k[0];
      if (run.size() == 1) ++k[1];
      if (run.size() > 2) ++k[2];
      if (run.size() == 2 && forward(run[0], lo) == forward(run[1], lo)) ++k[3];
      if (tris)
        for (const std::uint64_t side : run.subspan(1)) tris->unite(EdgeKeys::side(run[0]) / 3, EdgeKeys::side(side) / 3);
      // A side from a vertex to itself links nothing: a triangle naming v twice beside w has both
      // its corners at v on the edge vw, and one naming v thrice shares no other vertex.
      if (EdgeKeys::upper(run[0]) == lo) return;
      for (std::size_t i = 1; i < run.size(); ++i) {
        corners.unite(at(run[i - 1], lo, true), at(run[i], lo, true));
        corners.unite(at(run[i - 1], lo, false), at(run[i], lo, false));
      }
    });
  });
  for (const auto& k : counts) {
    c.edges += k[0];
    c.boundary_edges += k[1];
    c.nonmanifold_edges += k[2];
    c.misoriented_edges += k[3];
  }
  std::vector<std::uint8_t> root(3 * T.size());
  tbb::parallel_for(std::size_t(0), root.size(), [&](std::size_t k) { root[k] = corners.find(std::uint32_t(k)) == k; });
  std::vector<std::uint8_t> fans(vertices, 0);  // 0, 1, or 2 for more than one
  for (std::size_t k = 0; k < root.size(); ++k)
    if (root[k]) {
      std::uint8_t& f = fans[T[k / 3][static_cast<glm::length_t>(k % 3)]];
      f = std::uint8_t(std::min(f + 1, 2));
    }
  for (const std::uint8_t f : fans) {
    c.unused_vertices += f == 0;
    c.nonmanifold_vertices += f == 2;
  }
}

// Components, Euler characteristic and genus.
void component_census(const std::vector<glm::uvec3>& T, const EdgeKeys& ek, ConcurrentUnionFind& tris,
                      const std::vector<std::uint32_t>& start, const std::vector<std::uint32_t>& incident,
                      MeshChecks& c) {
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
  for (std::size_t v = 0; v + 1 < start.size(); ++v)
    if (start[v] != start[v + 1]) ++comp_v[comp_of[incident[start[v]]]];
  for_each_edge(ek, 0, ek.first.size() - 1,
                [&](std::uint32_t, std::span<const std::uint64_t> run) { ++comp_e[comp_of[EdgeKeys::side(run[0]) / 3]]; });
  for (std::size_t k = 0; k < comp_f.size(); ++k) {
    const long chi = comp_v[k] - comp_e[k] + comp_f[k];
    c.euler += chi;
    c.genus += (2 - chi) / 2;
  }
}

// Degenerate triangles and, when `full`, area, volume and angles: each triangle's figures in
// parallel, summed in triangle order (the same bits at any thread count).
void geometry_census(const TriangleMesh& mesh, bool full, MeshChecks& c) {
  const auto& P = mesh.positions;
  const auto& T = mesh.triangles;
  glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-lo);
  for (const auto& p : P) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      ++c.nonfinite_vertices;
      continue;
    }
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  if (lo.x > hi.x) lo = hi = glm::dvec3(0.0);  // no finite vertex
  const double scale = std::max(glm::length(hi - lo), 1e-300);
  const glm::dvec3 centre = 0.5 * (lo + hi);
  std::vector<double> area2(T.size());
  tbb::parallel_for(std::size_t(0), T.size(), [&](std::size_t i) {
    const glm::uvec3& t = T[i];
    area2[i] = glm::length(glm::cross(P[t[1]] - P[t[0]], P[t[2]] - P[t[0]]));
  });
  for (std::size_t i = 0; i < T.size(); ++i)
    if (area2[i] <= 1e-14 * scale * scale) ++c.degenerate_triangles;
  if (!full) return;
  std::vector<double> volume6(T.size());
  std::vector<float> smallest(T.size());  // each triangle's smallest angle, for the percentile
  std::vector<double> amin(T.size());
  tbb::parallel_for(std::size_t(0), T.size(), [&](std::size_t i) {
    const glm::uvec3& t = T[i];
    const glm::dvec3 a = P[t[0]], b = P[t[1]], d = P[t[2]];
    // About the box's centre: about the origin, a box at 1e6 summed to -15499 for 2.
    volume6[i] = glm::dot(a - centre, glm::cross(b - centre, d - centre));
    amin[i] = smallest_angle(a, b, d);
    smallest[i] = float(amin[i]);
  });
  c.min_angle = T.empty() ? 0.0 : 180.0;
  for (std::size_t i = 0; i < T.size(); ++i) {
    c.area += 0.5 * area2[i];
    c.volume += volume6[i] / 6.0;
    c.min_angle = std::min(c.min_angle, amin[i]);
    ++c.min_angle_histogram[std::min<std::size_t>(5, static_cast<std::size_t>(amin[i] / 10.0))];
  }
  if (!smallest.empty()) c.min_angle_p1 = min_and_p1(smallest).second;
}

// The figures of check_mesh() but the intersections; with `full` false only those
// check_watertight() fills.
MeshChecks census(const TriangleMesh& mesh, bool full) {
  MeshChecks c;
  const auto& P = mesh.positions;
  const auto& T = mesh.triangles;
  c.vertices = P.size();
  c.triangles = T.size();
  const EdgeKeys ek = edge_keys(T, P.size());
  ConcurrentUnionFind tris(full ? T.size() : 0);
  edge_and_fan_census(T, ek, P.size(), full ? &tris : nullptr, c);
  if (full) {
    // Each vertex's triangles.
    std::vector<std::uint32_t> start(P.size() + 1, 0);
    for (const auto& t : T)
      for (int k = 0; k < 3; ++k) ++start[t[k] + 1];
    std::partial_sum(start.begin(), start.end(), start.begin());
    std::vector<std::uint32_t> incident(start.back()), fill(start.begin(), start.end() - 1);
    for (std::uint32_t t = 0; t < T.size(); ++t)
      for (int k = 0; k < 3; ++k) incident[fill[T[t][k]]++] = t;
    component_census(T, ek, tris, start, incident, c);
  }
  geometry_census(mesh, full, c);
  return c;
}

}  // namespace

MeshChecks check_mesh(const TriangleMesh& mesh, bool self_intersections) {
  MeshChecks c = census(mesh, true);
  if (!mesh.triangles.empty() && self_intersections) c.self_intersecting_pairs = find_self_intersections(mesh, 0).pairs;
  return c;
}

MeshChecks check_watertight(const TriangleMesh& mesh) { return census(mesh, false); }

namespace {

// f and grad f come from `gradient(points, values, gradients)`.
// Flags the triangles across which the gradient turns by more than kCreaseTurnDegrees (between
// any two of its corners' and its centre's), and every triangle sharing a vertex with one.
std::vector<std::uint8_t> crease_triangles(const TriangleMesh& mesh, std::span<const glm::dvec3> at_vertices,
                                           std::span<const glm::dvec3> at_centres) {
  const double cos_turn = std::cos(kCreaseTurnDegrees * std::numbers::pi / 180.0);
  auto turns = [&](glm::dvec3 a, glm::dvec3 b) {
    const double la = glm::length(a), lb = glm::length(b);
    return la > 0 && lb > 0 && glm::dot(a, b) < cos_turn * la * lb;
  };
  std::vector<std::uint8_t> near_vertex(mesh.positions.size(), 0), out(mesh.triangles.size(), 0);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    const glm::dvec3 g[4] = {at_vertices[tri[0]], at_vertices[tri[1]], at_vertices[tri[2]], at_centres[t]};
    bool turned = false;
    for (int i = 0; i < 4 && !turned; ++i)
      for (int j = i + 1; j < 4 && !turned; ++j) turned = turns(g[i], g[j]);
    if (turned)
      for (int k = 0; k < 3; ++k) near_vertex[tri[k]] = 1;
  }
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    out[t] = near_vertex[tri[0]] | near_vertex[tri[1]] | near_vertex[tri[2]];
  }
  return out;
}

// The angle census of MeshChecks: kept, crease and smooth triangles.
void angle_census(const TriangleMesh& mesh, std::span<const std::uint8_t> kept, std::span<const std::uint8_t> crease,
                  MeshChecks& c) {
  std::vector<float> made, smooth;
  c.kept_triangles = c.crease_triangles = 0;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (!kept.empty() && kept[t]) {
      ++c.kept_triangles;
      continue;
    }
    const auto& tri = mesh.triangles[t];
    const auto a = float(smallest_angle(mesh.positions[tri[0]], mesh.positions[tri[1]], mesh.positions[tri[2]]));
    made.push_back(a);
    if (crease[t])
      ++c.crease_triangles;
    else
      smooth.push_back(a);
  }
  c.smooth_triangles = smooth.size();
  std::tie(c.made_min_angle, c.made_min_angle_p1) = min_and_p1(made);
  std::tie(c.smooth_min_angle, c.smooth_min_angle_p1) = min_and_p1(smooth);
}

// What a first-order estimate reads where grad f is zero and f is not T.
constexpr double kUnbounded = 1e300;

double first_order(double f, const glm::dvec3& g, double T) {
  const double gl = glm::length(g);
  return gl > 0 ? std::abs(f - T) / gl : (std::abs(f - T) > 0 ? kUnbounded : 0.0);
}

template <class Gradient>
void surface_error(const TriangleMesh& mesh, Gradient&& gradient, double T, MeshChecks& c,
                   std::span<const std::uint8_t> kept) {
  std::vector<double> f, vertex_errors(mesh.positions.size());
  std::vector<glm::dvec3> g;
  auto evaluate = [&](const std::vector<glm::dvec3>& pts) {
    f.resize(pts.size());
    g.resize(pts.size());
    if (!pts.empty()) gradient(pts, f, g);
  };
  auto summarize = [](const std::vector<double>& errors, double& max, double& mean) {
    max = mean = 0;
    for (const double e : errors) max = std::max(max, e), mean += e;
    if (!errors.empty()) mean /= double(errors.size());
  };
  evaluate(mesh.positions);
  for (std::size_t v = 0; v < vertex_errors.size(); ++v) vertex_errors[v] = first_order(f[v], g[v], T);
  summarize(vertex_errors, c.vertex_error_max, c.vertex_error_mean);
  const std::vector<glm::dvec3> at_vertices = g;
  std::vector<glm::dvec3> centres(mesh.triangles.size());
  for (std::size_t t = 0; t < centres.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    centres[t] = (mesh.positions[tri[0]] + mesh.positions[tri[1]] + mesh.positions[tri[2]]) / 3.0;
  }
  evaluate(centres);
  // The quotient is the error's first-order estimate. Where grad f nearly vanishes (a small
  // primitive's centre, a weak blend) it can read far more than the centre's distance to its
  // nearest corner plus that corner's error, which bounds the true distance: it is capped there.
  std::vector<double> face_errors(centres.size());
  for (std::size_t t = 0; t < centres.size(); ++t) {
    double bound = kUnbounded;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = mesh.triangles[t][k];
      bound = std::min(bound, glm::distance(centres[t], mesh.positions[v]) + vertex_errors[v]);
    }
    face_errors[t] = std::min(first_order(f[t], g[t], T), bound);
  }
  summarize(face_errors, c.face_error_max, c.face_error_mean);
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
  if (mesh.positions.empty()) return;
  c.folded_triangles = folded_triangles(mesh, [&](std::span<const glm::dvec3> p, std::span<double> v, std::span<glm::dvec3> d) {
                         gradient(p, v, d);
                       }).size();
  angle_census(mesh, kept, crease_triangles(mesh, at_vertices, g), c);
}

}  // namespace

void measure_surface_error(const TriangleMesh& mesh, const TapeEvaluator& tape, double T, MeshChecks& c,
                           std::span<const std::uint8_t> kept) {
  surface_error(mesh, [&](const auto& p, auto& f, auto& g) { tape.gradient(p, f, g); }, T, c, kept);
}

void measure_surface_error(const TriangleMesh& mesh, SurfaceField& field, MeshChecks& c,
                           std::span<const std::uint8_t> kept) {
  surface_error(mesh, [&](const auto& p, auto& f, auto& g) { field.gradient(p, f, g); }, field.threshold(), c, kept);
}

namespace {

// The corners of every mesh leaf (and prepared ffd) under `n`, moved by the affine nodes above it
// up to the root, the way the warped-child jobs move them: innermost first, with the same map.
// Below a twist, taper or bend the triangles change shape, so nothing there counts.
void leaf_corners(const Graph& g, NodeId n, std::vector<NodeId>& affines, std::vector<glm::dvec3>& out,
                  std::size_t& budget) {
  if (budget == 0) return;
  --budget;
  if (g.mesh[n] != kNone && g.meshes[g.mesh[n]]) {
    for (glm::dvec3 p : g.meshes[g.mesh[n]]->positions()) {
      for (auto a = affines.rbegin(); a != affines.rend(); ++a) p = warp_forward(NodeKind::Affine, g.params_of(*a).data(), p);
      out.push_back(p);
    }
    return;
  }
  if (kind_family(g.kind[n]) == Family::Warp && g.kind[n] != NodeKind::Affine) return;
  if (g.kind[n] == NodeKind::Affine) affines.push_back(n);
  for (NodeId c : g.children_of(n)) leaf_corners(g, c, affines, out, budget);
  if (g.kind[n] == NodeKind::Affine) affines.pop_back();
}

}  // namespace

std::vector<std::uint8_t> kept_leaf_triangles(const TriangleMesh& mesh, std::vector<glm::dvec3> corners) {
  auto less = [](const glm::dvec3& a, const glm::dvec3& b) {
    return a.x != b.x ? a.x < b.x : a.y != b.y ? a.y < b.y : a.z < b.z;
  };
  std::sort(corners.begin(), corners.end(), less);
  std::vector<std::uint8_t> on_leaf(mesh.positions.size(), 0), out(mesh.triangles.size(), 0);
  if (corners.empty()) return out;
  for (std::size_t v = 0; v < mesh.positions.size(); ++v)
    on_leaf[v] = std::binary_search(corners.begin(), corners.end(), mesh.positions[v], less);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    out[t] = on_leaf[tri[0]] & on_leaf[tri[1]] & on_leaf[tri[2]];
  }
  return out;
}

std::vector<std::uint8_t> kept_leaf_triangles(const TriangleMesh& mesh, const Graph& graph, NodeId root) {
  std::vector<glm::dvec3> corners;
  std::vector<NodeId> affines;
  std::size_t budget = 4096;  // node visits: a tree that shares subtrees is walked once a path
  leaf_corners(graph, root, affines, corners, budget);
  return kept_leaf_triangles(mesh, std::move(corners));
}

std::string describe_defects(const MeshChecks& c) {
  std::string why;
  auto add = [&](std::size_t n, const char* what) {
    if (n) why += (why.empty() ? "" : ", ") + std::to_string(n) + " " + what;
  };
  add(c.nonfinite_vertices, "vertices not finite");
  add(c.boundary_edges, "boundary edges");
  add(c.nonmanifold_edges, "non-manifold edges");
  add(c.nonmanifold_vertices, "non-manifold vertices");
  add(c.misoriented_edges, "misoriented edges");
  add(c.degenerate_triangles, "degenerate triangles");
  add(c.self_intersecting_pairs, "self-intersecting triangle pairs");
  return why;
}

}  // namespace ht
