// Collapsing folds away; see meshers/unfold.hpp.
#include "meshers/unfold.hpp"

#include "meshers/halfedge_ops.hpp"
#include "meshers/relax.hpp"
#include "meshers/submesh.hpp"
#include "meshers/triangle_shape.hpp"
#include "nodes/trimesh.hpp"

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <numbers>

namespace ht {
namespace {

using VH = TriMesh::VertexHandle;
using HH = TriMesh::HalfedgeHandle;
using FH = TriMesh::FaceHandle;

constexpr double kTurnCos = 0.5;                     // cos 60 degrees: the most a surviving face may turn
constexpr double kDegenerate = 1e-12;                // squared area (relative to the longest edge^4) left by a collapse

glm::dvec3 g(const TriMesh::Point& p) { return {p[0], p[1], p[2]}; }

glm::dvec3 face_normal(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) { return glm::cross(b - a, c - a); }

class Collapser {
 public:
  Collapser(TriMesh& m, OpenMesh::VPropHandleT<bool> locked, OpenMesh::VPropHandleT<std::uint32_t> origin,
            const std::vector<std::uint8_t>& crease)
      : m_(m), locked_(locked), origin_(origin), crease_(crease) {}

  // Each intersecting triangle (by its corners) gives up its shortest edge that may go. When
  // `widely`, for folds the strict rules could not touch: any edge at its corners may go, crease
  // points too, and a surviving face may turn up to 90 degrees.
  std::size_t run(const std::vector<std::array<std::uint32_t, 3>>& bad, bool widely) {
    widely_ = widely;
    std::size_t done = 0;
    std::vector<std::pair<double, HH>> edges;
    for (const auto& tri : bad) {
      const FH f = find_face(tri);
      if (!f.is_valid() || m_.status(f).deleted()) continue;
      edges.clear();
      if (!widely) {
        for (const HH h : m_.fh_range(f)) edges.push_back({m_.calc_edge_length(h), h});
      } else {
        for (const VH v : m_.fv_range(f))
          for (const HH h : m_.voh_range(v)) edges.push_back({m_.calc_edge_length(h), h});
      }
      std::stable_sort(edges.begin(), edges.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
      for (const auto& [len, h] : edges)
        if (collapse_either(h)) {
          ++done;
          break;
        }
    }
    return done;
  }

 private:
  bool crease(VH v) const {
    const std::uint32_t o = m_.property(origin_, v);
    return o != ~0u && o < crease_.size() && crease_[o];
  }

  FH find_face(const std::array<std::uint32_t, 3>& tri) const {
    const auto it = std::lower_bound(by_origin_.begin(), by_origin_.end(), tri[0],
                                     [](const std::pair<std::uint32_t, VH>& e, std::uint32_t o) { return e.first < o; });
    if (it == by_origin_.end() || it->first != tri[0] || m_.status(it->second).deleted()) return FH();
    for (const FH f : m_.vf_range(it->second)) {
      int hits = 0;
      for (const VH c : m_.fv_range(f)) {
        const std::uint32_t o = m_.property(origin_, c);
        hits += o == tri[0] || o == tri[1] || o == tri[2];
      }
      if (hits == 3) return f;
    }
    return FH();
  }

  // Collapses the edge of h one way or the other: the end that stays is a crease point where
  // one is, and never a locked one that would move.
  bool collapse_either(HH h) {
    const HH o = m_.opposite_halfedge_handle(h);
    HH order[2] = {h, o};
    if (crease(m_.from_vertex_handle(h)) && !crease(m_.to_vertex_handle(h))) std::swap(order[0], order[1]);
    for (const HH x : order) {
      const VH from = m_.from_vertex_handle(x);
      if (m_.property(locked_, from) || (!widely_ && crease(from) && !crease(m_.to_vertex_handle(x)))) continue;
      if (m_.is_boundary(from) || beside_rim(from, m_.to_vertex_handle(x)) || !ht::collapse_ok(m_, x) || !keeps_faces(x))
        continue;
      ht::collapse(m_, x);
      return true;
    }
    return false;
  }

  // OpenMesh's link check sees only the region: a neighbour of `from` on the rim may share an
  // edge with `to` outside it, which the collapse would double. Only `to` may be on the rim.
  bool beside_rim(VH from, VH to) const {
    for (const VH w : m_.vv_range(from))
      if (w != to && m_.property(locked_, w)) return true;
    return false;
  }

  bool keeps_faces(HH x) const {
    const VH from = m_.from_vertex_handle(x), to = m_.to_vertex_handle(x);
    for (const FH f : m_.vf_range(from)) {
      std::array<VH, 3> c;
      int k = 0;
      for (const VH v : m_.fv_range(f)) c[std::size_t(k++)] = v;
      if (c[0] == to || c[1] == to || c[2] == to) continue;
      std::array<glm::dvec3, 3> before, after;
      double longest = 0;
      for (int i = 0; i < 3; ++i) {
        before[std::size_t(i)] = g(m_.point(c[std::size_t(i)]));
        after[std::size_t(i)] = c[std::size_t(i)] == from ? g(m_.point(to)) : before[std::size_t(i)];
      }
      for (int i = 0; i < 3; ++i) longest = std::max(longest, glm::length(after[std::size_t(i)] - after[std::size_t((i + 1) % 3)]));
      const glm::dvec3 nb = face_normal(before[0], before[1], before[2]), na = face_normal(after[0], after[1], after[2]);
      const double la = glm::length(na), lb = glm::length(nb);
      if (!(la > 0) || la * la <= kDegenerate * longest * longest * longest * longest) return false;
      if (lb > 0 && glm::dot(na, nb) < (widely_ ? 0.0 : kTurnCos) * la * lb) return false;
    }
    return true;
  }

 public:
  void index() {
    by_origin_.clear();
    for (const VH v : m_.vertices()) by_origin_.push_back({m_.property(origin_, v), v});
    std::sort(by_origin_.begin(), by_origin_.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
  }

 private:
  TriMesh& m_;
  OpenMesh::VPropHandleT<bool> locked_;
  OpenMesh::VPropHandleT<std::uint32_t> origin_;
  const std::vector<std::uint8_t>& crease_;
  std::vector<std::pair<std::uint32_t, VH>> by_origin_;
  bool widely_ = false;
};

Aabb bounds_of(const TriangleMesh& mesh) {
  Aabb box;
  for (const glm::dvec3& p : mesh.positions) box.grow(p);
  return box;
}

// One round on the triangles of `pairs`: returns the collapses made; `changed` receives the
// vertices of the region that was reworked (numbered after the round).
std::size_t unfold_round(TriangleMesh& mesh, std::vector<std::uint8_t>& crease,
                         const std::vector<std::array<std::uint32_t, 2>>& pairs, bool widely, bool widen,
                         std::vector<std::uint8_t>& changed) {
  std::vector<std::uint8_t> region(mesh.positions.size(), 0);
  std::vector<std::array<std::uint32_t, 3>> bad;
  for (const auto& pair : pairs)
    for (const std::uint32_t t : pair) {
      const glm::uvec3 tri = mesh.triangles[t];
      bad.push_back({tri[0], tri[1], tri[2]});
      for (int k = 0; k < 3; ++k) region[tri[k]] = 1;
    }
  std::sort(bad.begin(), bad.end());
  bad.erase(std::unique(bad.begin(), bad.end()), bad.end());
  if (widen) {  // edges at the corners reach one ring further: their ends must be off the rim
    const std::vector<std::uint8_t> any(region.size(), 1), ring = rings_around(mesh, region, any, 1);
    for (std::size_t v = 0; v < region.size(); ++v) region[v] |= ring[v];
  }
  const Pieces pieces = take_region(mesh, region);
  if (pieces.parts.empty()) return 0;
  const Submesh& part = pieces.parts[0];
  TriMesh m;
  OpenMesh::VPropHandleT<bool> locked;
  OpenMesh::VPropHandleT<std::uint32_t> origin;
  if (!to_openmesh(part.mesh, part.rim, part.origin, m, locked, origin)) return 0;
  Collapser c(m, locked, origin, crease);
  c.index();
  const std::size_t done = c.run(bad, widely);
  if (done == 0) return 0;
  std::vector<TriangleMesh> reworked(1);
  std::vector<std::vector<std::uint32_t>> origins(1);
  from_openmesh(m, origin, reworked[0], origins[0]);
  std::vector<std::uint32_t> renumber;
  put_back(mesh, pieces, reworked, origins, &renumber);
  std::vector<std::uint8_t> kept(mesh.positions.size(), 0);
  changed.assign(mesh.positions.size(), 0);
  for (std::size_t v = 0; v < renumber.size(); ++v) {
    if (renumber[v] == ~0u) continue;
    if (v < crease.size()) kept[renumber[v]] = crease[v];
  }
  for (std::uint32_t o : part.origin)
    if (renumber[o] != ~0u) changed[renumber[o]] = 1;
  if (!crease.empty()) crease = std::move(kept);
  return done;
}

}  // namespace

UnfoldStats unfold(TriangleMesh& mesh, std::vector<std::uint8_t>& crease, std::vector<std::array<std::uint32_t, 2>>& pairs,
                   int rounds) {
  const auto t0 = std::chrono::steady_clock::now();
  UnfoldStats st;
  st.pairs_before = st.pairs_after = pairs.size();
  const double longest = longest_edge(mesh);
  const Aabb everywhere = bounds_of(mesh);
  std::vector<std::uint8_t> changed;
  bool widely = false;
  for (int round = 0; round < rounds && !pairs.empty(); ++round) {
    // A round that leaves more pairs than it found (a collapse folding elsewhere) is undone.
    const TriangleMesh before = mesh;
    const std::vector<std::uint8_t> crease_before = crease;
    const std::size_t done = unfold_round(mesh, crease, pairs, widely, widely, changed);
    ++st.rounds;
    std::vector<std::array<std::uint32_t, 2>> now;
    // Every pair found lies in the reworked region, and only triangles near it changed.
    if (done > 0) now = intersections_near(mesh, changed, longest, everywhere);
    if (done == 0 || now.size() >= pairs.size()) {
      if (done > 0) mesh = before, crease = crease_before;
      if (widely) break;
      widely = true;  // the strict rules are stuck: the next round may reach further
      continue;
    }
    st.collapses += done;
    pairs = std::move(now);
    st.pairs_after = pairs.size();
  }
  st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return st;
}

std::vector<std::uint32_t> folded_triangles(const TriangleMesh& mesh, const BatchGradient& gradient) {
  const auto& P = mesh.positions;
  const std::size_t n = mesh.triangles.size();
  std::vector<glm::dvec3> normal(n), at_vertex(P.size(), glm::dvec3(0.0));
  const tbb::blocked_range<std::size_t> all(0, n, 8192);
  tbb::parallel_for(all, [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t t = r.begin(); t != r.end(); ++t) {
      const glm::uvec3 c = mesh.triangles[t];
      normal[t] = face_normal(P[c[0]], P[c[1]], P[c[2]]);  // twice the area: the corners' weights
    }
  });
  for (std::size_t t = 0; t < n; ++t)  // in order: the sums are the same at any thread count
    for (int k = 0; k < 3; ++k) at_vertex[mesh.triangles[t][k]] += normal[t];
  std::vector<std::uint8_t> against_two(n, 0);
  tbb::parallel_for(all, [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t t = r.begin(); t != r.end(); ++t) {
      const glm::uvec3 c = mesh.triangles[t];
      int against = 0;
      for (int k = 0; k < 3; ++k) against += glm::dot(normal[t], at_vertex[c[k]]) < 0.0;
      against_two[t] = against >= 2;
    }
  });
  std::vector<std::uint32_t> candidates;
  for (std::size_t t = 0; t < n; ++t)
    if (against_two[t]) candidates.push_back(std::uint32_t(t));
  if (candidates.empty()) return candidates;
  // The field at each candidate's centre and corners: four points a candidate.
  std::vector<glm::dvec3> points, grad(4 * candidates.size());
  points.reserve(grad.size());
  for (const std::uint32_t t : candidates) {
    const glm::uvec3 c = mesh.triangles[t];
    points.push_back((P[c[0]] + P[c[1]] + P[c[2]]) / 3.0);
    for (int k = 0; k < 3; ++k) points.push_back(P[c[k]]);
  }
  gradient(points, {}, grad);
  // In the gradient's terms (it points inward): against the centre's, and within
  // kFoldAgreeDegrees of no point's.
  const double agree = std::cos(kFoldAgreeDegrees * std::numbers::pi / 180.0);
  std::vector<std::uint32_t> folded;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const glm::dvec3 u = glm::normalize(normal[candidates[i]]);
    const glm::dvec3* g = grad.data() + 4 * i;
    bool folded_over = glm::dot(u, g[0]) > 0.0;
    for (int k = 0; k < 4 && folded_over; ++k) {
      const double l = glm::length(g[k]);
      folded_over = !(l > 0) || -glm::dot(u, g[k]) < agree * l;
    }
    if (folded_over) folded.push_back(candidates[i]);
  }
  return folded;
}

