// The quality pass's improver (meshers/quality.hpp): one slab or band of a mesh in OpenMesh, its
// steps and their thresholds. Internal to the pass; its steps live in three rooms:
// meshers/quality.cpp (rounds, collapses, flips, splits), meshers/quality_relax.cpp (tangential
// relaxation with projection) and meshers/quality_creases.cpp (crease points: merging and
// evening their chains). Not thread-safe: one improver per piece, pieces in parallel.
#pragma once

#include "meshers/batch_field.hpp"
#include "meshers/off_surface.hpp"
#include "meshers/quality.hpp"
#include "meshers/submesh.hpp"
#include "meshers/triangle_mesh.hpp"
#include "meshers/triangle_shape.hpp"
#include "nodes/trimesh.hpp"

#include <glm/geometric.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

namespace ht::quality_detail {

using VH = TriMesh::VertexHandle;
using FH = TriMesh::FaceHandle;
using EH = TriMesh::EdgeHandle;
using HH = TriMesh::HalfedgeHandle;

// Angles by their cosines (meshers compare thinness(), the cosine of a triangle's smallest angle).
inline constexpr double kNeedleCos = 0.9396926207859084;   // cos 20 degrees: a thinner triangle may lose its shortest edge
inline constexpr double kNeedleRatio = 0.5;                // ... when that edge is this short beside the next
inline constexpr double kCoplanarCos = 0.9063077870366499; // cos 25 degrees: flips only between such faces
inline constexpr double kTurnCos = 0.5;                    // cos 60 degrees: a face may not turn further
inline constexpr double kKeepPlaneCos = 0.9396926207859084; // cos 20 degrees: a collapse may not turn a sound face further
inline constexpr double kSpeck = 1e-3;                     // an edge this many cells long is a speck
inline constexpr double kMergeFraction = 0.1;              // crease points closer than this many cells become one
inline constexpr double kDegenerateCos = 0.9999619230641713; // cos 0.5 degrees: no collapse leaves a face this thin
inline constexpr double kAimCos = 0.8191520442889918;      // cos 35 degrees: faces thinner than this are worked on
inline constexpr double kShortMove = 0.02;                 // of a cell: a tangential move this short is not made
inline constexpr double kWorseCos = 0.9659258262890683;    // cos 15 degrees: a relaxation may not leave a face thinner
// Beside a crease, how far off the surface (in cells) a relaxation may leave a vertex or a face's
// middle (a collapse's or flip's bound is QualityOptions::off_step_cells).
inline constexpr double kOffCells = 0.02;
inline constexpr double kCapFlipCos = 0.8660254037844387;  // cos 30 degrees: a cap's flip keeps its sound neighbour's plane
// Crease chains (meshers/quality_creases.cpp): a crease point whose two crease neighbours make
// an angle over 120 degrees at it is on a chain; one nearer a neighbour than kChainMergeCells
// cells goes into it; one whose two sides differ by more than kChainEven of their sum slides
// toward their middle, ending at most kChainOffCells cells off the surface (or as far as it was).
inline constexpr double kChainTurnCos = -0.5;
inline constexpr double kChainMergeCells = 0.35;
inline constexpr double kChainEven = 0.2;
inline constexpr double kChainOffCells = 0.005;

inline glm::dvec3 g(const TriMesh::Point& p) { return {p[0], p[1], p[2]}; }
inline TriMesh::Point om(const glm::dvec3& p) { return {p.x, p.y, p.z}; }

class Improver {
 public:
  Improver(const TriangleMesh& in, std::span<const std::uint8_t> locked, std::span<const std::uint8_t> crease,
           const BatchField& field, double T, double h, const QualityOptions& options)
      : crease_(crease), field_(field), T_(T), h_(h), o_(options), off_(field, T, h) {
    if (!to_openmesh(in, locked, {}, m_, locked_, origin_)) return;
    m_.add_property(slope_);
    m_.add_property(near_crease_);
    m_.add_property(pinned_);
    for (const VH v : m_.vertices()) {
      m_.property(slope_, v) = std::nan("");
      m_.property(near_crease_, v) = !locked.empty() && locked[std::size_t(v.idx())] == kNearCrease;
      m_.property(pinned_, v) = !locked.empty() && locked[std::size_t(v.idx())] == kPinned;
      if (m_.property(near_crease_, v)) m_.property(locked_, v) = false, creases_near_ = true;
    }
    // An open patch keeps its rim.
    for (const VH v : m_.vertices())
      if (m_.is_boundary(v)) m_.property(locked_, v) = true, m_.property(near_crease_, v) = false;
    ok_ = true;
  }
  bool ok() const { return ok_; }

