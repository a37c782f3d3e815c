#include "meshers/openmesh_link.hpp"

#include "meshers/edge_sides.hpp"

#include <cstdint>
#include <vector>

namespace ht {
namespace {

constexpr std::uint32_t kNone = ~0u;

using HH = TriMesh::HalfedgeHandle;

// The other side on a side's edge (sides numbered 3 * tri + corner), kNone on a boundary; false
// when an edge has more than two sides or two walked the same way.
bool mates_of(std::size_t vertices, std::span<const glm::uvec3> T, std::vector<std::uint32_t>& mate) {
  const std::vector<Side> sides = sides_by_edge(vertices, T);
  mate.assign(3 * T.size(), kNone);
  bool manifold = true;
  for_each_edge(sides, [&](std::span<const Side> run) {
    if (run.size() > 2 || (run.size() == 2 && run[0].forward == run[1].forward)) manifold = false;
    if (run.size() != 2) return;
    const std::uint32_t a = 3 * run[0].tri + run[0].corner, b = 3 * run[1].tri + run[1].corner;
    mate[a] = b, mate[b] = a;
  });
  return manifold;
}

std::uint32_t next_in(std::uint32_t s) { return s - s % 3 + (s % 3 + 1) % 3; }
std::uint32_t prev_in(std::uint32_t s) { return s - s % 3 + (s % 3 + 2) % 3; }

// Whether every vertex's triangles form one fan: turning about the vertex from one of its sides
// (to the mate of the side that arrives there, and back the other way to a boundary) must meet
// all of them. `first_out[v]` is v's side in the first triangle that uses it.
bool one_fan_each(const std::vector<std::uint32_t>& mate, const std::vector<std::uint32_t>& first_out,
                  const std::vector<std::uint32_t>& uses) {
  for (std::size_t v = 0; v < first_out.size(); ++v) {
    const std::uint32_t s0 = first_out[v];
    if (s0 == kNone) continue;
    std::uint32_t seen = 1, s = s0;
    bool open = false;
    while (true) {  // forward: the side arriving at v in this triangle, then its mate leaves v
      const std::uint32_t in = mate[prev_in(s)];
      if (in == kNone) {
        open = true;
        break;
      }
      if (in == s0 || seen > uses[v]) break;
      s = in, ++seen;
    }
    for (s = s0; open && seen <= uses[v];) {  // backward from s0 to the other boundary
      const std::uint32_t back = mate[s];
      if (back == kNone) break;
      s = next_in(back), ++seen;
    }
    if (seen != uses[v]) return false;
  }
  return true;
}

}  // namespace

bool link_manifold_triangles(TriMesh& m, std::span<const glm::uvec3> T) {
  const std::size_t n = m.n_vertices();
  if (m.n_edges() != 0 || m.n_faces() != 0) return false;
  for (const glm::uvec3& t : T)
    if (t[0] >= n || t[1] >= n || t[2] >= n || t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) return false;
  std::vector<std::uint32_t> mate;
  if (!mates_of(n, T, mate)) return false;
  std::vector<std::uint32_t> first_out(n, kNone), uses(n, 0), boundary_out(n, kNone);
  for (std::uint32_t s = 0; s < 3 * T.size(); ++s) {
    const std::uint32_t v = T[s / 3][s % 3];
    ++uses[v];
    if (first_out[v] == kNone) first_out[v] = s;
  }
  if (!one_fan_each(mate, first_out, uses)) return false;

  // Edges in order of first use, halfedge 0 along that side. The arrays are sized once: new_edge
  // and new_face would grow every property of the mesh by one element a call.
  std::vector<HH> half(3 * T.size());
  std::vector<std::uint8_t> made(3 * T.size(), 0);
  int edges = 0;
  for (std::uint32_t s = 0; s < 3 * T.size(); ++s) {
    if (made[s]) continue;
    half[s] = HH(2 * edges++);
    made[s] = 1;
    if (mate[s] != kNone) half[mate[s]] = m.opposite_halfedge_handle(half[s]), made[mate[s]] = 1;
  }
  m.resize(n, std::size_t(edges), T.size());
  for (std::uint32_t s = 0; s < 3 * T.size(); ++s)
    if (half[s].idx() % 2 == 0) {  // the side that made the edge: halfedge 0 runs along it
      const glm::uvec3& t = T[s / 3];
      m.set_vertex_handle(half[s], TriMesh::VertexHandle(int(t[(s % 3 + 1) % 3])));
      m.set_vertex_handle(m.opposite_halfedge_handle(half[s]), TriMesh::VertexHandle(int(t[s % 3])));
    }
  for (std::uint32_t t = 0; t < T.size(); ++t) {
    const TriMesh::FaceHandle f{int(t)};
    for (std::uint32_t k = 0; k < 3; ++k) {
      m.set_face_handle(half[3 * t + k], f);
      m.set_next_halfedge_handle(half[3 * t + k], half[3 * t + (k + 1) % 3]);
    }
    m.set_halfedge_handle(f, half[3 * t + 2]);
  }
  // Boundary halfedges (no face) run against their side: from its second vertex to its first.
  for (std::uint32_t s = 0; s < 3 * T.size(); ++s)
    if (mate[s] == kNone) boundary_out[T[s / 3][(s % 3 + 1) % 3]] = s;
  for (std::uint32_t s = 0; s < 3 * T.size(); ++s)
    if (mate[s] == kNone)  // it ends at the side's first vertex, where the next boundary halfedge leaves
      m.set_next_halfedge_handle(m.opposite_halfedge_handle(half[s]),
                                 m.opposite_halfedge_handle(half[boundary_out[T[s / 3][s % 3]]]));
  for (std::size_t v = 0; v < n; ++v) {
    if (first_out[v] == kNone) continue;
    const HH out = boundary_out[v] != kNone ? m.opposite_halfedge_handle(half[boundary_out[v]]) : half[first_out[v]];
    m.set_halfedge_handle(TriMesh::VertexHandle(int(v)), out);
  }
  return true;
}

}  // namespace ht
