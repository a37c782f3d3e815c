#include "meshers/halfedge_ops.hpp"

namespace ht {
namespace {

using HH = TriMesh::HalfedgeHandle;
using VH = TriMesh::VertexHandle;
using FH = TriMesh::FaceHandle;

// The far corner of the triangle on `h` (invalid when `h` is a boundary halfedge); false when
// that triangle's two other edges both lie on the boundary: collapsing would leave it hanging.
bool far_corner(const TriMesh& m, HH h, VH& corner) {
  if (m.is_boundary(h)) return true;
  const HH h1 = m.next_halfedge_handle(h), h2 = m.next_halfedge_handle(h1);
  corner = m.to_vertex_handle(h1);
  return !(m.is_boundary(m.opposite_halfedge_handle(h1)) && m.is_boundary(m.opposite_halfedge_handle(h2)));
}

// Links three halfedges (next and prev) into one triangle's cycle.
void link_triangle(TriMesh& m, HH x, HH y, HH z) {
  m.set_next_halfedge_handle(x, y);
  m.set_next_halfedge_handle(y, z);
  m.set_next_halfedge_handle(z, x);
}

// Points the vertex at a boundary halfedge leaving it, when it has one (OpenMesh's rule: a
// boundary vertex's outgoing halfedge is a boundary one).
void adjust_outgoing(TriMesh& m, VH v) {
  for (auto it = m.cvoh_iter(v); it.is_valid(); ++it)
    if (m.is_boundary(*it)) {
      m.set_halfedge_handle(v, *it);
      return;
    }
}

// Removes the edge of `h`: its from-vertex merges into its to-vertex, the two sides' loops
// close around the gap (each triangle on the edge left a loop of two halfedges).
void collapse_edge(TriMesh& m, HH h) {
  const HH hn = m.next_halfedge_handle(h), hp = m.prev_halfedge_handle(h);
  const HH o = m.opposite_halfedge_handle(h), on = m.next_halfedge_handle(o), op = m.prev_halfedge_handle(o);
  const FH fh = m.face_handle(h), fo = m.face_handle(o);
  const VH vh = m.to_vertex_handle(h), vo = m.to_vertex_handle(o);
  for (auto it = m.vih_iter(vo); it.is_valid(); ++it) m.set_vertex_handle(*it, vh);
  m.set_next_halfedge_handle(hp, hn);
  m.set_next_halfedge_handle(op, on);
  if (fh.is_valid()) m.set_halfedge_handle(fh, hn);
  if (fo.is_valid()) m.set_halfedge_handle(fo, on);
  if (m.halfedge_handle(vh) == o) m.set_halfedge_handle(vh, hn);
  adjust_outgoing(m, vh);
  m.set_isolated(vo);
  m.status(m.edge_handle(h)).set_deleted(true);
  m.status(vo).set_deleted(true);
  if (m.has_halfedge_status()) {
    m.status(h).set_deleted(true);
    m.status(o).set_deleted(true);
  }
}

// Removes a loop of two halfedges, h0 and next(h0): h0's edge goes, and with it the face the
// loop bounds; next(h0) takes over the face on h0's other side.
void collapse_loop(TriMesh& m, HH h0) {
  const HH h1 = m.next_halfedge_handle(h0);
  const HH o0 = m.opposite_halfedge_handle(h0), o1 = m.opposite_halfedge_handle(h1);
  const VH v0 = m.to_vertex_handle(h0), v1 = m.to_vertex_handle(h1);
  const FH fh = m.face_handle(h0), fo = m.face_handle(o0);
  m.set_next_halfedge_handle(h1, m.next_halfedge_handle(o0));
  m.set_next_halfedge_handle(m.prev_halfedge_handle(o0), h1);
  m.set_face_handle(h1, fo);
  m.set_halfedge_handle(v0, h1);
  adjust_outgoing(m, v0);
  m.set_halfedge_handle(v1, o1);
  adjust_outgoing(m, v1);
  if (fo.is_valid() && m.halfedge_handle(fo) == o0) m.set_halfedge_handle(fo, h1);
  if (fh.is_valid()) {
    m.set_halfedge_handle(fh, TriMesh::InvalidHalfedgeHandle);
    m.status(fh).set_deleted(true);
  }
  m.status(m.edge_handle(h0)).set_deleted(true);
  if (m.has_halfedge_status()) {
    m.status(h0).set_deleted(true);
    m.status(o0).set_deleted(true);
  }
}

}  // namespace

bool collapse_ok(const TriMesh& m, HH v0v1) {
  if (m.status(m.edge_handle(v0v1)).deleted()) return false;
  const HH v1v0 = m.opposite_halfedge_handle(v0v1);
  const VH v0 = m.to_vertex_handle(v1v0), v1 = m.to_vertex_handle(v0v1);
  if (m.status(v0).deleted() || m.status(v1).deleted()) return false;
  VH vl, vr;
  if (!far_corner(m, v0v1, vl) || !far_corner(m, v1v0, vr) || vl == vr) return false;
  if (m.is_boundary(v0) && m.is_boundary(v1) && !m.is_boundary(v0v1) && !m.is_boundary(v1v0)) return false;
  // The link condition: a neighbour of both ends other than the far corners would end up with
  // two edges to the merged vertex.
  for (auto a = m.cvv_iter(v0); a.is_valid(); ++a) {
    if (*a == vl || *a == vr) continue;
    for (auto b = m.cvv_iter(v1); b.is_valid(); ++b)
      if (*a == *b) return false;
  }
  return true;
}

void collapse(TriMesh& m, HH h0) {
  const HH h1 = m.next_halfedge_handle(h0);
  const HH o1 = m.next_halfedge_handle(m.opposite_halfedge_handle(h0));
  collapse_edge(m, h0);
  // Each triangle on the edge is now a loop of two halfedges.
  if (m.next_halfedge_handle(m.next_halfedge_handle(h1)) == h1) collapse_loop(m, m.next_halfedge_handle(h1));
  if (m.next_halfedge_handle(m.next_halfedge_handle(o1)) == o1) collapse_loop(m, o1);
}

bool flip_ok(const TriMesh& m, TriMesh::EdgeHandle e) {
  if (m.is_boundary(e)) return false;
  const VH a = m.to_vertex_handle(m.next_halfedge_handle(m.halfedge_handle(e, 0)));
  const VH b = m.to_vertex_handle(m.next_halfedge_handle(m.halfedge_handle(e, 1)));
  if (a == b) return false;
  for (auto it = m.cvv_iter(a); it.is_valid(); ++it)
    if (*it == b) return false;
  return true;
}

void flip(TriMesh& m, TriMesh::EdgeHandle e) {
  // The triangles (a0, a1, a2) and (b0, b1, b2) around the edge's halfedges a0 and b0 become
  // (a0, a2, b1) and (b0, b2, a1).
  const HH a0 = m.halfedge_handle(e, 0), b0 = m.halfedge_handle(e, 1);
  const HH a1 = m.next_halfedge_handle(a0), a2 = m.next_halfedge_handle(a1);
  const HH b1 = m.next_halfedge_handle(b0), b2 = m.next_halfedge_handle(b1);
  const VH va0 = m.to_vertex_handle(a0), va1 = m.to_vertex_handle(a1);
  const VH vb0 = m.to_vertex_handle(b0), vb1 = m.to_vertex_handle(b1);
  const FH fa = m.face_handle(a0), fb = m.face_handle(b0);
  m.set_vertex_handle(a0, va1);
  m.set_vertex_handle(b0, vb1);
  link_triangle(m, a0, a2, b1);
  link_triangle(m, b0, b2, a1);
  m.set_face_handle(a1, fb);
  m.set_face_handle(b1, fa);
  m.set_halfedge_handle(fa, a0);
  m.set_halfedge_handle(fb, b0);
  if (m.halfedge_handle(va0) == b0) m.set_halfedge_handle(va0, a1);
  if (m.halfedge_handle(vb0) == a0) m.set_halfedge_handle(vb0, b1);
}

unsigned valence(const TriMesh& m, VH v) {
  unsigned n = 0;
  for (auto it = m.cvoh_iter(v); it.is_valid(); ++it) ++n;
  return n;
}

}  // namespace ht
