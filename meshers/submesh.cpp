#include "meshers/submesh.hpp"

#include "meshers/edges.hpp"

namespace ht {
namespace {

// The taken triangles must form a manifold: where their boundary touches itself at a vertex (two
// fans of that vertex taken, not the ones between), the whole fan of that vertex is taken too,
// until no such vertex is left.
void widen_past_pinches(const TriangleMesh& mesh, std::vector<std::uint8_t>& taken) {
  for (int round = 0; round < 8; ++round) {
    TriangleMesh part;
    part.positions.resize(mesh.positions.size());
    for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
      if (taken[t]) part.triangles.push_back(mesh.triangles[t]);
    std::vector<std::uint8_t> out(mesh.positions.size(), 0), pinch(mesh.positions.size(), 0);
    bool any = false;
    for (const BoundaryEdge& e : boundary_edges(part))
      if (++out[e.from] == 2) pinch[e.from] = 1, any = true;
    if (!any) return;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
      for (int k = 0; k < 3; ++k)
        if (pinch[mesh.triangles[t][k]]) taken[t] = 1;
  }
}

}  // namespace

Submesh take_region(const TriangleMesh& mesh, std::span<const std::uint8_t> region) {
  const std::size_t nv = mesh.positions.size();
  std::vector<std::uint8_t> taken(mesh.triangles.size(), 0), used_outside(nv, 0);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const glm::uvec3 tri = mesh.triangles[t];
    taken[t] = region[tri[0]] || region[tri[1]] || region[tri[2]];
  }
  widen_past_pinches(mesh, taken);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    if (!taken[t]) used_outside[mesh.triangles[t][0]] = used_outside[mesh.triangles[t][1]] = used_outside[mesh.triangles[t][2]] = 1;
  Submesh sub;
  std::vector<std::uint32_t> local(nv, ~0u);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const glm::uvec3 tri = mesh.triangles[t];
    if (!taken[t]) {
      sub.rest.push_back(tri);
      continue;
    }
    glm::uvec3 lt;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = tri[k];
      if (local[v] == ~0u) {
        local[v] = std::uint32_t(sub.mesh.positions.size());
        sub.mesh.positions.push_back(mesh.positions[v]);
        sub.origin.push_back(v);
        sub.rim.push_back(!region[v] || used_outside[v]);
      }
      lt[k] = local[v];
    }
    sub.mesh.triangles.push_back(lt);
  }
  return sub;
}

void put_back(TriangleMesh& mesh, const Submesh& sub, const TriangleMesh& changed, std::span<const std::uint32_t> origin) {
  std::vector<glm::dvec3> positions = std::move(mesh.positions);
  std::vector<std::uint32_t> index(changed.positions.size());
  for (std::size_t v = 0; v < changed.positions.size(); ++v) {
    std::uint32_t o = origin[v];
    if (o == ~0u) {
      o = std::uint32_t(positions.size());
      positions.push_back(changed.positions[v]);
    } else {
      positions[o] = changed.positions[v];
    }
    index[v] = o;
  }
  std::vector<glm::uvec3> triangles = sub.rest;
  triangles.reserve(sub.rest.size() + changed.triangles.size());
  for (const glm::uvec3& t : changed.triangles) triangles.push_back({index[t[0]], index[t[1]], index[t[2]]});
  // Vertices collapsed away leave unused slots: compact, keeping the order.
  std::vector<std::uint32_t> slot(positions.size(), ~0u);
  for (const glm::uvec3& t : triangles)
    for (int k = 0; k < 3; ++k) slot[t[k]] = 0;
  mesh.positions.clear();
  for (std::uint32_t v = 0; v < positions.size(); ++v)
    if (slot[v] != ~0u) slot[v] = std::uint32_t(mesh.positions.size()), mesh.positions.push_back(positions[v]);
  mesh.triangles.clear();
  mesh.triangles.reserve(triangles.size());
  for (const glm::uvec3& t : triangles) mesh.triangles.push_back({slot[t[0]], slot[t[1]], slot[t[2]]});
}

bool to_openmesh(const TriangleMesh& mesh, std::span<const std::uint8_t> locked, std::span<const std::uint32_t> origin,
                 TriMesh& m, OpenMesh::VPropHandleT<bool>& locked_prop, OpenMesh::VPropHandleT<std::uint32_t>& origin_prop) {
  m.request_vertex_status();
  m.request_edge_status();
  m.request_halfedge_status();
  m.request_face_status();
  m.add_property(locked_prop);
  m.add_property(origin_prop);
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    const glm::dvec3& p = mesh.positions[v];
    const auto h = m.add_vertex({p.x, p.y, p.z});
    m.property(locked_prop, h) = !locked.empty() && locked[v];
    m.property(origin_prop, h) = origin.empty() ? std::uint32_t(v) : origin[v];
  }
  for (const glm::uvec3& t : mesh.triangles)
    if (!m.add_face(TriMesh::VertexHandle(int(t[0])), TriMesh::VertexHandle(int(t[1])), TriMesh::VertexHandle(int(t[2])))
             .is_valid())
      return false;
  return true;
}

void from_openmesh(TriMesh& m, OpenMesh::VPropHandleT<std::uint32_t> origin, TriangleMesh& out,
                   std::vector<std::uint32_t>& origins) {
  m.garbage_collection();
  out.positions.resize(m.n_vertices());
  origins.resize(m.n_vertices());
  for (const auto v : m.vertices()) {
    const auto& p = m.point(v);
    out.positions[std::size_t(v.idx())] = {p[0], p[1], p[2]};
    origins[std::size_t(v.idx())] = m.property(origin, v);
  }
  out.triangles.clear();
  out.triangles.reserve(m.n_faces());
  for (const auto f : m.faces()) {
    glm::uvec3 t;
    int k = 0;
    for (const auto v : m.fv_range(f)) t[k++] = std::uint32_t(v.idx());
    out.triangles.push_back(t);
  }
}

}  // namespace ht
