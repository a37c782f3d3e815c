// A region of a mesh taken out to be reworked on its own and put back: what the remeshing and
// quality passes do when only part of a mesh may change (a local strategy's seams and patches,
// while the operands' own triangles stay bit for bit).
#pragma once

#include "meshers/triangle_mesh.hpp"
#include "nodes/trimesh.hpp"

#include <cstdint>
#include <span>
#include <vector>

namespace ht {

struct Submesh {
  TriangleMesh mesh;                  ///< the triangles taken, their vertices numbered anew
  std::vector<std::uint32_t> origin;  ///< each taken vertex's index in the whole mesh
  /// Taken vertices that must stay: used by a triangle not taken too (or outside the region).
  std::vector<std::uint8_t> rim;
};

/// Disjoint parts of a mesh taken out at once, and the triangles no part took, in their order.
struct Pieces {
  std::vector<Submesh> parts;
  std::vector<glm::uvec3> rest;
};

/// Takes the triangles with a corner in `region` (one flag per vertex) as one part. Where the
/// taken triangles would touch themselves at a vertex (a pinch OpenMesh cannot hold), the whole
/// fan of that vertex is taken too. With `apart`, each connected piece of the taken triangles
/// (through shared vertices) is a part of its own, numbered by its first triangle, so that they
/// can be worked on in parallel.
Pieces take_region(const TriangleMesh& mesh, std::span<const std::uint8_t> region, bool apart = false);

/// Takes `count` parts: triangle t goes to part piece_of[t], or stays in `rest` when that is ~0u.
/// Where a part would touch itself at a vertex, its triangles at that vertex stay in `rest`.
Pieces take_pieces(const TriangleMesh& mesh, std::vector<std::uint32_t> piece_of, std::size_t count);

/// What take_pieces decides before it copies anything: each part's triangles (ascending), the
/// part using each vertex (~0u: only untaken triangles; ~1u: several) and the untaken triangles.
/// With it a part can be taken when its work starts (take_part), so that parts worked on one after
/// another are not all held at once.
struct PiecePlan {
  std::vector<std::vector<std::uint32_t>> of_part;
  std::vector<std::uint32_t> owner;
  std::vector<glm::uvec3> rest;
};
PiecePlan plan_pieces(const TriangleMesh& mesh, std::vector<std::uint32_t> piece_of, std::size_t count);

/// Part i of `plan`, as take_pieces makes it (its arrays sized exactly). `local` holds one entry
/// per vertex of `mesh`, all ~0u, and is left so (a scratch a thread may reuse for every part).
Submesh take_part(const TriangleMesh& mesh, const PiecePlan& plan, std::size_t i, std::vector<std::uint32_t>& local);

/// Puts the reworked parts back. changed[i] is part i after the work and origin[i] gives each of
/// its vertices' index in the whole mesh, or ~0u for a new vertex. Surviving vertices keep their
/// order, new ones follow in part order, unused ones are dropped; the untaken triangles come
/// first, then each part's. With `renumber`, receives each old vertex's new index (~0u: dropped).
/// The mesh's arrays are rebuilt in place: `rest` must not alias mesh.triangles.
void put_back(TriangleMesh& mesh, const Pieces& pieces, std::span<const TriangleMesh> changed,
              std::span<const std::vector<std::uint32_t>> origin, std::vector<std::uint32_t>* renumber = nullptr);
/// The same, given the untaken triangles.
void put_back(TriangleMesh& mesh, std::span<const glm::uvec3> rest, std::span<const TriangleMesh> changed,
              std::span<const std::vector<std::uint32_t>> origin, std::vector<std::uint32_t>* renumber = nullptr);

/// Each vertex's slab across the mesh's longest axis: slab k holds [k d, (k + 1) d) along it for
/// the thickness d, numbered from the lowest one used; `count` receives how many. Where the slabs
/// lie depends on d alone (an edit elsewhere does not move them); past kMaxSlabs, d is a whole
/// multiple thicker. A NaN coordinate goes to slab 0.
inline constexpr std::size_t kMaxSlabs = 4096;
std::vector<std::uint32_t> slab_of_vertices(const TriangleMesh& mesh, double thickness, std::size_t& count);

/// Per-vertex flags carried through put_back's `renumber` (old index -> new, ~0u: dropped) onto a
/// mesh of `size` vertices; vertices no old one became (made by the work) get `fresh`, and so
/// does every vertex when `flags` is empty.
std::vector<std::uint8_t> renumbered(std::span<const std::uint8_t> flags, std::span<const std::uint32_t> renumber,
                                     std::size_t size, std::uint8_t fresh = 0);

/// Loads `mesh` into an empty `m` for editing (vertex, edge, halfedge and face status requested,
/// as collapses and flips need): vertex v gets locked[v] (or false) and origin[v] (or v when
/// `origin` is empty) in the two properties, which it adds. False when OpenMesh refuses a face
/// (the mesh is not a manifold it can hold).
bool to_openmesh(const TriangleMesh& mesh, std::span<const std::uint8_t> locked, std::span<const std::uint32_t> origin,
                 TriMesh& m, OpenMesh::VPropHandleT<bool>& locked_prop, OpenMesh::VPropHandleT<std::uint32_t>& origin_prop);

/// A reworked OpenMesh region back in flat arrays: its vertices and triangles numbered as
/// `m.garbage_collection()` would number them (without collecting: `m` is left as it is), and each
/// vertex's `origin` property.
void from_openmesh(const TriMesh& m, OpenMesh::VPropHandleT<std::uint32_t> origin, TriangleMesh& out,
                   std::vector<std::uint32_t>& origins);

}  // namespace ht
