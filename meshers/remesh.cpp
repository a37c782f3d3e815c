#include "meshers/remesh.hpp"

#include "meshers/halfedge_ops.hpp"
#include "meshers/relax.hpp"
#include "meshers/submesh.hpp"
#include "meshers/triangle_shape.hpp"
#include "nodes/trimesh.hpp"
#include "runtime/tape_eval.hpp"

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace ht {
namespace {

constexpr double kCreaseCos = 0.8660254037844387;  // cos 30 degrees
constexpr double kSlabTargets = 24.0;  // slabs are this many target edge lengths thick
constexpr int kBandRings = 3;          // rings around the triangles across slabs, remeshed after
constexpr double kSettled = 1e-3;      // of the target: a Newton step this short is the last
constexpr double kSliverCos = 0.9659258262890683;     // cos 15 degrees: a thinner face is a sliver
constexpr double kDegenerateCos = 0.9999619230641713; // cos 0.5 degrees: no collapse leaves a face this thin
constexpr int kSliverSweeps = 3;       // rounds of sliver removal at most (each stops when none changes)
constexpr double kTinyEdge = 0.3;      // of the target: a crease point this close to a neighbour may go into it
constexpr double kShortMove = 0.02;    // of the target: a tangential move this short is not made

glm::dvec3 g(const TriMesh::Point& p) { return {p[0], p[1], p[2]}; }
TriMesh::Point om(const glm::dvec3& p) { return {p.x, p.y, p.z}; }

class Remesher {
 public:
  // `sub` holds the triangles being remeshed; origin[v] is each vertex's index in the whole
  // mesh; locked[v] those that must stay (outside the region, fixed, or on the rim).
  Remesher(const TriangleMesh& sub, const std::vector<std::uint32_t>& origin, const std::vector<std::uint8_t>& locked,
           const BatchGradient& field, double T, double target)
      : field_(field), T_(T), L_(target) {
    ok_ = to_openmesh(sub, locked, origin, m_, locked_, origin_);
    m_.add_property(creased_);
    for (const auto v : m_.vertices()) m_.property(creased_, v) = false;
    if (ok_) lock_creases();
  }
  bool ok() const { return ok_; }

  void run(int iterations, RemeshStats& st) {
    for (int it = 0; it < iterations; ++it) {
      st.splits += split();
      st.collapses += collapse();
      st.flips += flip();
      relax();
    }
    st.sliver_fixes += clean_slivers();
  }

  // The remeshed triangles, and each vertex's index in the whole mesh (~0u for new ones).
  void result(TriangleMesh& out, std::vector<std::uint32_t>& origin) { from_openmesh(m_, origin_, out, origin); }

 private:
  // Creases stay: both ends of an edge whose triangles meet at more than 30 degrees are locked,
  // when the field's gradient at those ends turns by more than 30 degrees too. A sliver's normal
  // says little of the surface (its corners lie on it, its plane need not), so a sliver beside a
  // smooth stretch is not a crease, and the remeshing may take it away.
  void lock_creases() {
    struct Candidate {
      TriMesh::VertexHandle a, b, c, d;  // the edge's ends, then its far corners
    };
    std::vector<Candidate> candidates;
    for (const auto e : m_.edges()) {
      if (m_.is_boundary(e)) continue;
      const auto h = m_.halfedge_handle(e, 0);
      if (glm::dot(normal(m_.face_handle(h)), normal(m_.face_handle(m_.opposite_halfedge_handle(h)))) >= kCreaseCos)
        continue;
      candidates.push_back({m_.from_vertex_handle(h), m_.to_vertex_handle(h),
                            m_.to_vertex_handle(m_.next_halfedge_handle(h)),
                            m_.to_vertex_handle(m_.next_halfedge_handle(m_.opposite_halfedge_handle(h)))});
    }
    if (candidates.empty()) return;
    std::vector<glm::dvec3> at, grad;
    std::vector<double> value;
    for (const Candidate& k : candidates)
      for (const auto v : {k.a, k.b, k.c, k.d}) at.push_back(g(m_.point(v)));
    grad.resize(at.size());
    value.resize(at.size());
    field_(at, value, grad);
    auto turns = [&](std::size_t i, std::size_t j) {
      const double li = glm::length(grad[i]), lj = glm::length(grad[j]);
      return !(li > 0 && lj > 0) || glm::dot(grad[i], grad[j]) < kCreaseCos * li * lj;
    };
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      // The far corners too: a crease may run along the edge itself, both ends on it.
      if (!turns(4 * i, 4 * i + 1) && !turns(4 * i + 2, 4 * i + 3)) continue;
      for (const auto v : {candidates[i].a, candidates[i].b}) {
        m_.property(creased_, v) = !locked(v) || m_.property(creased_, v);
        m_.property(locked_, v) = true;
      }
    }
  }

  bool locked(TriMesh::VertexHandle v) const { return m_.property(locked_, v); }
  bool frozen(TriMesh::EdgeHandle e) const {
    const auto h = m_.halfedge_handle(e, 0);
    return locked(m_.from_vertex_handle(h)) && locked(m_.to_vertex_handle(h));
  }
  glm::dvec3 normal(TriMesh::FaceHandle f) const {
    const auto n = m_.calc_face_normal(f);
    return {n[0], n[1], n[2]};
  }

  // Two Newton steps along the gradient; a point whose first step was shorter than
  // kSettled * L takes no second: that step's length is about the curvature times the first's
  // squared (on the bowl, 70% of the second steps were under 1e-4 L, all but 0.05% under 1e-3 L).
  void project(std::vector<glm::dvec3>& at) const {
    newton_onto(at, field_, T_, 2, std::vector<double>(at.size(), kSettled * L_));
  }

  std::size_t split() {
    struct Todo {
      TriMesh::EdgeHandle e;
      TriMesh::VertexHandle a, b;
    };
    std::vector<Todo> todo;
    std::vector<glm::dvec3> mids;
    for (const auto e : m_.edges()) {
      if (m_.status(e).deleted() || frozen(e) || m_.calc_edge_length(e) <= 4.0 / 3.0 * L_) continue;
      const auto h = m_.halfedge_handle(e, 0);
      todo.push_back({e, m_.from_vertex_handle(h), m_.to_vertex_handle(h)});
      mids.push_back(g(m_.calc_edge_midpoint(e)));
    }
    project(mids);
    std::size_t done = 0;
    for (std::size_t i = 0; i < todo.size(); ++i) {
      const auto h = m_.halfedge_handle(todo[i].e, 0);
      if (m_.from_vertex_handle(h) != todo[i].a || m_.to_vertex_handle(h) != todo[i].b) continue;
      const auto v = m_.add_vertex(om(mids[i]));
      m_.property(locked_, v) = false;
      m_.property(creased_, v) = false;
      m_.property(origin_, v) = ~0u;
      m_.split_edge(todo[i].e, v);
      ++done;
    }
    return done;
  }

  // Moving `from` onto `to` keeps every surviving triangle around `from` facing as it did.
  bool keeps_faces(TriMesh::VertexHandle from, TriMesh::VertexHandle to) {
    const auto saved = m_.point(from);
    auto& before = faces_before_;
    before.clear();
    for (const auto f : m_.vf_range(from)) before.push_back({f, normal(f)});
    m_.set_point(from, m_.point(to));
    bool good = true;
    for (const auto& [f, n] : before) {
      bool gone = false;
      for (const auto v : m_.fv_range(f)) gone |= v == to;
      if (!gone && glm::dot(normal(f), n) < 0.5) good = false;
    }
    m_.set_point(from, saved);
    return good;
  }

  std::size_t collapse() {
    std::size_t done = 0;
    for (const auto e : m_.edges()) {
      if (m_.status(e).deleted() || m_.calc_edge_length(e) >= 0.8 * L_) continue;
      for (int side = 0; side < 2; ++side) {
        const auto h = m_.halfedge_handle(e, side);
        const auto from = m_.from_vertex_handle(h), to = m_.to_vertex_handle(h);
        if (locked(from)) continue;
        // The shapes first: they turn most candidates down, the link check few.
        bool too_long = false;
        for (const auto w : m_.vv_range(from)) too_long |= glm::length(g(m_.point(w)) - g(m_.point(to))) > 4.0 / 3.0 * L_;
        if (too_long || !keeps_faces(from, to) || !ht::collapse_ok(m_, h)) continue;
        ht::collapse(m_, h);
        ++done;
        break;
      }
    }
    return done;
  }

  std::size_t flip() {
    // Valences counted once and kept up to date: m_.valence() walks the ring each time (three
    // quarters of the flips' time when called for the four corners of every edge).
    std::vector<int>& val = valence_;
    val.assign(m_.n_vertices(), 0);
    for (const auto e : m_.edges())
      if (!m_.status(e).deleted()) {
        const auto h = m_.halfedge_handle(e, 0);
        ++val[std::size_t(m_.from_vertex_handle(h).idx())], ++val[std::size_t(m_.to_vertex_handle(h).idx())];
      }
    auto dev = [&](TriMesh::VertexHandle v, int delta) {
      const int x = val[std::size_t(v.idx())] + delta - 6;
      return x * x;
    };
    std::size_t done = 0;
    for (const auto e : m_.edges()) {
      if (m_.status(e).deleted() || m_.is_boundary(e) || frozen(e)) continue;
      const auto h = m_.halfedge_handle(e, 0), o = m_.opposite_halfedge_handle(h);
      const auto a = m_.from_vertex_handle(h), b = m_.to_vertex_handle(h);
      const auto c = m_.to_vertex_handle(m_.next_halfedge_handle(h)), d = m_.to_vertex_handle(m_.next_halfedge_handle(o));
      const int before = dev(a, 0) + dev(b, 0) + dev(c, 0) + dev(d, 0);
      const int after = dev(a, -1) + dev(b, -1) + dev(c, 1) + dev(d, 1);
      if (after >= before) continue;
      const glm::dvec3 n1 = normal(m_.face_handle(h)), n2 = normal(m_.face_handle(o));
      if (glm::dot(n1, n2) < 0.95) continue;  // a crease or a tight bend: keep its edge
      if (!ht::flip_ok(m_, e)) continue;  // the topological check after the shapes'
      // The two new triangles must face as the old ones did.
      const glm::dvec3 pa = g(m_.point(a)), pb = g(m_.point(b)), pc = g(m_.point(c)), pd = g(m_.point(d));
      const glm::dvec3 up = n1 + n2;
      if (glm::dot(glm::cross(pd - pc, pa - pc), up) <= 0 || glm::dot(glm::cross(pc - pd, pb - pd), up) <= 0) continue;
      ht::flip(m_, e);
      --val[std::size_t(a.idx())], --val[std::size_t(b.idx())], ++val[std::size_t(c.idx())], ++val[std::size_t(d.idx())];
      ++done;
    }
    return done;
  }

  glm::dvec3 p(TriMesh::VertexHandle v) const { return g(m_.point(v)); }

  // The thinness of the thinnest face around `from` that survives its collapse into `to` (2 when
  // one would turn over or come out degenerate).
  double thinness_after_collapse(TriMesh::VertexHandle from, TriMesh::VertexHandle to) const {
    double worst = 0;
    for (const auto f : m_.vf_range(from)) {
      glm::dvec3 q[3], was[3];
      int k = 0;
      bool gone = false;
      for (const auto v : m_.fv_range(f)) {
        gone |= v == to;
        was[k] = p(v);
        q[k++] = v == from ? p(to) : p(v);
      }
      if (gone) continue;
      const double thin = thinness(q[0], q[1], q[2]);
      if (thin > kDegenerateCos || glm::dot(unit_normal(q[0], q[1], q[2]), unit_normal(was[0], was[1], was[2])) < 0.5)
        return 2.0;
      worst = std::max(worst, thin);
    }
    return worst;
  }

  double ring_thinness(TriMesh::VertexHandle v) const {
    double worst = 0;
    for (const auto f : m_.vf_range(v)) {
      glm::dvec3 q[3];
      int k = 0;
      for (const auto w : m_.fv_range(f)) q[k++] = p(w);
      worst = std::max(worst, thinness(q[0], q[1], q[2]));
    }
    return worst;
  }

  // Needles and caps the isotropic steps leave, mostly beside the locked rim, whose edges (a
  // scan's own, or an exact seam's) they cannot change: a triangle thinner than kSliverCos loses
  // the edge whose collapse (from a free corner) leaves the faces around it least thin, when that
  // is better than they are now; failing that its longest edge is flipped when that makes the
  // thinner of the two triangles less thin. Nothing moves, so the field is not evaluated.
  std::size_t clean_slivers() {
    std::size_t done = 0;
    for (int sweep = 0; sweep < kSliverSweeps; ++sweep) {
      std::size_t now = 0;
      for (const auto f : m_.faces()) {
        if (m_.status(f).deleted()) continue;
        TriMesh::HalfedgeHandle h[3];
        glm::dvec3 q[3];
        int k = 0;
        for (const auto he : m_.fh_range(f)) h[k] = he, q[k++] = p(m_.from_vertex_handle(he));
        if (thinness(q[0], q[1], q[2]) <= kSliverCos) continue;
        now += collapse_sliver(h) || flip_cap(h, q);
      }
      done += now;
      if (now == 0) break;
    }
    return done;
  }

  bool collapse_sliver(const TriMesh::HalfedgeHandle (&h)[3]) {
    TriMesh::HalfedgeHandle best;
    double best_thin = 2.0;
    for (const auto he : h)
      for (const auto c : {he, m_.opposite_halfedge_handle(he)}) {
        const auto from = m_.from_vertex_handle(c), to = m_.to_vertex_handle(c);
        // A crease point may go into a neighbour this close (only for a sliver, and only when the
        // faces around get less thin). Measured on the examples: at 0.1, 0.2 and 0.3 of the
        // target every largest and mean face error stayed or shrank; at 0.5 the largest grew
        // (restoration 1.6e-4 -> 3.4e-4) as crease points went too far.
        if (locked(from) && !(m_.property(creased_, from) && m_.calc_edge_length(c) < kTinyEdge * L_)) continue;
        const double after = thinness_after_collapse(from, to);
        if (after < best_thin && after < ring_thinness(from) && ht::collapse_ok(m_, c)) best_thin = after, best = c;
      }
    if (!best.is_valid()) return false;
    const auto from = m_.from_vertex_handle(best), to = m_.to_vertex_handle(best);
    if (m_.property(creased_, from) && !locked(to)) m_.property(creased_, to) = m_.property(locked_, to) = true;
    ht::collapse(m_, best);
    return true;
  }

  bool flip_cap(const TriMesh::HalfedgeHandle (&h)[3], const glm::dvec3 (&q)[3]) {
    int longest = 0;  // h[i] runs from q[i] to q[(i + 1) % 3]
    for (int i = 1; i < 3; ++i)
      if (glm::length(q[(i + 1) % 3] - q[i]) > glm::length(q[(longest + 1) % 3] - q[longest])) longest = i;
    const auto e = m_.edge_handle(h[longest]);
    if (m_.is_boundary(e) || frozen(e)) return false;
    const auto o = m_.opposite_halfedge_handle(h[longest]);
    const glm::dvec3 pa = q[longest], pb = q[(longest + 1) % 3], pc = q[(longest + 2) % 3];
    const glm::dvec3 pd = p(m_.to_vertex_handle(m_.next_halfedge_handle(o)));
    const double before = std::max(thinness(pa, pb, pc), thinness(pb, pa, pd));
    const double after = std::max(thinness(pa, pd, pc), thinness(pd, pb, pc));
    if (after >= before) return false;
    // The two new triangles face as the well-shaped neighbour does, within 30 degrees.
    const glm::dvec3 up = unit_normal(pb, pa, pd);
    if (glm::dot(unit_normal(pa, pd, pc), up) < kCreaseCos || glm::dot(unit_normal(pd, pb, pc), up) < kCreaseCos)
      return false;
    if (!ht::flip_ok(m_, e)) return false;
    ht::flip(m_, e);
    return true;
  }

  void relax() {
    std::vector<TriMesh::VertexHandle> moving;
    std::vector<glm::dvec3> at;
    // Each face's normal once, not once per corner (nothing moves until all targets are known).
    std::vector<glm::dvec3>& face_normal = face_normal_;
    face_normal.resize(m_.n_faces());
    for (const auto f : m_.faces())
      if (!m_.status(f).deleted()) face_normal[std::size_t(f.idx())] = normal(f);
    for (const auto v : m_.vertices()) {
      if (m_.status(v).deleted() || locked(v)) continue;
      glm::dvec3 c(0.0), n(0.0);
      int k = 0;
      for (const auto w : m_.vv_range(v)) c += g(m_.point(w)), ++k;
      for (const auto f : m_.vf_range(v)) n += face_normal[std::size_t(f.idx())];
      if (k == 0 || glm::length(n) == 0) continue;
      n = glm::normalize(n);
      const glm::dvec3 p = g(m_.point(v)), d = c / double(k) - p, t = d - glm::dot(d, n) * n;
      // A move this short changes no angle that matters and is not worth a field evaluation
      // (on the bowl, a fifth of all the moves).
      if (glm::dot(t, t) < kShortMove * kShortMove * L_ * L_) continue;
      moving.push_back(v);
      at.push_back(p + t);
    }
    project(at);
    for (std::size_t i = 0; i < moving.size(); ++i) {
      const auto v = moving[i];
      const auto saved = m_.point(v);
      std::vector<glm::dvec3>& before = ring_normals_;
      before.clear();
      for (const auto f : m_.vf_range(v)) before.push_back(normal(f));
      m_.set_point(v, om(at[i]));
      std::size_t k = 0;
      bool good = true;
      for (const auto f : m_.vf_range(v)) good &= glm::dot(normal(f), before[k++]) > 0.5;
      if (!good) m_.set_point(v, saved);
    }
  }

  TriMesh m_;
  std::vector<std::pair<TriMesh::FaceHandle, glm::dvec3>> faces_before_;  // keeps_faces' scratch
  std::vector<int> valence_;  // flip's: each vertex's valence
  std::vector<glm::dvec3> face_normal_;  // relax's: each face's unit normal before the moves
  std::vector<glm::dvec3> ring_normals_;  // relax's: the normals around the vertex being moved
  OpenMesh::VPropHandleT<bool> locked_;
  OpenMesh::VPropHandleT<bool> creased_;  // locked by lock_creases() alone (not a rim, not fixed)
  OpenMesh::VPropHandleT<std::uint32_t> origin_;
  const BatchGradient& field_;
  double T_, L_;
  bool ok_ = false;
};

// Each part remeshed on its own, in parallel, its rim and `fixed` vertices locked; put back in
// part order (renumber: as put_back).
void remesh_parts(TriangleMesh& mesh, const Pieces& pieces, std::span<const std::uint8_t> fixed,
                  const BatchGradient& field, double threshold, const RemeshOptions& options, RemeshStats& st,
                  std::vector<std::uint32_t>* renumber) {
  const std::size_t n = pieces.parts.size();
  std::vector<TriangleMesh> changed(n);
  std::vector<std::vector<std::uint32_t>> origin(n);
  std::vector<RemeshStats> part_stats(n);
  tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
    const Submesh& sub = pieces.parts[i];
    changed[i] = sub.mesh;  // a part OpenMesh refuses stays as it was
    origin[i] = sub.origin;
    if (sub.mesh.triangles.empty()) return;
    std::vector<std::uint8_t> locked(sub.mesh.positions.size());
    for (std::size_t v = 0; v < locked.size(); ++v) locked[v] = sub.rim[v] || fixed[sub.origin[v]];
    Remesher r(sub.mesh, sub.origin, locked, field, threshold, options.target);
    if (!r.ok()) return;
    r.run(options.iterations, part_stats[i]);
    r.result(changed[i], origin[i]);
  });
  for (const RemeshStats& p : part_stats) {
    st.splits += p.splits, st.collapses += p.collapses, st.flips += p.flips;
    st.sliver_fixes += p.sliver_fixes;
  }
  put_back(mesh, pieces, changed, origin, renumber);
}

}  // namespace