  void run(QualityStats& st);

  // The mesh, compacted, and each vertex's index in the input (~0u for new ones).
  void result(TriangleMesh& out, std::vector<std::uint32_t>& origin) { from_openmesh(m_, origin_, out, origin); }

 private:
  bool locked(VH v) const { return m_.property(locked_, v); }
  // A crease point or within kNearCrease rings of one: faces here may straddle the crease.
  bool beside_crease(VH v) const { return m_.property(near_crease_, v) || on_crease(v); }
  // A collapse or flip beside a crease may not take a face's middle further off the surface than
  // off_step_cells cells or the faces it replaces were, the larger: a face across the crease cuts
  // its corner off (measured, not guessed from normals). `faces`: the old ones, then the new ones.
  bool no_further_off(std::span<const std::array<glm::dvec3, 3>> faces, std::size_t old);
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
  // Next to a locked vertex (a crease point, a rim): the ring may span two sheets, so the vertex
  // of valence 3 stays (remove_valence3).
  bool near_locked(VH v) const {
    for (const VH w : m_.vv_range(v))
      if (locked(w)) return true;
    return false;
  }
  // Next to a locked vertex that holds its neighbours (a rim's, a pinned one): such a vertex
  // neither moves nor goes away. Beside a crease point it may, each step measured against the surface there
  // (beside_crease): its faces lie on the crease's sheets, which crease points bound.
  bool near_rim(VH v) const {
    for (const VH w : m_.vv_range(v))
      if (holds_neighbours(w)) return true;
    return false;
  }
  bool pinned(VH v) const { return m_.property(pinned_, v); }
  // A locked vertex whose neighbours stay too: a rim's (a slab's, an open patch's, even a crease
  // point on it) or a pinned one. An inner crease point's neighbours move.
  bool holds_neighbours(VH w) const { return locked(w) && (!on_crease(w) || pinned(w) || m_.is_boundary(w)); }
  std::array<VH, 3> corners(FH f) const {
    const HH h = m_.halfedge_handle(f);
    return {m_.from_vertex_handle(h), m_.to_vertex_handle(h), m_.to_vertex_handle(m_.next_halfedge_handle(h))};
  }

  std::size_t split();

  // The thinness of the thinnest face around `from` that survives its collapse into `to`, with
  // `from` at `to`'s place; 2 when one of them would turn over. A needle's own normal means
  // nothing, so faces are held to the ring's area-weighted normal, which the well-shaped faces
  // dominate; with `tiny` (the edge is a speck: vertices a thousandth of a cell apart, around a
  // grid point the surface passes through) needles are not held to it at all.
  double after_collapse(HH h, bool tiny, bool to_ring = true) const;

  // Collapsing h beside a crease takes no face's middle further off the surface.
  bool surface_kept(HH h);

  // Crease points almost together (the crease passing near where several edges' crease points
  // meet) leave slivers turned any way between them, which fold into their neighbours: each such
  // pair becomes one point of the crease.
  std::size_t merge_crease_points();

  // A crease point on a chain: exactly two crease-point neighbours, on opposite sides (the
  // angle between them over 120 degrees). Corners, crossings and crease points side by side
  // across a sliver are not.
  bool chain_neighbours(VH v, VH& a, VH& b) const;

  // Moves v to `to` if its faces keep their planes, none gets degenerate, the thinnest gets less
  // thin, no face's middle goes further off the surface and v stays on it (kChainOffCells).
  bool try_move(VH v, const glm::dvec3& to);

