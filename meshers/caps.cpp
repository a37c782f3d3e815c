#include "meshers/caps.hpp"

#include "meshers/bridge.hpp"
#include "meshers/halfedge_ops.hpp"
#include "nodes/trimesh.hpp"

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <vector>

namespace ht {
namespace {

// A face of the box: the axis it is normal to and which end (outward normal +axis when hi).
struct Face {
  int axis = 0;
  bool hi = false;
  double value = 0;
};

double cross2(glm::dvec2 a, glm::dvec2 b, glm::dvec2 c) { return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x); }

// The face a loop lies on, or throws.
Face face_of(const TriangleMesh& m, const std::vector<std::uint32_t>& loop, const Aabb& box, double tol) {
  Face best;
  double best_dev = tol;
  bool found = false;
  for (int axis = 0; axis < 3; ++axis)
    for (bool hi : {false, true}) {
      const double v = hi ? box.hi[axis] : box.lo[axis];
      double dev = 0;
      for (std::uint32_t i : loop) dev = std::max(dev, std::abs(m.positions[i][axis] - v));
      if (dev <= best_dev) best = {axis, hi, v}, best_dev = dev, found = true;
    }
  if (!found) throw CapError("a cut loop leaves the face of the box it starts on (a cap across an edge of the box)");
  return best;
}

// 2D coordinates in the face's plane, oriented so that counter-clockwise faces out of the box.
glm::dvec2 planar(const glm::dvec3& p, const Face& f) {
  const int u = (f.axis + 1) % 3, w = (f.axis + 2) % 3;
  return f.hi ? glm::dvec2(p[u], p[w]) : glm::dvec2(p[w], p[u]);
}

double signed_area(const std::vector<glm::dvec2>& q) {
  double a = 0;
  for (std::size_t i = 0; i < q.size(); ++i) a += q[i].x * q[(i + 1) % q.size()].y - q[(i + 1) % q.size()].x * q[i].y;
  return 0.5 * a;
}

bool inside_polygon(const std::vector<glm::dvec2>& poly, glm::dvec2 p) {
  bool in = false;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++)
    if ((poly[i].y > p.y) != (poly[j].y > p.y) &&
        p.x < (poly[j].x - poly[i].x) * (p.y - poly[i].y) / (poly[j].y - poly[i].y) + poly[i].x)
      in = !in;
  return in;
}

// Ear clipping of a counter-clockwise simple polygon; triangles as indices into q.
std::vector<std::array<std::uint32_t, 3>> ear_clip(const std::vector<glm::dvec2>& q) {
  const std::size_t n = q.size();
  std::vector<std::uint32_t> prev(n), next(n);
  for (std::size_t i = 0; i < n; ++i) prev[i] = std::uint32_t((i + n - 1) % n), next[i] = std::uint32_t((i + 1) % n);
  auto is_ear = [&](std::uint32_t b) {
    const std::uint32_t a = prev[b], c = next[b];
    if (cross2(q[a], q[b], q[c]) <= 0) return false;
    for (std::uint32_t o = next[c]; o != a; o = next[o]) {
      if (cross2(q[prev[o]], q[o], q[next[o]]) > 0) continue;  // only reflex corners can lie inside
      if (cross2(q[a], q[b], q[o]) >= 0 && cross2(q[b], q[c], q[o]) >= 0 && cross2(q[c], q[a], q[o]) >= 0) return false;
    }
    return true;
  };
  std::vector<std::array<std::uint32_t, 3>> tris;
  std::uint32_t v = 0;
  for (std::size_t left = n, misses = 0; left > 3;) {
    if (is_ear(v)) {
      tris.push_back({prev[v], v, next[v]});
      next[prev[v]] = next[v];
      prev[next[v]] = prev[v];
      v = next[v];
      --left;
      misses = 0;
    } else {
      v = next[v];
      if (++misses > left) throw CapError("a cut loop is not a simple polygon in its face");
    }
  }
  tris.push_back({prev[v], v, next[v]});
  return tris;
}

