#include "meshers/quality.hpp"
#include "meshers/quality_whole.hpp"

#include "meshers/halfedge_ops.hpp"
#include "meshers/off_surface.hpp"
#include "meshers/relax.hpp"
#include "meshers/submesh.hpp"
#include "meshers/triangle_shape.hpp"
#include "nodes/trimesh.hpp"

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <vector>

namespace ht {
namespace {

using VH = TriMesh::VertexHandle;
using FH = TriMesh::FaceHandle;
using EH = TriMesh::EdgeHandle;
using HH = TriMesh::HalfedgeHandle;

// Angles by their cosines (meshers compare thinness(), the cosine of a triangle's smallest angle).
constexpr double kNeedleCos = 0.9396926207859084;   // cos 20 degrees: a thinner triangle may lose its shortest edge
constexpr double kNeedleRatio = 0.5;                // ... when that edge is this short beside the next
constexpr double kCoplanarCos = 0.9063077870366499; // cos 25 degrees: flips only between such faces
constexpr double kTurnCos = 0.5;                    // cos 60 degrees: a face may not turn further
constexpr double kKeepPlaneCos = 0.9396926207859084; // cos 20 degrees: a collapse may not turn a sound face further
constexpr double kSpeck = 1e-3;                     // an edge this many cells long is a speck
constexpr double kMergeFraction = 0.1;              // crease points closer than this many cells become one
constexpr double kDegenerateCos = 0.9999619230641713; // cos 0.5 degrees: no collapse leaves a face this thin
constexpr double kAimCos = 0.8191520442889918;      // cos 35 degrees: faces thinner than this are worked on
constexpr double kShortMove = 0.02;                 // of a cell: a tangential move this short is not made
constexpr double kWorseCos = 0.9659258262890683;    // cos 15 degrees: a relaxation may not leave a face thinner
// Beside a crease, how far off the surface (in cells) a relaxation may leave a vertex or a face's
// middle, and a collapse or flip a face's middle (a looser bound: at 0.02 the slivers there stayed).
constexpr double kOffCells = 0.02;
constexpr double kOffStepCells = 0.05;
constexpr double kCapFlipCos = 0.8660254037844387;  // cos 30 degrees: a cap's flip keeps its sound neighbour's plane

glm::dvec3 g(const TriMesh::Point& p) { return {p[0], p[1], p[2]}; }
TriMesh::Point om(const glm::dvec3& p) { return {p.x, p.y, p.z}; }

class Improver {
 public:
  Improver(const TriangleMesh& in, std::span<const std::uint8_t> locked, std::span<const std::uint8_t> crease,
           const BatchField& field, double T, double h, const QualityOptions& options)
      : crease_(crease), field_(field), T_(T), h_(h), o_(options), off_(field, T, h) {
    if (!to_openmesh(in, locked, {}, m_, locked_, origin_)) return;
    m_.add_property(slope_);
    m_.add_property(near_crease_);
    for (const VH v : m_.vertices()) {
      m_.property(slope_, v) = std::nan("");
      m_.property(near_crease_, v) = !locked.empty() && locked[std::size_t(v.idx())] == kNearCrease;
      if (m_.property(near_crease_, v)) m_.property(locked_, v) = false, creases_near_ = true;
    }
    // An open patch keeps its rim.
    for (const VH v : m_.vertices())
      if (m_.is_boundary(v)) m_.property(locked_, v) = true, m_.property(near_crease_, v) = false;
    ok_ = true;
  }
  bool ok() const { return ok_; }

  void run(QualityStats& st) {
    st.collapses += merge_crease_points();
    for (int it = 0; it < o_.iterations; ++it) {
      st.splits += split();
      st.collapses += remove_valence3();
      st.collapses += collapse();
      st.flips += flip();
      relax(st);
    }
    st.flips += flip();
  }

  // The mesh, compacted, and each vertex's index in the input (~0u for new ones).
  void result(TriangleMesh& out, std::vector<std::uint32_t>& origin) { from_openmesh(m_, origin_, out, origin); }

