#include "meshers/quality_improver.hpp"

#include "meshers/halfedge_ops.hpp"

#include <algorithm>

namespace ht::quality_detail {

std::size_t Improver::merge_crease_points() {
  if (crease_.empty()) return 0;
  std::size_t done = 0;
  for (const EH e : m_.edges()) {
    if (m_.status(e).deleted() || m_.calc_edge_length(e) >= kMergeFraction * h_) continue;
    const HH h = m_.halfedge_handle(e, 0);
    const VH a = m_.from_vertex_handle(h), b = m_.to_vertex_handle(h);
    if (!on_crease(a) || !on_crease(b) || pinned(a) || pinned(b)) continue;
    for (const HH x : {h, m_.opposite_halfedge_handle(h)}) {
      if (m_.is_boundary(m_.from_vertex_handle(x)) || !ht::collapse_ok(m_, x) || !keeps_faces(x)) continue;
      ht::collapse(m_, x);
      ++done;
      break;
    }
  }
  return done;
}

bool Improver::chain_neighbours(VH v, VH& a, VH& b) const {
  if (!on_crease(v) || m_.is_boundary(v)) return false;
  int n = 0;
  for (const VH w : m_.vv_range(v))
    if (on_crease(w)) {
      if (++n > 2) return false;
      (n == 1 ? a : b) = w;
    }
  if (n != 2 || pinned(v) || pinned(a) || pinned(b)) return false;
  const glm::dvec3 u = p(a) - p(v), w = p(b) - p(v);
  return glm::dot(u, w) < kChainTurnCos * glm::length(u) * glm::length(w);
}

bool Improver::try_move(VH v, const glm::dvec3& to) {
  const glm::dvec3 from = p(v), ref = ring_normal(v);
  double before = -1.0, after = -1.0;
  std::vector<std::array<glm::dvec3, 3>>& faces = faces_;
  faces.clear();
  for (const FH f : m_.vf_range(v)) {
    const auto c = corners(f);
    std::array<glm::dvec3, 3> q{p(c[0]), p(c[1]), p(c[2])}, r = q;
    for (int k = 0; k < 3; ++k)
      if (c[k] == v) r[k] = to;
    const double was = thinness(q[0], q[1], q[2]), is = thinness(r[0], r[1], r[2]);
    if (is > kDegenerateCos) return false;
    // No face turns over: a cap's apex pushed across its long edge would be less thin, and no
    // further off the surface.
    if (glm::dot(unit_normal(r[0], r[1], r[2]), ref) <= 0.0) return false;
    if (was < kNeedleCos && glm::dot(unit_normal(q[0], q[1], q[2]), unit_normal(r[0], r[1], r[2])) < kKeepPlaneCos) return false;
    before = std::max(before, was), after = std::max(after, is);
    faces.push_back(q);
  }
  if (!(after < before)) return false;
  const std::size_t old = faces.size();
  for (std::size_t i = 0; i < old; ++i) {
    std::array<glm::dvec3, 3> r = faces[i];
    for (auto& x : r)
      if (x == from) x = to;
    faces.push_back(r);
  }
  if (!no_further_off(faces, old)) return false;
  // The point itself stays as near the surface as it was, or within kChainOffCells: a chord of
  // a curved crease leaves it.
  const glm::dvec3 at[2] = {from, to}, dir[2] = {ref, ref};
  const std::vector<double>& off = off_.points(at, dir);
  if (!(off[1] <= std::max(off[0], kChainOffCells * h_))) return false;
  m_.set_point(v, om(to));
  return true;
}

std::size_t Improver::even_chains(QualityStats& st) {
  if (crease_.empty()) return 0;
  std::size_t done = 0;
  const std::size_t n = m_.n_vertices();
  for (std::size_t vi = 0; vi < n; ++vi) {
    const VH v{int(vi)};
    VH a, b;
    if (m_.status(v).deleted() || !chain_neighbours(v, a, b)) continue;
    const double la = glm::length(p(a) - p(v)), lb = glm::length(p(b) - p(v));
    if (std::min(la, lb) < kChainMergeCells * h_) {
      const VH into = la < lb ? a : b;
      const HH x = m_.find_halfedge(v, into);
      // A crease point's ring spans both sheets, so its mean normal says nothing of a face's
      // turn: keeps_faces holds each face to its own normal instead.
      if (x.is_valid() && ht::collapse_ok(m_, x) && keeps_faces(x) && after_collapse(x, false, false) <= ring_thinness(v) &&
          surface_kept(x)) {
        ht::collapse(m_, x);
        ++done;
        continue;
      }
    }
    if (std::abs(la - lb) < kChainEven * (la + lb)) continue;
    const glm::dvec3 to = la < lb ? p(v) + 0.5 * (lb - la) / lb * (p(b) - p(v)) : p(v) + 0.5 * (la - lb) / la * (p(a) - p(v));
    if (try_move(v, to)) ++st.moved;
  }
  return done;
}

}  // namespace ht::quality_detail