// Lawson flips to the constrained Delaunay triangulation: polygon edges stay.
std::size_t delaunay_flips(const std::vector<glm::dvec2>& q, std::vector<std::array<std::uint32_t, 3>>& t) {
  auto key = [](std::uint32_t a, std::uint32_t b) { return (std::uint64_t(std::min(a, b)) << 32) | std::max(a, b); };
  auto angle = [&](std::uint32_t o, std::uint32_t a, std::uint32_t b) {
    const glm::dvec2 u = q[a] - q[o], v = q[b] - q[o];
    return std::abs(std::atan2(u.x * v.y - u.y * v.x, u.x * v.x + u.y * v.y));
  };
  std::size_t flips = 0;
  for (bool changed = true; changed && flips < 50 * t.size();) {
    changed = false;
    std::map<std::uint64_t, std::vector<std::size_t>> owner;
    for (std::size_t i = 0; i < t.size(); ++i)
      for (int k = 0; k < 3; ++k) owner[key(t[i][k], t[i][(k + 1) % 3])].push_back(i);
    std::vector<std::uint8_t> touched(t.size(), 0);
    for (const auto& [edge, tris] : owner) {
      if (tris.size() != 2 || touched[tris[0]] || touched[tris[1]]) continue;
      auto& t1 = t[tris[0]];
      auto& t2 = t[tris[1]];
      int k1 = 0;
      while (key(t1[k1], t1[(k1 + 1) % 3]) != edge) ++k1;
      const std::uint32_t a = t1[k1], b = t1[(k1 + 1) % 3], r = t1[(k1 + 2) % 3];
      std::uint32_t s = t2[0] + t2[1] + t2[2] - a - b;
      if (angle(r, b, a) + angle(s, a, b) <= 3.14159265358979 + 1e-12) continue;
      if (cross2(q[r], q[s], q[b]) <= 0 || cross2(q[s], q[r], q[a]) <= 0) continue;  // the quad is not convex
      t1 = {r, a, s};
      t2 = {s, b, r};
      touched[tris[0]] = touched[tris[1]] = 1;
      changed = true;
      ++flips;
    }
  }
  return flips;
}

// Remeshes a cap's interior to edges of about `target` (Botsch & Kobbelt's isotropic remeshing,
// in the cap's plane): split edges longer than 4/3 target, collapse those shorter than 4/5 into
// an interior end, flip to Delaunay, move interior vertices to their neighbours' centroid. The
// boundary (shared with the cut mesh) never changes. Halfedge work on an OpenMesh mesh of the
// cap, with OpenMesh's collapse and flip checks (meshers/halfedge_ops.hpp). Points are appended
// to q; t is replaced.
class CapRemesher {
 public:
  CapRemesher(const std::vector<glm::dvec2>& q, const std::vector<std::array<std::uint32_t, 3>>& t) {
    m_.request_vertex_status();  // collapse and garbage collection mark and sweep
    m_.request_edge_status();
    m_.request_halfedge_status();
    m_.request_face_status();
    for (const glm::dvec2& p : q) m_.add_vertex(TriMesh::Point(p.x, p.y, 0.0));
    for (const auto& tri : t)
      m_.add_face(TriMesh::VertexHandle(int(tri[0])), TriMesh::VertexHandle(int(tri[1])), TriMesh::VertexHandle(int(tri[2])));
    ok_ = m_.n_faces() == t.size();
    boundary_count_ = q.size();
  }
  bool ok() const { return ok_; }

  std::size_t run(double target) {
    for (int it = 0; it < 6; ++it) {
      split(4.0 / 3.0 * target);
      collapse(0.8 * target, 4.0 / 3.0 * target);
      delaunay();
      relax();
    }
    delaunay();
    return flips_;
  }

  void result(std::vector<glm::dvec2>& q, std::vector<std::array<std::uint32_t, 3>>& t) {
    m_.garbage_collection();
    q.clear();
    for (const auto v : m_.vertices()) q.push_back(xy(v));
    t.clear();
    for (const auto f : m_.faces()) {
      std::array<std::uint32_t, 3> tri;
      int k = 0;
      for (const auto v : m_.fv_range(f)) tri[std::size_t(k++)] = std::uint32_t(v.idx());
      t.push_back(tri);
    }
  }

