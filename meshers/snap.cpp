#include "meshers/snap.hpp"

#include "meshers/union_find.hpp"

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace ht {
namespace {

constexpr std::uint64_t kFar = ~std::uint64_t(0);
constexpr int kRounds = 64;

// The clusters: vertices sorted by the grid point they are near, one run per point.
std::vector<std::uint32_t> by_point(std::span<const std::uint64_t> near) {
  std::vector<std::uint32_t> order;
  for (std::uint32_t v = 0; v < near.size(); ++v)
    if (near[v] != kFar) order.push_back(v);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return near[a] != near[b] ? near[a] < near[b] : a < b; });
  return order;
}

// contractible()'s arrays, kept across clusters.
struct ContractScratch {
  std::vector<std::uint32_t> tris;
  std::vector<std::uint64_t> edges, far;  // far: the outside edge of each triangle that survives
};

// The triangles at each vertex near a grid point, in triangle order (a vertex far from every grid
// point has none listed): vertex v's are list[start[v], start[v + 1]).
struct TrianglesOf {
  std::vector<std::uint32_t> start, list;
  TrianglesOf(const TriangleMesh& mesh, const std::vector<std::uint64_t>& near, std::uint64_t far) {
    start.assign(mesh.positions.size() + 1, 0);
    for (const glm::uvec3& t : mesh.triangles)
      for (int c = 0; c < 3; ++c)
        if (near[t[c]] != far) ++start[t[c] + 1];
    for (std::size_t v = 0; v + 1 < start.size(); ++v) start[v + 1] += start[v];
    list.resize(start.back());
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
      for (int c = 0; c < 3; ++c)
        if (near[mesh.triangles[t][c]] != far) list[fill[mesh.triangles[t][c]]++] = t;
  }
};

// A cluster may merge when the patch it spans (its vertices, the edges and triangles among them)
// is a disc, Euler characteristic V - E + F = 1, and every outside vertex next to it keeps a
// manifold edge to the merged vertex: exactly two surviving triangles use that edge, and no
// outside edge is in two of them (the link condition). `ring` receives the outside neighbours.
bool contractible(const TriangleMesh& m, const std::vector<std::uint32_t>& cluster, const TrianglesOf& tris_of,
                  std::vector<std::uint32_t>& ring, ContractScratch& scratch) {
  auto& [tris, edges, far] = scratch;
  tris.clear(), edges.clear(), far.clear();
  for (std::uint32_t v : cluster)
    tris.insert(tris.end(), tris_of.list.begin() + tris_of.start[v], tris_of.list.begin() + tris_of.start[v + 1]);
  std::sort(tris.begin(), tris.end());
  tris.erase(std::unique(tris.begin(), tris.end()), tris.end());
  auto in = [&](std::uint32_t v) { return std::binary_search(cluster.begin(), cluster.end(), v); };
  std::size_t inner = 0;  // triangles with all three corners in the cluster
  ring.clear();
  for (std::uint32_t t : tris) {
    int k = 0;
    for (int c = 0; c < 3; ++c) k += in(m.triangles[t][c]);
    if (k == 3) ++inner;
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t a = m.triangles[t][c], b = m.triangles[t][(c + 1) % 3];
      if (in(a) && in(b)) edges.push_back((std::uint64_t(std::min(a, b)) << 32) | std::max(a, b));
      if (k == 1 && !in(a)) ring.push_back(a);  // an edge to the merged vertex that survives
      if (k == 1 && !in(a) && !in(b)) far.push_back((std::uint64_t(std::min(a, b)) << 32) | std::max(a, b));
    }
  }
  // Two surviving triangles on one outside edge would become the same triangle twice (a
  // tetrahedron around the patch flattens into a pillow).
  std::sort(far.begin(), far.end());
  if (std::adjacent_find(far.begin(), far.end()) != far.end()) return false;
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  if (long(cluster.size()) - long(edges.size()) + long(inner) != 1) return false;
  std::sort(ring.begin(), ring.end());
  for (std::size_t i = 0; i < ring.size();) {
    std::size_t j = i;
    while (j < ring.size() && ring[j] == ring[i]) ++j;
    if (j - i != 2) return false;
    i = j;
  }
  ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
  return true;
}