// Where collapses are stuck: the folded triangles' corners (crease points staying) move toward
// their neighbours' centroid and back onto {f = T}, which turns a triangle pulled over its
// neighbour back where its corners' rings are convex. Kept when fewer triangles are folded after
// (then `folded` receives them), nothing crosses and no triangle around the moved corners is
// left thinner than the thinnest there before; otherwise undone.
bool relax_folded(TriangleMesh& mesh, const std::vector<std::uint8_t>& crease, const BatchGradient& gradient, double T,
                  std::vector<std::uint32_t>& folded, double longest, const Aabb& everywhere) {
  // Beside a crease a vertex's projection may land on the other sheet and round the edge
  // (as untangle knows): only corners a ring or more away from crease points move.
  std::vector<std::uint8_t> beside;
  if (std::find(crease.begin(), crease.end(), std::uint8_t(1)) != crease.end()) {
    std::vector<std::uint8_t> seeds(crease.begin(), crease.end());
    seeds.resize(mesh.positions.size(), 0);
    beside = rings_around(mesh, seeds, std::vector<std::uint8_t>(mesh.positions.size(), 1), 1);
  }
  std::vector<std::uint8_t> movable(mesh.positions.size(), 0);
  for (const std::uint32_t t : folded)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = mesh.triangles[t][k];
      const bool on_crease = v < crease.size() && crease[v], near_crease = v < beside.size() && beside[v];
      if (!on_crease && !near_crease) movable[v] = 1;
    }
  if (std::find(movable.begin(), movable.end(), std::uint8_t(1)) == movable.end()) return false;
  auto thinnest = [&] {  // meshers/triangle_shape.hpp thinness: 1 for a degenerate triangle
    double most = 0.0;
    for (const glm::uvec3& t : mesh.triangles)
      if (movable[t[0]] || movable[t[1]] || movable[t[2]])
        most = std::max(most, thinness(mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]));
    return most;
  };
  const double thinnest_before = thinnest();
  const std::vector<glm::dvec3> before = mesh.positions;
  relax_vertices(mesh, movable, gradient, T);
  if (thinnest() <= thinnest_before && intersections_near(mesh, movable, longest, everywhere).empty()) {
    std::vector<std::uint32_t> now = folded_triangles(mesh, gradient);
    if (now.size() < folded.size()) {
      folded = std::move(now);
      return true;
    }
  }
  mesh.positions = before;
  return false;
}