 private:
  glm::dvec2 xy(TriMesh::VertexHandle v) const { return {m_.point(v)[0], m_.point(v)[1]}; }

  void split(double longer) {
    std::vector<TriMesh::EdgeHandle> todo;
    for (const auto e : m_.edges())
      if (!m_.is_boundary(e) && m_.calc_edge_length(e) > longer) todo.push_back(e);
    for (const auto e : todo)
      if (!m_.status(e).deleted() && m_.calc_edge_length(e) > longer) m_.split_edge(e, m_.add_vertex(m_.calc_edge_midpoint(e)));
  }

  void collapse(double shorter, double longer) {
    for (const auto e : m_.edges()) {
      if (m_.status(e).deleted() || m_.calc_edge_length(e) >= shorter) continue;
      for (int side = 0; side < 2; ++side) {
        const auto h = m_.halfedge_handle(e, side);  // collapse from -> to
        const auto from = m_.from_vertex_handle(h), to = m_.to_vertex_handle(h);
        if (m_.is_boundary(from) || !ht::collapse_ok(m_, h)) continue;
        bool too_long = false;
        for (const auto w : m_.vv_range(from)) too_long |= glm::length(xy(w) - xy(to)) > longer;
        if (too_long || !keeps_orientation(from, to)) continue;
        ht::collapse(m_, h);
        break;
      }
    }
  }

  // Moving `from` onto `to` must not turn any surviving triangle around `from` over.
  bool keeps_orientation(TriMesh::VertexHandle from, TriMesh::VertexHandle to) const {
    for (const auto f : m_.vf_range(from)) {
      glm::dvec2 p[3];
      int k = 0;
      bool gone = false;
      for (const auto v : m_.fv_range(f)) {
        gone |= v == to;
        p[k++] = v == from ? xy(to) : xy(v);
      }
      if (!gone && cross2(p[0], p[1], p[2]) <= 0) return false;
    }
    return true;
  }

  double opposite_angles(TriMesh::EdgeHandle e) const {
    double sum = 0;
    for (int side = 0; side < 2; ++side) {
      const auto h = m_.halfedge_handle(e, side);
      const auto o = m_.to_vertex_handle(m_.next_halfedge_handle(h));
      const glm::dvec2 u = xy(m_.from_vertex_handle(h)) - xy(o), v = xy(m_.to_vertex_handle(h)) - xy(o);
      sum += std::abs(std::atan2(u.x * v.y - u.y * v.x, u.x * v.x + u.y * v.y));
    }
    return sum;
  }

  void delaunay() {
    for (int round = 0; round < 16; ++round) {
      std::size_t done = 0;
      for (const auto e : m_.edges()) {
        if (m_.status(e).deleted() || m_.is_boundary(e) || opposite_angles(e) <= 3.14159265358979 + 1e-9 || !ht::flip_ok(m_, e))
          continue;
        const auto h = m_.halfedge_handle(e, 0);
        const auto a = m_.from_vertex_handle(h), b = m_.to_vertex_handle(h);
        const auto r = m_.to_vertex_handle(m_.next_halfedge_handle(h));
        const auto s = m_.to_vertex_handle(m_.next_halfedge_handle(m_.opposite_halfedge_handle(h)));
        if (cross2(xy(r), xy(s), xy(b)) <= 0 || cross2(xy(s), xy(r), xy(a)) <= 0) continue;  // not a convex quad
        ht::flip(m_, e);
        ++done;
      }
      flips_ += done;
      if (done == 0) break;
    }
  }

