#include "meshers/submesh.hpp"

#include "meshers/openmesh_link.hpp"
#include "meshers/union_find.hpp"

#include <glm/common.hpp>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace ht {
namespace {

// The vertices where the boundary of a set of triangles passes twice (the set touches itself
// there, a pinch OpenMesh cannot hold), sorted: an undirected edge used once in the set is on its
// boundary, and a vertex that two such edges leave in the set's orientation is pinched. Only the
// edges both of whose ends `may_rim` allows are counted: a caller that knows a vertex has all its
// triangles in the set and the mesh closed around it (so no edge at it is on the boundary)
// passes over the set's inside. Edges
// are sorted as one 64-bit key each, {min, max, whether it leaves max} (so vertex indices must
// stay under 2^31), which compares faster than arrays of three indices.
template <class MayRim>
std::vector<std::uint32_t> pinched_vertices(const TriangleMesh& mesh, std::span<const std::uint32_t> tris,
                                            MayRim&& may_rim) {
  if (mesh.positions.size() > (std::size_t(1) << 31)) throw std::length_error("pinched_vertices: over 2^31 vertices");
  std::vector<std::uint64_t> edges;
  for (const std::uint32_t t : tris)
    for (int k = 0; k < 3; ++k) {
      const std::uint64_t a = mesh.triangles[t][k], b = mesh.triangles[t][(k + 1) % 3];
      if (may_rim(std::uint32_t(a)) && may_rim(std::uint32_t(b)))
        edges.push_back(std::min(a, b) << 33 | std::max(a, b) << 1 | std::uint64_t(a > b));
    }
  tbb::parallel_sort(edges.begin(), edges.end());  // plain keys: one order at any thread count
  std::vector<std::uint32_t> leaving;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i + 1;
    while (j < edges.size() && edges[j] >> 1 == edges[i] >> 1) ++j;
    if (j - i == 1) leaving.push_back(std::uint32_t(edges[i] & 1 ? edges[i] >> 1 & 0xffffffffu : edges[i] >> 33));
    i = j;
  }
  std::sort(leaving.begin(), leaving.end());
  std::vector<std::uint32_t> pinched;
  for (std::size_t i = 0; i + 1 < leaving.size(); ++i)
    if (leaving[i] == leaving[i + 1] && (pinched.empty() || pinched.back() != leaving[i])) pinched.push_back(leaving[i]);
  return pinched;
}

// Flags the vertices where the mesh itself is open: around a vertex of a closed fan every edge
// runs once each way, so the sums of the vertices after it and before it along its triangles'
// edges agree; at a vertex on the mesh's boundary they differ by its next boundary neighbour less
// its previous one. Exact on consistently oriented manifold meshes, closed or open (what the
// meshers take parts of: their own output and closed mesh leaves; winding leaves, which may be
// neither, are polygonized whole). At a non-manifold or misoriented vertex the sums may cancel,
// and a pinch there go unseen.
std::vector<std::uint8_t> open_vertices(const TriangleMesh& mesh) {
  std::vector<std::int64_t> balance(mesh.positions.size(), 0);
  for (const glm::uvec3& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      balance[t[k]] += std::int64_t(t[(k + 1) % 3]);
      balance[t[(k + 1) % 3]] -= std::int64_t(t[k]);
    }
  std::vector<std::uint8_t> open(balance.size());
  for (std::size_t v = 0; v < open.size(); ++v) open[v] = balance[v] != 0;
  return open;
}

// The one part whose triangles use each vertex (~0u: only untaken triangles), ~1u for several.
std::vector<std::uint32_t> owners(const TriangleMesh& mesh, std::span<const std::uint32_t> piece_of) {
  constexpr std::uint32_t kUnseen = ~2u;
  std::vector<std::uint32_t> owner(mesh.positions.size(), kUnseen);
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      std::uint32_t& o = owner[mesh.triangles[t][k]];
      o = o == kUnseen || o == piece_of[t] ? piece_of[t] : ~1u;
    }
  return owner;
}

bool touches(const glm::uvec3& t, const std::vector<std::uint32_t>& sorted_vertices) {
  for (int k = 0; k < 3; ++k)
    if (std::binary_search(sorted_vertices.begin(), sorted_vertices.end(), t[k])) return true;
  return false;
}