UnfoldStats unfold_folded(TriangleMesh& mesh, std::vector<std::uint8_t>& crease, const BatchGradient& gradient, double T,
                          bool may_widen, int rounds) {
  const auto t0 = std::chrono::steady_clock::now();
  UnfoldStats st;
  std::vector<std::uint32_t> folded = folded_triangles(mesh, gradient);
  st.pairs_before = st.pairs_after = folded.size();
  if (folded.empty()) return st;
  double longest = longest_edge(mesh);  // grows as collapses join edges: measured again after each
  const Aabb everywhere = bounds_of(mesh);
  std::vector<std::uint8_t> changed;
  bool widely = false;
  for (int round = 0; round < rounds && !folded.empty(); ++round) {
    const TriangleMesh before = mesh;
    const std::vector<std::uint8_t> crease_before = crease;
    std::vector<std::array<std::uint32_t, 2>> bad;
    for (const std::uint32_t t : folded) bad.push_back({t, t});
    const std::size_t done = unfold_round(mesh, crease, bad, widely, true, changed);
    ++st.rounds;
    std::vector<std::uint32_t> now;
    bool crossing = false;
    if (done > 0) {
      crossing = !intersections_near(mesh, changed, longest, everywhere).empty();
      if (!crossing) now = folded_triangles(mesh, gradient);
    }
    if (done == 0 || crossing || now.size() >= folded.size()) {
      if (done > 0) mesh = before, crease = crease_before;
      if (widely || !may_widen) break;
      widely = true;
      continue;
    }
    st.collapses += done;
    folded = std::move(now);
    st.pairs_after = folded.size();
    longest = longest_edge(mesh);
  }
  if (!folded.empty() && relax_folded(mesh, crease, gradient, T, folded, longest, everywhere)) st.pairs_after = folded.size();
  st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return st;
}

}  // namespace ht