  void relax() {
    std::vector<std::pair<TriMesh::VertexHandle, glm::dvec2>> moves;
    for (const auto v : m_.vertices()) {
      if (m_.status(v).deleted() || m_.is_boundary(v)) continue;
      glm::dvec2 c(0.0);
      int n = 0;
      for (const auto w : m_.vv_range(v)) c += xy(w), ++n;
      if (n) moves.push_back({v, c / double(n)});
    }
    for (const auto& [v, c] : moves) {
      const glm::dvec2 old = xy(v);
      m_.set_point(v, TriMesh::Point(c.x, c.y, 0.0));
      bool flipped = false;  // a move that turns a triangle over is undone
      for (const auto f : m_.vf_range(v)) {
        glm::dvec2 p[3];
        int k = 0;
        for (const auto w : m_.fv_range(f)) p[k++] = xy(w);
        flipped |= cross2(p[0], p[1], p[2]) <= 0;
      }
      if (flipped) m_.set_point(v, TriMesh::Point(old.x, old.y, 0.0));
    }
  }

  TriMesh m_;
  bool ok_ = false;
  std::size_t boundary_count_ = 0, flips_ = 0;
};

void refine(std::vector<glm::dvec2>& q, std::vector<std::array<std::uint32_t, 3>>& t, double max_edge, std::size_t& flips) {
  CapRemesher r(q, t);
  if (!r.ok()) return;  // not a manifold OpenMesh takes: keep the plain triangulation
  flips += r.run(max_edge / 1.5);
  r.result(q, t);
}

}  // namespace

void cap_box_openings(TriangleMesh& mesh, const Aabb& box, double tol, double max_edge, CapStats* stats) {
  CapStats st;
  const auto loops = boundary_loops(mesh);
  struct Ring {
    Face face;
    std::vector<std::uint32_t> vertices;  // the loop reversed: the cap's boundary
    std::vector<glm::dvec2> q;
  };
  std::vector<Ring> rings;
  for (const auto& loop : loops) {
    Ring r;
    r.face = face_of(mesh, loop, box, tol);
    r.vertices.assign(loop.rbegin(), loop.rend());
    for (std::uint32_t v : r.vertices) {
      mesh.positions[v][r.face.axis] = r.face.value;
      r.q.push_back(planar(mesh.positions[v], r.face));
    }
    if (signed_area(r.q) <= 0) throw CapError("a cut loop bounds a hole in its cap (a cap with a hole)");
    rings.push_back(std::move(r));
  }
  for (std::size_t i = 0; i < rings.size(); ++i)
    for (std::size_t j = 0; j < rings.size(); ++j)
      if (i != j && rings[i].face.axis == rings[j].face.axis && rings[i].face.hi == rings[j].face.hi &&
          inside_polygon(rings[j].q, rings[i].q[0]))
        throw CapError("cut loops nest in one face (a cap with a hole)");
  // Each opening on its own, in parallel; appended in loop order.
  std::vector<std::vector<std::array<std::uint32_t, 3>>> tris(rings.size());
  std::vector<std::size_t> flips(rings.size(), 0);
  tbb::parallel_for(std::size_t(0), rings.size(), [&](std::size_t i) {
    tris[i] = ear_clip(rings[i].q);
    flips[i] = delaunay_flips(rings[i].q, tris[i]);
    if (max_edge > 0) refine(rings[i].q, tris[i], max_edge, flips[i]);
  });
  for (std::size_t i = 0; i < rings.size(); ++i) {
    Ring& r = rings[i];
    // Points the refinement added become vertices in the face's plane.
    for (std::size_t k = r.vertices.size(); k < r.q.size(); ++k) {
      glm::dvec3 p;
      const int u = (r.face.axis + 1) % 3, w = (r.face.axis + 2) % 3;
      p[r.face.axis] = r.face.value;
      p[r.face.hi ? u : w] = r.q[k].x;
      p[r.face.hi ? w : u] = r.q[k].y;
      r.vertices.push_back(std::uint32_t(mesh.positions.size()));
      mesh.positions.push_back(p);
    }
    for (const auto& t : tris[i])
      mesh.triangles.push_back({r.vertices[t[0]], r.vertices[t[1]], r.vertices[t[2]]});
    st.triangles += tris[i].size();
    st.flips += flips[i];
    ++st.loops;
  }
  if (stats) *stats = st;
}

}  // namespace ht