 private:
  bool locked(VH v) const { return m_.property(locked_, v); }
  // A crease point or within kNearCrease rings of one: faces here may straddle the crease.
  bool beside_crease(VH v) const { return m_.property(near_crease_, v) || on_crease(v); }
  // A collapse or flip beside a crease may not take a face's middle further off the surface than
  // kOffStepCells cells or the faces it replaces were, the larger: a face across the crease cuts
  // its corner off (measured, not guessed from normals). `faces`: the old ones, then the new ones.
  bool no_further_off(std::span<const std::array<glm::dvec3, 3>> faces, std::size_t old) {
    const std::vector<double>& off = off_.faces(faces);
    double was = kOffStepCells * h_, is = 0;
    for (std::size_t i = 0; i < off.size(); ++i) (i < old ? was : is) = std::max(i < old ? was : is, off[i]);
    return is <= was;
  }
  // Beside a crease: a crease point or kNearCrease vertex among `v` and its neighbours.
  bool near_a_crease(VH v) const {
    if (beside_crease(v)) return true;
    for (const VH w : m_.vv_range(v))
      if (beside_crease(w)) return true;
    return false;
  }
  bool frozen(EH e) const {
    const HH h = m_.halfedge_handle(e, 0);
    return locked(m_.from_vertex_handle(h)) && locked(m_.to_vertex_handle(h));
  }
  glm::dvec3 p(VH v) const { return g(m_.point(v)); }
  glm::dvec3 ring_normal(VH v) const {
    glm::dvec3 n(0.0);
    for (const FH f : m_.vf_range(v)) {
      const auto c = corners(f);
      n += glm::cross(p(c[1]) - p(c[0]), p(c[2]) - p(c[0]));
    }
    const double l = glm::length(n);
    return l > 0 ? n / l : n;
  }
  double ring_thinness(VH v) const {
    double worst = -1.0;
    for (const FH f : m_.vf_range(v)) {
      const auto c = corners(f);
      worst = std::max(worst, thinness(p(c[0]), p(c[1]), p(c[2])));
    }
    return worst;
  }
  // Next to a locked vertex (a crease, a rim): the ring may span two sheets, so the vertex
  // neither moves nor goes away; only flips between coplanar faces reach it.
  bool near_locked(VH v) const {
    for (const VH w : m_.vv_range(v))
      if (locked(w)) return true;
    return false;
  }
  std::array<VH, 3> corners(FH f) const {
    const HH h = m_.halfedge_handle(f);
    return {m_.from_vertex_handle(h), m_.to_vertex_handle(h), m_.to_vertex_handle(m_.next_halfedge_handle(h))};
  }

  std::size_t split() {
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

  // The thinness of the thinnest face around `from` that survives its collapse into `to`, with
  // `from` at `to`'s place; 2 when one of them would turn over. A needle's own normal means
  // nothing, so faces are held to the ring's area-weighted normal, which the well-shaped faces
  // dominate; with `tiny` (the edge is a speck: vertices a thousandth of a cell apart, around a
  // grid point the surface passes through) needles are not held to it at all.
  double after_collapse(HH h, bool tiny) const {
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
      if (glm::dot(ref, n) < kTurnCos && !(tiny && thin > kNeedleCos)) return 2.0;
      // A face with a shape of its own keeps its plane: beside a crease, a face may not swing
      // over to the other sheet.
      if (was < kNeedleCos && glm::dot(unit_normal(a, b, d), n) < kKeepPlaneCos) return 2.0;
      worst = std::max(worst, thin);
    }
    return worst;
  }