// The point nearest `centre` that lies best on the tangent planes (p_i, n_i): the least-squares
// point of dual contouring (Ju et al. 2002), with the directions the planes do not pin (tiny
// eigenvalues of sum n n^T) left at the centre's. Two planes give a point on their line, three a
// corner.
glm::dvec3 plane_point(std::span<const glm::dvec3> p, std::span<const glm::dvec3> n, const glm::dvec3& centre) {
  glm::dmat3 A(0.0);
  glm::dvec3 b(0.0);
  for (std::size_t i = 0; i < p.size(); ++i) {
    A += glm::outerProduct(n[i], n[i]);
    b += n[i] * glm::dot(n[i], p[i] - centre);
  }
  // Jacobi rotations diagonalize the symmetric A = V D V^T.
  glm::dmat3 V(1.0);
  for (int sweep = 0; sweep < 12; ++sweep) {
    const double off = A[1][0] * A[1][0] + A[2][0] * A[2][0] + A[2][1] * A[2][1];
    if (off < 1e-24) break;
    for (int q = 1; q < 3; ++q)
      for (int r = 0; r < q; ++r) {
        if (std::abs(A[q][r]) < 1e-30) continue;
        const double theta = 0.5 * (A[q][q] - A[r][r]) / A[q][r];
        const double t = (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1.0));
        const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
        glm::dmat3 J(1.0);
        J[r][r] = c, J[q][q] = c, J[q][r] = s, J[r][q] = -s;
        A = glm::transpose(J) * A * J;
        V = V * J;
      }
  }
  const double top = std::max({A[0][0], A[1][1], A[2][2]});
  glm::dvec3 x = centre;
  for (int k = 0; k < 3; ++k)
    if (A[k][k] > 0.1 * top) x += (glm::dot(V[k], b) / A[k][k]) * V[k];
  return x;
}

// Where each merged cluster's vertex goes (its head, the cluster's first vertex). Where the
// cluster's normals agree, the mean of the cluster projected onto the surface by Newton steps.
// Where they spread past the sharp angle, the grid point sits on a crease or a corner: the point
// of the cluster's tangent planes, which becomes a crease point with no normal (so the feature
// step does not split its edges), when it is on the surface and near the cluster.
void place_merged(TriangleMesh& mesh, const std::vector<std::vector<std::uint32_t>>& clusters,
                  std::vector<glm::vec3>& normals, std::vector<std::uint8_t>& crease, const BatchGradient& field,
                  double T, double h, const SnapOptions& options, SnapStats& st) {
  const double cos_sharp = std::cos(options.sharp_angle_degrees * std::numbers::pi / 180.0);
  const std::size_t n = clusters.size();
  std::vector<glm::dvec3> mean(n), at(n);
  std::vector<std::uint8_t> sharp(n, 0);
  std::vector<glm::dvec3> p, nn;
  for (std::size_t c = 0; c < n; ++c) {
    const auto& cluster = clusters[c];
    glm::dvec3 sum(0.0);
    glm::vec3 first(0.0f);
    p.clear(), nn.clear();
    for (std::uint32_t v : cluster) {
      sum += mesh.positions[v];
      if (normals[v] == glm::vec3(0.0f)) continue;
      if (first == glm::vec3(0.0f)) first = normals[v];
      p.push_back(mesh.positions[v]);
      nn.push_back(glm::dvec3(normals[v]));
    }
    mean[c] = sum / double(cluster.size());
    for (std::size_t a = 0; a < nn.size() && !sharp[c]; ++a)
      for (std::size_t b = a + 1; b < nn.size() && !sharp[c]; ++b) sharp[c] = glm::dot(nn[a], nn[b]) < cos_sharp;
    at[c] = sharp[c] ? plane_point(p, nn, mean[c]) : mean[c];
    normals[cluster[0]] = first;
  }
  if (n == 0) return;
  // Only the sharp clusters' plane points are checked against the field.
  std::vector<std::size_t> sharp_ones;
  std::vector<glm::dvec3> sp;
  for (std::size_t c = 0; c < n; ++c)
    if (sharp[c]) sharp_ones.push_back(c), sp.push_back(at[c]);
  std::vector<double> sv(sp.size());
  std::vector<glm::dvec3> sg(sp.size());
  if (!sp.empty()) field(sp, sv, sg);
  for (std::size_t i = 0; i < sharp_ones.size(); ++i) {
    const std::size_t c = sharp_ones[i];
    const double g = glm::length(sg[i]);
    if (g > 0 && std::abs(sv[i] - T) <= options.max_error * h * g && glm::length(at[c] - mean[c]) <= h) {
      const std::uint32_t head = clusters[c][0];
      mesh.positions[head] = at[c];
      crease[head] = 1;
      normals[head] = glm::vec3(0.0f);
      ++st.crease_points;
    } else {
      sharp[c] = 0;
      at[c] = mean[c];
    }
  }
  // The smooth clusters' means onto the surface: two Newton steps (one leaves a face off by half
  // a cell where a cluster beside a crease was judged smooth: tests/test_features.cpp).
  std::vector<std::size_t> smooth;
  std::vector<glm::dvec3> q;
  for (std::size_t c = 0; c < n; ++c)
    if (!sharp[c]) smooth.push_back(c), q.push_back(mean[c]);
  std::vector<glm::dvec3> qg(q.size());
  std::vector<double> qv(q.size());
  for (int step = 0; step < 2 && !q.empty(); ++step) {
    field(q, qv, qg);
    for (std::size_t i = 0; i < q.size(); ++i) {
      const double g2 = glm::dot(qg[i], qg[i]);
      if (g2 > 0 && std::isfinite(g2)) q[i] -= (qv[i] - T) / g2 * qg[i];
    }
  }
  for (std::size_t i = 0; i < smooth.size(); ++i) mesh.positions[clusters[smooth[i]][0]] = q[i];
}