// The taken triangles must form a manifold: at a pinch the whole fan of the vertex is taken too,
// until no pinch is left. Only the taken triangles' rim can be pinched: vertices an untaken
// triangle uses, or where the mesh itself is open.
void widen_past_pinches(const TriangleMesh& mesh, std::vector<std::uint8_t>& taken) {
  const std::vector<std::uint8_t> open = open_vertices(mesh);
  for (int round = 0; round < 8; ++round) {
    std::vector<std::uint32_t> tris;
    std::vector<std::uint8_t> rim = open;
    for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
      if (taken[t]) tris.push_back(t);
      else rim[mesh.triangles[t][0]] = rim[mesh.triangles[t][1]] = rim[mesh.triangles[t][2]] = 1;
    const std::vector<std::uint32_t> pinched = pinched_vertices(mesh, tris, [&](std::uint32_t v) { return rim[v] != 0; });
    if (pinched.empty()) return;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
      if (touches(mesh.triangles[t], pinched)) taken[t] = 1;
  }
}

// Where OpenMesh's garbage collection puts the elements that survive (new index -> old): it
// fills the first hole with the last survivor, and so on inward. Computed without moving
// anything, so the output is numbered as a collected mesh would be without collecting it.
template <class Deleted>
std::vector<int> collected_order(int n, Deleted deleted) {
  std::vector<int> order(std::size_t(std::max(n, 0)));
  for (int i = 0; i < n; ++i) order[std::size_t(i)] = i;
  if (n == 0) return order;
  int i0 = 0, i1 = n - 1;
  for (;;) {
    while (!deleted(order[std::size_t(i0)]) && i0 < i1) ++i0;
    while (deleted(order[std::size_t(i1)]) && i0 < i1) --i1;
    if (i0 >= i1) break;
    std::swap(order[std::size_t(i0)], order[std::size_t(i1)]);
  }
  order.resize(std::size_t(deleted(order[std::size_t(i0)]) ? i0 : i0 + 1));
  return order;
}

}  // namespace

PiecePlan plan_pieces(const TriangleMesh& mesh, std::vector<std::uint32_t> piece_of, std::size_t count) {
  const std::size_t nt = mesh.triangles.size();
  PiecePlan plan;
  plan.of_part.resize(count);
  for (std::uint32_t t = 0; t < nt; ++t)
    if (piece_of[t] != ~0u) plan.of_part[piece_of[t]].push_back(t);
  // A part pinched at a vertex gives its triangles there back, until no part is pinched. Only
  // its rim can be pinched: a vertex all of whose triangles are the part's, where the mesh is
  // closed, is inside it. The vertices of triangles given back join the rim.
  const std::vector<std::uint32_t> first_owner = owners(mesh, piece_of);
  const std::vector<std::uint8_t> open = open_vertices(mesh);
  tbb::parallel_for(std::size_t(0), count, [&](std::size_t i) {
    std::vector<std::uint32_t> freed;  // sorted: vertices beside triangles the part gave back
    auto may_rim = [&](std::uint32_t v) {
      return first_owner[v] != i || open[v] || std::binary_search(freed.begin(), freed.end(), v);
    };
    for (int round = 0; round < 8; ++round) {
      const std::vector<std::uint32_t> pinched = pinched_vertices(mesh, plan.of_part[i], may_rim);
      if (pinched.empty()) break;
      std::erase_if(plan.of_part[i], [&](std::uint32_t t) {
        const bool drop = touches(mesh.triangles[t], pinched);
        if (drop) {
          piece_of[t] = ~0u;
          for (int k = 0; k < 3; ++k) freed.push_back(mesh.triangles[t][k]);
        }
        return drop;
      });
      std::sort(freed.begin(), freed.end());
      freed.erase(std::unique(freed.begin(), freed.end()), freed.end());
    }
  });
  // A vertex is on a part's rim when a triangle of another part, or of none, uses it.
  plan.owner = owners(mesh, piece_of);
  for (std::uint32_t t = 0; t < nt; ++t)
    if (piece_of[t] == ~0u) plan.rest.push_back(mesh.triangles[t]);
  return plan;
}

// The part numbers its vertices in the order its triangles meet them: counted first, so that its
// arrays are sized exactly.
Submesh take_part(const TriangleMesh& mesh, const PiecePlan& plan, std::size_t i, std::vector<std::uint32_t>& local) {
  Submesh sub;
  std::uint32_t used = 0;
  for (const std::uint32_t t : plan.of_part[i])
    for (int k = 0; k < 3; ++k)
      if (std::uint32_t& l = local[mesh.triangles[t][k]]; l == ~0u) l = used++;
  sub.mesh.positions.resize(used);
  sub.origin.resize(used);
  sub.rim.resize(used);
  sub.mesh.triangles.reserve(plan.of_part[i].size());
  for (const std::uint32_t t : plan.of_part[i]) {
    glm::uvec3 lt;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = mesh.triangles[t][k];
      lt[k] = local[v];
      sub.mesh.positions[lt[k]] = mesh.positions[v];
      sub.origin[lt[k]] = v;
      sub.rim[lt[k]] = plan.owner[v] != i;
    }
    sub.mesh.triangles.push_back(lt);
  }
  for (const std::uint32_t v : sub.origin) local[v] = ~0u;
  return sub;
}