  // Crease points slide along their chain toward the middle of their two neighbours (on the
  // chord to the farther one, which is the crease where it is straight), and one closer than
  // kChainMergeCells cells to a neighbour goes into it when that leaves its ring no thinner and
  // the surface kept: the crease step puts them where grid edges cross the crease, however
  // unevenly, and the locked points kept the slivers between them. Returns the collapses;
  // slides count as moves.
  std::size_t even_chains(QualityStats& st);

  bool on_crease(VH v) const {
    const std::uint32_t o = m_.property(origin_, v);
    return o != ~0u && !crease_.empty() && crease_[o];
  }

  // Collapsing x turns no face around its start by more than 60 degrees and leaves none degenerate.
  bool keeps_faces(HH x) const;

  std::size_t collapse();

  // A vertex of valence 3 at the corner of a needle or a cap (one that sits almost on an edge of
  // its neighbours' triangle) or of a speck (speck_corner) keeps its neighbours' needles from
  // collapsing: each of their short edges has it as a third common neighbour, which OpenMesh's
  // link check refuses. Removing it leaves its three neighbours' triangle, whichever edge
  // collapses; that triangle must face the way the ring did and not be a needle. Not beside a
  // locked vertex: there the ring may span two sheets (a crease), as for collapses.
  std::size_t remove_valence3();

  // A corner of a speck: a vertex nearer than kShortNeedleEdge cells to one of its neighbours
  // (marching tetrahedra's vertices around a grid point the surface passes near, a few
  // hundredths of a cell apart). Its own triangles may be sound while it keeps its neighbours'
  // needles from collapsing.
  bool speck_corner(VH v) const;

  // Flips `e` when that makes its two triangles' thinner one less thin (max-min angle).
  bool try_flip(EH e);

  // A cap (a corner almost on its long edge ab, here c or d) tilts its own normal any way, so the
  // pair's planes say nothing of a bend there: its flip is held instead to the well-shaped face,
  // both new faces within kCapFlipCos of it (as the remesher's caps are, meshers/remesh.cpp).
  static bool cap_flip(const glm::dvec3& pa, const glm::dvec3& pb, const glm::dvec3& pc, const glm::dvec3& pd);

  // Flips from a queue seeded with the edges of the thin faces; a flip queues the four edges
  // around it. Each flip raises the smallest angle of its pair, so the queue empties.
  std::size_t flip();

  // Faces whose smallest angle is under the pass's aim (computed in parallel).
  std::vector<std::uint8_t> thin_faces() const;

  // A vertex whose Newton step was long (kOffCells cells or more: near a crease, the field's
  // kink) goes back when it ended off the surface, more than kOffCells cells by |f - T| over the
  // slope along its normal; a short step lands within about the curvature times its square.
  void stay_on_surface(const std::vector<std::uint32_t>& movers, const std::vector<glm::dvec3>& dirs,
                       const std::vector<glm::dvec3>& tangential, const std::vector<glm::dvec3>& old,
                       std::vector<glm::dvec3>& now);

  // One Jacobi step of tangential relaxation with projection, then the moves that hurt undone.
  void relax(QualityStats& st);


  TriMesh m_;
  std::span<const std::uint8_t> crease_;  // by input vertex: on a crease line
  OpenMesh::VPropHandleT<bool> locked_;
  OpenMesh::VPropHandleT<std::uint32_t> origin_;
  OpenMesh::VPropHandleT<double> slope_;  // f's derivative along the vertex normal, NaN until known
  OpenMesh::VPropHandleT<bool> near_crease_;  // kNearCrease: not locked, but its steps are checked (beside_crease)
  OpenMesh::VPropHandleT<bool> pinned_;       // kPinned: locked, crease point or not
  bool creases_near_ = false;                // some vertex is kNearCrease
  std::vector<std::array<glm::dvec3, 3>> faces_;  // surface_kept's and relax's scratch
  const BatchField& field_;
  double T_, h_;
  QualityOptions o_;
  OffSurface off_;
  bool ok_ = false;
};

}  // namespace ht::quality_detail