void remesh_region(TriangleMesh& mesh, std::span<const std::uint8_t> region, std::span<const std::uint8_t> fixed,
                   const BatchGradient& field, double threshold, const RemeshOptions& options, RemeshStats* stats,
                   std::vector<std::uint32_t>* renumber_out) {
  RemeshStats st;
  // Slabs of the region first, in parallel, each triangle with a corner in the region and all
  // three in one slab; a vertex that any other triangle uses is on a rim and stays.
  std::size_t count = 1;
  const std::vector<std::uint32_t> slab = slab_of_vertices(mesh, kSlabTargets * options.target, count);
  std::vector<std::uint32_t> piece_of(mesh.triangles.size(), ~0u);
  std::vector<std::uint8_t> band(mesh.positions.size(), 0);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const glm::uvec3 c = mesh.triangles[t];
    if (!region[c[0]] && !region[c[1]] && !region[c[2]]) continue;
    if (slab[c[0]] == slab[c[1]] && slab[c[0]] == slab[c[2]]) piece_of[t] = slab[c[0]];
    else band[c[0]] = band[c[1]] = band[c[2]] = 1;
  }
  std::vector<std::uint32_t> renumber;
  remesh_parts(mesh, take_pieces(mesh, std::move(piece_of), count), fixed, field, threshold, options, st, &renumber);
  // Then the triangles across slabs and kBandRings rings of the region around them, each
  // connected band on its own, in parallel.
  if (std::find(band.begin(), band.end(), 1) != band.end()) {
    // Vertices the slabs made are inside the region, neither band nor fixed.
    auto moved = [&](std::span<const std::uint8_t> flags, std::uint8_t fresh) {
      return renumbered(flags, renumber, mesh.positions.size(), fresh);
    };
    std::vector<std::uint8_t> seeds = moved(band, 0);
    const std::vector<std::uint8_t> inside = moved(region, 1), fixed2 = moved(fixed, 0);
    const std::vector<std::uint8_t> around = rings_around(mesh, seeds, inside, kBandRings);
    for (std::size_t v = 0; v < seeds.size(); ++v) seeds[v] = (seeds[v] || around[v]) && inside[v];
    std::vector<std::uint32_t> second;
    remesh_parts(mesh, take_region(mesh, seeds, true), fixed2, field, threshold, options, st, renumber_out ? &second : nullptr);
    if (renumber_out)
      for (std::uint32_t& v : renumber)
        if (v != ~0u) v = second[v];
  }
  if (renumber_out) *renumber_out = std::move(renumber);
  if (stats) *stats = st;
}

}  // namespace ht