Pieces take_pieces(const TriangleMesh& mesh, std::vector<std::uint32_t> piece_of, std::size_t count) {
  PiecePlan plan = plan_pieces(mesh, std::move(piece_of), count);
  Pieces out;
  out.parts.resize(count);
  out.rest = std::move(plan.rest);
  // In parallel: a thread's table of local numbers is cleared after each part it takes.
  tbb::enumerable_thread_specific<std::vector<std::uint32_t>> locals(mesh.positions.size(), ~0u);
  tbb::parallel_for(std::size_t(0), count, [&](std::size_t i) { out.parts[i] = take_part(mesh, plan, i, locals.local()); });
  return out;
}

Pieces take_region(const TriangleMesh& mesh, std::span<const std::uint8_t> region, bool apart) {
  std::vector<std::uint8_t> taken(mesh.triangles.size(), 0);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const glm::uvec3 tri = mesh.triangles[t];
    taken[t] = region[tri[0]] || region[tri[1]] || region[tri[2]];
  }
  widen_past_pinches(mesh, taken);
  std::vector<std::uint32_t> piece_of(mesh.triangles.size(), ~0u);
  std::size_t count = 1;
  if (apart) {
    // Pieces apart share no vertex, so each is free of pinches as the whole is.
    UnionFind sets(mesh.positions.size());
    for (std::size_t t = 0; t < taken.size(); ++t)
      if (taken[t]) sets.unite(mesh.triangles[t][0], mesh.triangles[t][1]), sets.unite(mesh.triangles[t][0], mesh.triangles[t][2]);
    std::vector<std::uint32_t> piece(mesh.positions.size(), ~0u);
    count = 0;
    for (std::size_t t = 0; t < taken.size(); ++t) {
      if (!taken[t]) continue;
      std::uint32_t& p = piece[sets.find(mesh.triangles[t][0])];
      if (p == ~0u) p = std::uint32_t(count++);
      piece_of[t] = p;
    }
  } else {
    for (std::size_t t = 0; t < taken.size(); ++t) piece_of[t] = taken[t] ? 0u : ~0u;
  }
  Pieces out = take_pieces(mesh, std::move(piece_of), count);
  for (Submesh& sub : out.parts)
    for (std::size_t v = 0; v < sub.rim.size(); ++v) sub.rim[v] |= !region[sub.origin[v]];
  return out;
}

void put_back(TriangleMesh& mesh, const Pieces& pieces, std::span<const TriangleMesh> changed,
              std::span<const std::vector<std::uint32_t>> origin, std::vector<std::uint32_t>* renumber) {
  put_back(mesh, pieces.rest, changed, origin, renumber);
}

void put_back(TriangleMesh& mesh, std::span<const glm::uvec3> rest, std::span<const TriangleMesh> changed,
              std::span<const std::vector<std::uint32_t>> origin, std::vector<std::uint32_t>* renumber) {
  // The mesh's own arrays are rebuilt in place, each grown once to its final size: copies of
  // them beside the parts were the peak of a trimmed Boolean's run (bunny00 minus a ball).
  const std::size_t old_count = mesh.positions.size();
  std::size_t added = 0, fresh = 0;
  for (std::size_t i = 0; i < changed.size(); ++i) {
    added += changed[i].triangles.size();
    fresh += std::size_t(std::count(origin[i].begin(), origin[i].end(), ~0u));
  }
  std::vector<glm::dvec3>& positions = mesh.positions;
  positions.reserve(old_count + fresh);
  std::vector<glm::uvec3>& triangles = mesh.triangles;
  std::vector<glm::uvec3>().swap(triangles);  // the untaken ones are in `rest`, a copy of their own
  triangles.reserve(rest.size() + added);
  triangles.assign(rest.begin(), rest.end());
  for (std::size_t i = 0; i < changed.size(); ++i) {
    std::vector<std::uint32_t> index(changed[i].positions.size());
    for (std::size_t v = 0; v < changed[i].positions.size(); ++v) {
      std::uint32_t o = origin[i][v];
      if (o == ~0u) {
        o = std::uint32_t(positions.size());
        positions.push_back(changed[i].positions[v]);
      } else {
        positions[o] = changed[i].positions[v];
      }
      index[v] = o;
    }
    for (const glm::uvec3& t : changed[i].triangles) triangles.push_back({index[t[0]], index[t[1]], index[t[2]]});
  }
  // Vertices collapsed away leave unused slots: compacted, keeping the order (a vertex moves
  // only down, onto a slot already read).
  std::vector<std::uint32_t> slot(positions.size(), ~0u);
  for (const glm::uvec3& t : triangles)
    for (int k = 0; k < 3; ++k) slot[t[k]] = 0;
  std::uint32_t used = 0;
  for (std::uint32_t v = 0; v < positions.size(); ++v)
    if (slot[v] != ~0u) slot[v] = used, positions[used++] = positions[v];
  positions.resize(used);
  for (glm::uvec3& t : triangles) t = {slot[t[0]], slot[t[1]], slot[t[2]]};
  if (renumber) renumber->assign(slot.begin(), slot.begin() + std::ptrdiff_t(old_count));
}

