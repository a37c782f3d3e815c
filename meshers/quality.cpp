#include "meshers/quality_whole.hpp"
#include "meshers/quality_improver.hpp"

#include "meshers/halfedge_ops.hpp"

#include <algorithm>
#include <limits>

namespace ht::quality_detail {

void Improver::run(QualityStats& st) {
  st.collapses += merge_crease_points();
  for (int it = 0; it < o_.iterations; ++it) {
    st.collapses += even_chains(st);
    st.splits += split();
    st.collapses += remove_valence3();
    st.collapses += collapse();
    st.flips += flip();
    relax(st);
  }
  st.flips += flip();
}

bool Improver::no_further_off(std::span<const std::array<glm::dvec3, 3>> faces, std::size_t old) {
  const std::vector<double>& off = off_.faces(faces);
  double was = o_.off_step_cells * h_, is = 0;
  for (std::size_t i = 0; i < off.size(); ++i) (i < old ? was : is) = std::max(i < old ? was : is, off[i]);
  return is <= was;
}

std::size_t Improver::split() {
  std::vector<EH> todo;
  std::vector<glm::dvec3> mids, dirs;
  for (const EH e : m_.edges()) {
    if (frozen(e) || m_.calc_edge_length(e) <= 2.0 * h_) continue;
    // Beside a crease a midpoint's Newton step may stop at the field's kink, off the surface.
    if (beside_crease(m_.from_vertex_handle(m_.halfedge_handle(e, 0))) || beside_crease(m_.to_vertex_handle(m_.halfedge_handle(e, 0))))
      continue;
    todo.push_back(e);
    mids.push_back(g(m_.calc_edge_midpoint(e)));
    glm::dvec3 n(0.0);
    for (int side = 0; side < 2; ++side) {
      const FH f = m_.face_handle(m_.halfedge_handle(e, side));
      if (f.is_valid()) n += g(m_.calc_face_normal(f));
    }
    dirs.push_back(glm::length(n) > 0 ? glm::normalize(n) : glm::dvec3(0.0));
  }
  std::vector<double> slopes(todo.size(), std::nan(""));
  off_.project(mids, dirs, slopes, o_.newton_steps);
  std::size_t done = 0;
  for (std::size_t i = 0; i < todo.size(); ++i) {
    if (std::isnan(mids[i].x)) continue;  // the midpoint found no surface near it
    const VH v = m_.add_vertex(om(mids[i]));
    m_.property(locked_, v) = false;
    m_.property(near_crease_, v) = false;
    m_.property(origin_, v) = ~0u;
    m_.property(slope_, v) = slopes[i];
    m_.split_edge(todo[i], v);
    ++done;
  }
  return done;
}

double Improver::after_collapse(HH h, bool tiny, bool to_ring) const {
  const VH from = m_.from_vertex_handle(h), to = m_.to_vertex_handle(h);
  const glm::dvec3 target = p(to), ref = ring_normal(from);
  double worst = -1.0;
  for (const FH f : m_.vf_range(from)) {
    auto c = corners(f);
    if (c[0] == to || c[1] == to || c[2] == to) continue;
    glm::dvec3 q[3];
    for (int k = 0; k < 3; ++k) q[k] = c[k] == from ? target : p(c[k]);
    const glm::dvec3 n = unit_normal(q[0], q[1], q[2]);
    const glm::dvec3 a = p(c[0]), b = p(c[1]), d = p(c[2]);
    const double thin = thinness(q[0], q[1], q[2]), was = thinness(a, b, d);
    // No face gets degenerate (unless it was as thin already: a cluster's needles).
    if (thin > kDegenerateCos && thin > was) return 2.0;
    if (to_ring && glm::dot(ref, n) < kTurnCos && !(tiny && thin > kNeedleCos)) return 2.0;
    // A face with a shape of its own keeps its plane: beside a crease, a face may not swing
    // over to the other sheet.
    if (was < kNeedleCos && glm::dot(unit_normal(a, b, d), n) < kKeepPlaneCos) return 2.0;
    worst = std::max(worst, thin);
  }
  return worst;
}

bool Improver::surface_kept(HH h) {
  const VH from = m_.from_vertex_handle(h), to = m_.to_vertex_handle(h);
  std::vector<std::array<glm::dvec3, 3>>& faces = faces_;
  faces.clear();
  for (const FH f : m_.vf_range(from)) {
    const auto c = corners(f);
    faces.push_back({p(c[0]), p(c[1]), p(c[2])});
  }
  const std::size_t old = faces.size();
  for (const FH f : m_.vf_range(from)) {
    const auto c = corners(f);
    if (c[0] == to || c[1] == to || c[2] == to) continue;
    faces.push_back({c[0] == from ? p(to) : p(c[0]), c[1] == from ? p(to) : p(c[1]), c[2] == from ? p(to) : p(c[2])});
  }
  return no_further_off(faces, old);
}

bool Improver::keeps_faces(HH x) const {
  const VH from = m_.from_vertex_handle(x), to = m_.to_vertex_handle(x);
  for (const FH f : m_.vf_range(from)) {
    auto c = corners(f);
    if (c[0] == to || c[1] == to || c[2] == to) continue;
    glm::dvec3 q[3];
    for (int k = 0; k < 3; ++k) q[k] = c[k] == from ? p(to) : p(c[k]);
    if (thinness(q[0], q[1], q[2]) > kDegenerateCos) return false;
    if (glm::dot(unit_normal(p(c[0]), p(c[1]), p(c[2])), unit_normal(q[0], q[1], q[2])) < kTurnCos) return false;
  }
  return true;
}

std::size_t Improver::collapse() {
  std::size_t done = 0;
  const std::size_t faces = m_.n_faces();
  for (std::size_t fi = 0; fi < faces; ++fi) {
    const FH f{int(fi)};
    if (m_.status(f).deleted()) continue;
    const auto c = corners(f);
    const double thin = thinness(p(c[0]), p(c[1]), p(c[2]));
    if (thin <= kNeedleCos) continue;
    HH shortest;
    double len[3] = {0, 0, 0};
    int k = 0, at = 0;
    for (const HH h : m_.fh_range(f)) {
      len[k] = m_.calc_edge_length(h);
      if (len[k] < len[at]) at = k;
      if (k == at) shortest = h;
      ++k;
    }
    const double next = std::min(len[(at + 1) % 3], len[(at + 2) % 3]);
    if (len[at] >= kNeedleRatio * next) continue;  // a cap, not a needle: flips mend it
    // The collapse may not leave the ring worse than it is (a cluster of needles around one
    // grid point goes one vertex at a time, each step leaving the others as thin as before).
    HH best;
    double best_thin = 2.0;
    const bool short_edge = len[at] < kShortNeedleEdge * h_;
    for (const HH h : {shortest, m_.opposite_halfedge_handle(shortest)}) {
      const VH from = m_.from_vertex_handle(h);
      // An edge this short moves nothing that matters: a kNearCrease vertex may go even beside
      // a vertex that holds its neighbours (near_rim). Any collapse beside a crease is measured
      // after the shapes (surface_kept).
      const bool may_go = (!locked(from) && !near_rim(from)) || (short_edge && m_.property(near_crease_, from));
      if (!may_go) continue;
      // The shapes first: on the snake they turn down 60% of the candidates, the link check
      // 2%.
      const double a = after_collapse(h, len[at] < kSpeck * h_);
      if (a < best_thin && a <= ring_thinness(from) && ht::collapse_ok(m_, h)) best_thin = a, best = h;
    }
    if (!best.is_valid() || (near_a_crease(m_.from_vertex_handle(best)) && !surface_kept(best))) continue;
    ht::collapse(m_, best);
    ++done;
  }
  return done;
}

std::size_t Improver::remove_valence3() {
  std::size_t done = 0;
  const std::size_t n = m_.n_vertices();
  for (std::size_t vi = 0; vi < n; ++vi) {
    const VH v{int(vi)};
    if (m_.status(v).deleted() || locked(v) || m_.is_boundary(v) || ht::valence(m_, v) != 3 || near_locked(v)) continue;
    if (!(ring_thinness(v) > kNeedleCos) && !speck_corner(v)) continue;
    // Collapsing v into `to` turns v's face without `to` into the triangle that stays.
    const HH h = m_.halfedge_handle(v);
    const VH to = m_.to_vertex_handle(h);
    std::array<glm::dvec3, 3> q{};
    for (const FH f : m_.vf_range(v)) {
      const auto c = corners(f);
      if (c[0] == to || c[1] == to || c[2] == to) continue;
      for (int k = 0; k < 3; ++k) q[std::size_t(k)] = p(c[std::size_t(k)] == v ? to : c[std::size_t(k)]);
    }
    if (thinness(q[0], q[1], q[2]) > kNeedleCos || glm::dot(unit_normal(q[0], q[1], q[2]), ring_normal(v)) < kTurnCos)
      continue;
    if (!ht::collapse_ok(m_, h) || (near_a_crease(v) && !surface_kept(h))) continue;
    ht::collapse(m_, h);
    ++done;
  }
  return done;
}

bool Improver::speck_corner(VH v) const {
  for (const VH w : m_.vv_range(v))
    if (glm::length(p(w) - p(v)) < kShortNeedleEdge * h_) return true;
  return false;
}

bool Improver::try_flip(EH e) {
  if (m_.status(e).deleted() || m_.is_boundary(e)) return false;
  const HH h = m_.halfedge_handle(e, 0), o = m_.opposite_halfedge_handle(h);
  const VH a = m_.from_vertex_handle(h), b = m_.to_vertex_handle(h);
  if (locked(a) && locked(b)) return false;  // a crease edge (or a rim's) keeps its place
  const VH c = m_.to_vertex_handle(m_.next_halfedge_handle(h)), d = m_.to_vertex_handle(m_.next_halfedge_handle(o));
  const glm::dvec3 pa = p(a), pb = p(b), pc = p(c), pd = p(d);
  const double before = std::max(thinness(pa, pb, pc), thinness(pb, pa, pd));
  const double after = std::max(thinness(pa, pd, pc), thinness(pd, pb, pc));
  if (after >= before - 1e-12 || after > kDegenerateCos) return false;
  const glm::dvec3 n1 = unit_normal(pa, pb, pc), n2 = unit_normal(pb, pa, pd);
  if (glm::dot(n1, n2) < kCoplanarCos && !cap_flip(pa, pb, pc, pd)) return false;  // a crease or a tight bend keeps its edge
  const glm::dvec3 up = n1 + n2;
  if (glm::dot(unit_normal(pa, pd, pc), up) <= 0 || glm::dot(unit_normal(pd, pb, pc), up) <= 0) return false;
  if (!ht::flip_ok(m_, e)) return false;
  // Last, as it asks the field: beside a crease the pair may straddle it.
  if (beside_crease(a) || beside_crease(b) || beside_crease(c) || beside_crease(d)) {
    const std::array<glm::dvec3, 3> faces[4] = {{pa, pb, pc}, {pb, pa, pd}, {pa, pd, pc}, {pd, pb, pc}};
    if (!no_further_off(faces, 2)) return false;
  }
  ht::flip(m_, e);
  return true;
}

bool Improver::cap_flip(const glm::dvec3& pa, const glm::dvec3& pb, const glm::dvec3& pc, const glm::dvec3& pd) {
  const double t1 = thinness(pa, pb, pc), t2 = thinness(pb, pa, pd);
  if (std::max(t1, t2) <= kNeedleCos || std::min(t1, t2) > kNeedleCos) return false;
  const glm::dvec3 sound = t1 < t2 ? unit_normal(pa, pb, pc) : unit_normal(pb, pa, pd);
  return glm::dot(unit_normal(pa, pd, pc), sound) >= kCapFlipCos && glm::dot(unit_normal(pd, pb, pc), sound) >= kCapFlipCos;
}

std::size_t Improver::flip() {
  std::vector<std::uint8_t> thin = thin_faces();
  std::vector<std::uint8_t> queued(m_.n_edges(), 0);
  std::vector<EH> queue;
  for (std::size_t f = 0; f < thin.size(); ++f)
    if (thin[f])
      for (const EH e : m_.fe_range(FH{int(f)}))
        if (!queued[std::size_t(e.idx())]) queued[std::size_t(e.idx())] = 1, queue.push_back(e);
  std::size_t done = 0;
  for (std::size_t at = 0; at < queue.size() && at < 16 * queued.size(); ++at) {
    const EH e = queue[at];
    queued[std::size_t(e.idx())] = 0;
    if (!try_flip(e)) continue;
    ++done;
    const HH h = m_.halfedge_handle(e, 0), o = m_.opposite_halfedge_handle(h);
    for (const HH x : {m_.next_halfedge_handle(h), m_.prev_halfedge_handle(h), m_.next_halfedge_handle(o),
                       m_.prev_halfedge_handle(o)}) {
      const EH n = m_.edge_handle(x);
      if (!queued[std::size_t(n.idx())]) queued[std::size_t(n.idx())] = 1, queue.push_back(n);
    }
  }
  return done;
}

}  // namespace ht::quality_detail

namespace ht {

void improve_whole(TriangleMesh& mesh, std::span<const std::uint8_t> locked, std::span<const std::uint8_t> crease,
                   const BatchField& field, double T, double h, const QualityOptions& options, QualityStats& st,
                   std::vector<std::uint32_t>& origin) {
  quality_detail::Improver im(mesh, locked, crease, field, T, h, options);
  if (!im.ok()) {
    st.skipped = true;
    origin.resize(mesh.positions.size());
    for (std::size_t v = 0; v < origin.size(); ++v) origin[v] = std::uint32_t(v);
    return;
  }
  im.run(st);
  im.result(mesh, origin);
}

}  // namespace ht