// One round: every cluster whose neighbourhood no other merge of the round touches.
void snap_round(TriangleMesh& mesh, std::vector<std::uint64_t>& near, std::vector<glm::vec3>& normals,
                std::vector<std::uint8_t>& crease, const BatchGradient& field, double T, double h,
                const SnapOptions& options, SnapStats& st) {
  const TrianglesOf tris_of(mesh, near, kFar);
  const std::vector<std::uint32_t> order = by_point(near);
  UnionFind uf(mesh.positions.size());
  std::vector<std::vector<std::uint32_t>> clusters;
  std::vector<std::uint32_t> ring;
  ContractScratch scratch;
  std::vector<std::uint8_t> touched(mesh.positions.size(), 0);
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i;
    while (j < order.size() && near[order[j]] == near[order[i]]) ++j;
    std::vector<std::uint32_t> cluster(order.begin() + std::ptrdiff_t(i), order.begin() + std::ptrdiff_t(j));
    i = j;
    if (cluster.size() < 2) continue;
    // Clusters merge one neighbourhood at a time: none touches another merged one, so each
    // check above holds for the mesh the others leave.
    const bool free = std::none_of(cluster.begin(), cluster.end(), [&](std::uint32_t v) { return touched[v]; });
    const bool ok = free && contractible(mesh, cluster, tris_of, ring, scratch);
    if (!ok || std::any_of(ring.begin(), ring.end(), [&](std::uint32_t v) { return touched[v]; })) {
      ++st.skipped_points;
      continue;
    }
    for (std::uint32_t v : cluster) uf.unite(cluster[0], v), touched[v] = 2;
    for (std::uint32_t v : ring) touched[v] = 1;
    st.merged_vertices += cluster.size() - 1;
    clusters.push_back(std::move(cluster));
  }
  // Nothing merged: every vertex is its own head, and the mesh stays as it is unless a triangle
  // names a vertex twice (which the renumbering below takes away).
  if (clusters.empty() && std::none_of(mesh.triangles.begin(), mesh.triangles.end(), [](const glm::uvec3& t) {
        return t[0] == t[1] || t[1] == t[2] || t[2] == t[0];
      }))
    return;
  place_merged(mesh, clusters, normals, crease, field, T, h, options, st);
  // Renumber: merged vertices share their head, heads keep their order; collapsed triangles go.
  const std::size_t n = mesh.positions.size();
  std::vector<std::uint32_t> head(n), index(n);
  std::uint32_t heads = 0;
  for (std::uint32_t v = 0; v < n; ++v) {  // serial: find() shortens paths as it goes
    head[v] = uf.find(v);
    index[v] = heads;
    heads += head[v] == v;
  }
  // In place, in order (a vertex's new index is never above its old one, nor a triangle's): a
  // copy of the mesh beside it was the peak of a global polygonization.
  for (std::uint32_t v = 0; v < n; ++v) {
    if (head[v] != v) continue;
    const std::uint32_t k = index[v];
    mesh.positions[k] = mesh.positions[v];
    normals[k] = normals[v];
    crease[k] = crease[v];
    near[k] = touched[v] == 2 ? kFar : near[v];  // a merged vertex is done
  }
  mesh.positions.resize(heads);
  normals.resize(heads);
  crease.resize(heads);
  near.resize(heads);
  std::size_t kept = 0;
  for (const glm::uvec3& t : mesh.triangles) {
    const glm::uvec3 r{index[head[t[0]]], index[head[t[1]]], index[head[t[2]]]};
    if (r[0] == r[1] || r[1] == r[2] || r[2] == r[0]) {
      ++st.removed_triangles;
      continue;
    }
    mesh.triangles[kept++] = r;
  }
  mesh.triangles.resize(kept);
}
}  // namespace

void snap_to_grid_points(TriangleMesh& mesh, std::span<const std::uint64_t> near_in, std::vector<glm::vec3>& normals,
                         std::vector<std::uint8_t>& crease, const BatchGradient& field, double T, double h,
                         const SnapOptions& options, SnapStats* stats) {
  SnapStats total;
  std::vector<std::uint64_t> near(near_in.begin(), near_in.end());
  normals.resize(mesh.positions.size(), glm::vec3(0.0f));
  crease.assign(mesh.positions.size(), 0);
  // Clusters next to one merged in a round wait for the next: a plane of grid points merges in a
  // few rounds, each check made on the mesh the previous rounds left.
  for (int round = 0; round < kRounds; ++round) {
    SnapStats st;
    snap_round(mesh, near, normals, crease, field, T, h, options, st);
    total.merged_vertices += st.merged_vertices;
    total.removed_triangles += st.removed_triangles;
    total.crease_points += st.crease_points;
    total.skipped_points = st.skipped_points;
    if (st.merged_vertices == 0 || st.skipped_points == 0) break;
  }
  if (stats) *stats = total;
}

}  // namespace ht