bool to_openmesh(const TriangleMesh& mesh, std::span<const std::uint8_t> locked, std::span<const std::uint32_t> origin,
                 TriMesh& m, OpenMesh::VPropHandleT<bool>& locked_prop, OpenMesh::VPropHandleT<std::uint32_t>& origin_prop) {
  m.request_vertex_status();
  m.request_edge_status();
  m.request_halfedge_status();
  m.request_face_status();
  m.add_property(locked_prop);
  m.add_property(origin_prop);
  // Room for every element up front (a closed mesh has 3/2 edges a face, a rim a few more):
  // the arrays and their properties do not grow and copy face by face.
  const std::size_t nf = mesh.triangles.size();
  m.reserve(mesh.positions.size(), nf + nf / 2 + mesh.positions.size() / 8, nf);
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    const glm::dvec3& p = mesh.positions[v];
    const auto h = m.add_vertex({p.x, p.y, p.z});
    m.property(locked_prop, h) = !locked.empty() && locked[v];
    m.property(origin_prop, h) = origin.empty() ? std::uint32_t(v) : origin[v];
  }
  if (link_manifold_triangles(m, mesh.triangles)) return true;
  for (const glm::uvec3& t : mesh.triangles)  // not a manifold: what add_face makes of it
    if (!m.add_face(TriMesh::VertexHandle(int(t[0])), TriMesh::VertexHandle(int(t[1])), TriMesh::VertexHandle(int(t[2])))
             .is_valid())
      return false;
  return true;
}

void from_openmesh(const TriMesh& m, OpenMesh::VPropHandleT<std::uint32_t> origin, TriangleMesh& out,
                   std::vector<std::uint32_t>& origins) {
  const std::vector<int> vertices =
      collected_order(int(m.n_vertices()), [&](int v) { return m.status(TriMesh::VertexHandle(v)).deleted(); });
  const std::vector<int> faces =
      collected_order(int(m.n_faces()), [&](int f) { return m.status(TriMesh::FaceHandle(f)).deleted(); });
  std::vector<std::uint32_t> index(m.n_vertices(), ~0u);
  out.positions.resize(vertices.size());
  origins.resize(vertices.size());
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    const TriMesh::VertexHandle v(vertices[i]);
    const auto& p = m.point(v);
    out.positions[i] = {p[0], p[1], p[2]};
    origins[i] = m.property(origin, v);
    index[std::size_t(vertices[i])] = std::uint32_t(i);
  }
  out.triangles.resize(faces.size());
  for (std::size_t i = 0; i < faces.size(); ++i) {
    int k = 0;
    for (const auto v : m.fv_range(TriMesh::FaceHandle(faces[i]))) out.triangles[i][k++] = index[std::size_t(v.idx())];
  }
}

std::vector<std::uint32_t> slab_of_vertices(const TriangleMesh& mesh, double thickness, std::size_t& count) {
  glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
  for (const glm::dvec3& p : mesh.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
  const glm::dvec3 size = hi - lo;
  const int axis = size.x >= size.y && size.x >= size.z ? 0 : size.y >= size.z ? 1 : 2;
  double d = thickness;
  const double span = std::floor(hi[axis] / d) - std::floor(lo[axis] / d) + 1.0;
  if (!(span <= double(kMaxSlabs))) d *= std::ceil(span / double(kMaxSlabs));
  const double first = std::floor(lo[axis] / d);
  std::vector<std::uint32_t> slab(mesh.positions.size());
  count = 1;
  for (std::size_t v = 0; v < slab.size(); ++v) {
    const double k = std::floor(mesh.positions[v][axis] / d) - first;
    slab[v] = std::uint32_t(k >= 0.0 ? std::min(k, double(kMaxSlabs)) : 0.0);  // NaN: slab 0
    count = std::max<std::size_t>(count, slab[v] + 1);
  }
  return slab;
}

std::vector<std::uint8_t> renumbered(std::span<const std::uint8_t> flags, std::span<const std::uint32_t> renumber,
                                     std::size_t size, std::uint8_t fresh) {
  std::vector<std::uint8_t> out(size, fresh);
  if (!flags.empty())
    for (std::size_t v = 0; v < renumber.size(); ++v)
      if (renumber[v] != ~0u) out[renumber[v]] = flags[v];
  return out;
}

}  // namespace ht