  // Collapsing h beside a crease takes no face's middle further off the surface.
  bool surface_kept(HH h) {
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

  // Crease points almost together (the crease passing near where several edges' crease points
  // meet) leave slivers turned any way between them, which fold into their neighbours: each such
  // pair becomes one point of the crease.
  std::size_t merge_crease_points() {
    if (crease_.empty()) return 0;
    std::size_t done = 0;
    for (const EH e : m_.edges()) {
      if (m_.status(e).deleted() || m_.calc_edge_length(e) >= kMergeFraction * h_) continue;
      const HH h = m_.halfedge_handle(e, 0);
      const VH a = m_.from_vertex_handle(h), b = m_.to_vertex_handle(h);
      if (!on_crease(a) || !on_crease(b)) continue;
      for (const HH x : {h, m_.opposite_halfedge_handle(h)}) {
        if (m_.is_boundary(m_.from_vertex_handle(x)) || !ht::collapse_ok(m_, x) || !keeps_faces(x)) continue;
        ht::collapse(m_, x);
        ++done;
        break;
      }
    }
    return done;
  }

  bool on_crease(VH v) const {
    const std::uint32_t o = m_.property(origin_, v);
    return o != ~0u && !crease_.empty() && crease_[o];
  }

  // Collapsing x turns no face around its start by more than 60 degrees and leaves none degenerate.
  bool keeps_faces(HH x) const {
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

  std::size_t collapse() {
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
        // a crease point (near_locked). Any collapse beside a crease is measured after the
        // shapes (surface_kept).
        const bool may_go = (!locked(from) && !near_locked(from)) || (short_edge && m_.property(near_crease_, from));
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

  // A vertex of valence 3 at the corner of a needle or a cap (one that sits almost on an edge of
  // its neighbours' triangle) or of a speck (speck_corner) keeps its neighbours' needles from
  // collapsing: each of their short edges has it as a third common neighbour, which OpenMesh's
  // link check refuses. Removing it leaves its three neighbours' triangle, whichever edge
  // collapses; that triangle must face the way the ring did and not be a needle. Not beside a
  // locked vertex: there the ring may span two sheets (a crease), as for collapses.
  std::size_t remove_valence3() {
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

  // A corner of a speck: a vertex nearer than kShortNeedleEdge cells to one of its neighbours
  // (marching tetrahedra's vertices around a grid point the surface passes near, a few
  // hundredths of a cell apart). Its own triangles may be sound while it keeps its neighbours'
  // needles from collapsing.
  bool speck_corner(VH v) const {
    for (const VH w : m_.vv_range(v))
      if (glm::length(p(w) - p(v)) < kShortNeedleEdge * h_) return true;
    return false;
  }

  // Flips `e` when that makes its two triangles' thinner one less thin (max-min angle).
  bool try_flip(EH e) {
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

  // A cap (a corner almost on its long edge ab, here c or d) tilts its own normal any way, so the
  // pair's planes say nothing of a bend there: its flip is held instead to the well-shaped face,
  // both new faces within kCapFlipCos of it (as the remesher's caps are, meshers/remesh.cpp).
  static bool cap_flip(const glm::dvec3& pa, const glm::dvec3& pb, const glm::dvec3& pc, const glm::dvec3& pd) {
    const double t1 = thinness(pa, pb, pc), t2 = thinness(pb, pa, pd);
    if (std::max(t1, t2) <= kNeedleCos || std::min(t1, t2) > kNeedleCos) return false;
    const glm::dvec3 sound = t1 < t2 ? unit_normal(pa, pb, pc) : unit_normal(pb, pa, pd);
    return glm::dot(unit_normal(pa, pd, pc), sound) >= kCapFlipCos && glm::dot(unit_normal(pd, pb, pc), sound) >= kCapFlipCos;
  }

  // Flips from a queue seeded with the edges of the thin faces; a flip queues the four edges
  // around it. Each flip raises the smallest angle of its pair, so the queue empties.
  std::size_t flip() {
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

  // Faces whose smallest angle is under the pass's aim (computed in parallel).
  std::vector<std::uint8_t> thin_faces() const {
    std::vector<std::uint8_t> thin(m_.n_faces(), 0);
    tbb::parallel_for(std::size_t(0), thin.size(), [&](std::size_t fi) {
      const FH f{int(fi)};
      if (m_.status(f).deleted()) return;
      const auto c = corners(f);
      thin[fi] = thinness(p(c[0]), p(c[1]), p(c[2])) > kAimCos;
    });
    return thin;
  }

  // A vertex whose Newton step was long (kOffCells cells or more: near a crease, the field's
  // kink) goes back when it ended off the surface, more than kOffCells cells by |f - T| over the
  // slope along its normal; a short step lands within about the curvature times its square.
  void stay_on_surface(const std::vector<std::uint32_t>& movers, const std::vector<glm::dvec3>& dirs,
                       const std::vector<glm::dvec3>& tangential, const std::vector<glm::dvec3>& old,
                       std::vector<glm::dvec3>& now) {
    if (!creases_near_) return;  // a field without creases has no kink to stop at
    std::vector<std::uint32_t> check;
    std::vector<glm::dvec3> at, dir;
    for (std::size_t i = 0; i < movers.size(); ++i)
      if (now[movers[i]] != old[movers[i]] && glm::length(now[movers[i]] - tangential[i]) >= kOffCells * h_) {
        check.push_back(std::uint32_t(i));
        at.push_back(now[movers[i]]);
        dir.push_back(dirs[i]);
      }
    const std::vector<double>& off = off_.points(at, dir);
    for (std::size_t k = 0; k < check.size(); ++k)
      if (!(off[k] <= kOffCells * h_)) now[movers[check[k]]] = old[movers[check[k]]];
  }

  // One Jacobi step of tangential relaxation with projection, then the moves that hurt undone.
  void relax(QualityStats& st) {
    // Only the corners of thin faces move: the rest is as good as relaxation makes it. The work
    // is on them, their rings (whose normals judge the moves) and the faces around them.
    // Per vertex: 1 when locked or next to a locked vertex (near_locked, found from the few
    // locked vertices' rings rather than every candidate's), 2 when it moves.
    std::vector<std::uint8_t> wanted(m_.n_vertices(), 0);
    for (const VH v : m_.vertices())
      if (locked(v)) {
        wanted[std::size_t(v.idx())] = 1;
        for (const VH w : m_.vv_range(v)) wanted[std::size_t(w.idx())] = 1;
      }
    const std::vector<std::uint8_t> thin = thin_faces();
    for (std::size_t f = 0; f < thin.size(); ++f)
      if (thin[f])
        for (const VH v : corners(FH{int(f)}))
          if (!wanted[std::size_t(v.idx())]) wanted[std::size_t(v.idx())] = 2;
    std::vector<std::uint32_t> who;  // ascending
    for (std::uint32_t v = 0; v < wanted.size(); ++v)
      if (wanted[v] == 2) who.push_back(v);
    std::vector<std::uint32_t> faces, ring;
    std::vector<std::uint8_t> face_seen(m_.n_faces(), 0), ring_seen(m_.n_vertices(), 0);
    for (const std::uint32_t v : who)
      for (const FH f : m_.vf_range(VH(int(v))))
        if (!face_seen[std::size_t(f.idx())]) {
          face_seen[std::size_t(f.idx())] = 1;
          faces.push_back(std::uint32_t(f.idx()));
          for (const VH c : corners(f))
            if (!ring_seen[std::size_t(c.idx())]) ring_seen[std::size_t(c.idx())] = 1, ring.push_back(std::uint32_t(c.idx()));
        }
    std::sort(faces.begin(), faces.end());
    // Ring normals (area-weighted) of every vertex the checks read; centroids of the movers.
    std::vector<glm::dvec3> normal(m_.n_vertices(), glm::dvec3(0.0)), moved(who.size()), dirs(who.size());
    std::vector<std::uint8_t> moves(who.size(), 0);
    auto ring_of = [&](VH v, glm::dvec3& centroid) {
      glm::dvec3 c(0.0), n(0.0);
      double area = 0;
      for (const FH f : m_.vf_range(v)) {
        const auto k = corners(f);
        const glm::dvec3 a = p(k[0]), b = p(k[1]), d = p(k[2]);
        const glm::dvec3 cr = glm::cross(b - a, d - a);
        const double w = glm::length(cr);
        c += w * (a + b + d) / 3.0;
        n += cr;
        area += w;
      }
      const double nl = glm::length(n);
      if (!(area > 0) || !(nl > 0)) return false;
      normal[std::size_t(v.idx())] = n / nl;
      centroid = c / area;
      return true;
    };
    // The movers' own rings are done below, with their centroids.
    tbb::parallel_for(std::size_t(0), ring.size(), [&](std::size_t i) {
      glm::dvec3 unused;
      if (wanted[ring[i]] != 2) ring_of(VH(int(ring[i])), unused);
    });
    tbb::parallel_for(std::size_t(0), who.size(), [&](std::size_t i) {
      const VH v(static_cast<int>(who[i]));  // not VH v(int(x)): clang reads that as a function
      glm::dvec3 c;
      if (!ring_of(v, c)) return;
      const glm::dvec3 n = normal[who[i]], at = p(v);
      glm::dvec3 d = c - at;
      d -= glm::dot(d, n) * n;
      // A move this short changes no angle that matters and is not worth a field evaluation.
      if (glm::dot(d, d) < kShortMove * kShortMove * h_ * h_) return;
      moved[i] = at + d;
      dirs[i] = n;
      moves[i] = 1;
    });
    std::vector<std::uint32_t> movers;
    std::vector<glm::dvec3> targets, normals_of;
    for (std::size_t i = 0; i < who.size(); ++i)
      if (moves[i]) movers.push_back(who[i]), targets.push_back(moved[i]), normals_of.push_back(dirs[i]);
    std::vector<double> slopes(movers.size());
    for (std::size_t i = 0; i < movers.size(); ++i) slopes[i] = m_.property(slope_, VH{int(movers[i])});
    const std::vector<glm::dvec3> tangential = creases_near_ ? targets : std::vector<glm::dvec3>();
    off_.project(targets, normals_of, slopes, o_.newton_steps);
    for (std::size_t i = 0; i < movers.size(); ++i) m_.property(slope_, VH{int(movers[i])}) = slopes[i];
    // Positions before and after, indexed like the mesh's vertices but filled only where read.
    std::vector<glm::dvec3> old(m_.n_vertices()), now(m_.n_vertices());
    for (const std::uint32_t v : ring) old[v] = now[v] = p(VH(int(v)));
    for (std::size_t i = 0; i < movers.size(); ++i)
      if (!std::isnan(targets[i].x)) now[movers[i]] = targets[i];
    stay_on_surface(movers, normals_of, tangential, old, now);
    // Beside a crease, faces a move takes further off the surface than kOffCells or than they
    // were are marked: their moves are undone below with the others'.
    std::vector<std::uint8_t> too_far(creases_near_ ? m_.n_faces() : 0, 0);
    if (creases_near_) {
      std::vector<std::uint32_t> near;  // faces with a corner beside a crease and one that moved
      std::vector<std::array<glm::dvec3, 3>>& both = faces_;
      both.clear();
      for (const std::uint32_t f : faces) {
        const auto k = corners(FH(int(f)));
        bool beside = false, moved_one = false;
        for (const VH v : k) {
          beside |= beside_crease(v);
          moved_one |= now[std::size_t(v.idx())] != old[std::size_t(v.idx())];
        }
        if (!beside || !moved_one) continue;
        near.push_back(f);
        both.push_back({old[std::size_t(k[0].idx())], old[std::size_t(k[1].idx())], old[std::size_t(k[2].idx())]});
      }
      for (const std::uint32_t f : near) {
        const auto k = corners(FH(int(f)));
        both.push_back({now[std::size_t(k[0].idx())], now[std::size_t(k[1].idx())], now[std::size_t(k[2].idx())]});
      }
      const std::vector<double>& off = off_.faces(both);
      for (std::size_t i = 0; i < near.size(); ++i)
        too_far[near[i]] = off[near.size() + i] > std::max(off[i], kOffCells * h_);
    }
    // Undo the moves of every face that turned or got much thinner, until none does. After the
    // first round only the faces around a vertex just put back can have turned bad: the others
    // are as they were checked.
    auto turns_bad = [&](std::uint32_t f) {
      if (!too_far.empty() && too_far[f]) return true;
      const auto k = corners(FH(int(f)));
      const std::size_t i0 = std::size_t(k[0].idx()), i1 = std::size_t(k[1].idx()), i2 = std::size_t(k[2].idx());
      if (now[i0] == old[i0] && now[i1] == old[i1] && now[i2] == old[i2]) return false;
      // Held to its corners' ring normals: a sliver's own normal means nothing.
      const glm::dvec3 ref = normal[i0] + normal[i1] + normal[i2], after = unit_normal(now[i0], now[i1], now[i2]);
      const double t0 = thinness(old[i0], old[i1], old[i2]), t1 = thinness(now[i0], now[i1], now[i2]);
      // Beside a crease a face stays on its sheet: a mover's faces keep to its ring's plane.
      for (const VH v : k)
        if (m_.property(near_crease_, v) && now[std::size_t(v.idx())] != old[std::size_t(v.idx())] &&
            glm::dot(normal[std::size_t(v.idx())], after) < kKeepPlaneCos)
          return true;
      return glm::dot(ref, after) < kTurnCos * glm::length(ref) || (t1 > t0 && t1 > kWorseCos) || t1 > kDegenerateCos;
    };
    std::vector<std::uint32_t> check = faces, undone;
    std::vector<std::uint8_t> bad, queued(m_.n_faces(), 0);
    for (int round = 0; round < 16 && !check.empty(); ++round) {
      bad.assign(check.size(), 0);
      tbb::parallel_for(std::size_t(0), check.size(), [&](std::size_t fi) { bad[fi] = turns_bad(check[fi]); });
      undone.clear();
      for (std::size_t fi = 0; fi < check.size(); ++fi)
        if (bad[fi])
          for (const VH v : corners(FH(int(check[fi])))) {
            const std::size_t i = std::size_t(v.idx());
            if (now[i] != old[i]) now[i] = old[i], undone.push_back(std::uint32_t(i));
          }
      st.reverted += undone.size();
      check.clear();
      for (const std::uint32_t v : undone)
        for (const FH f : m_.vf_range(VH(int(v))))
          if (!queued[std::size_t(f.idx())]) queued[std::size_t(f.idx())] = 1, check.push_back(std::uint32_t(f.idx()));
      for (const std::uint32_t f : check) queued[f] = 0;
    }
    for (const std::uint32_t v : movers)
      if (now[v] != old[v]) m_.set_point(VH(int(v)), om(now[v])), ++st.moved;
  }


  TriMesh m_;
  std::span<const std::uint8_t> crease_;  // by input vertex: on a crease line
  OpenMesh::VPropHandleT<bool> locked_;
  OpenMesh::VPropHandleT<std::uint32_t> origin_;
  OpenMesh::VPropHandleT<double> slope_;  // f's derivative along the vertex normal, NaN until known
  OpenMesh::VPropHandleT<bool> near_crease_;  // kNearCrease: not locked, but its steps are checked (beside_crease)
  bool creases_near_ = false;                // some vertex is kNearCrease
  std::vector<std::array<glm::dvec3, 3>> faces_;  // surface_kept's and relax's scratch
  const BatchField& field_;
  double T_, h_;
  QualityOptions o_;
  OffSurface off_;
  bool ok_ = false;
};

}  // namespace

void improve_whole(TriangleMesh& mesh, std::span<const std::uint8_t> locked, std::span<const std::uint8_t> crease,
                   const BatchField& field, double T, double h, const QualityOptions& options, QualityStats& st,
                   std::vector<std::uint32_t>& origin) {
  Improver im(mesh, locked, crease, field, T, h, options);
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
