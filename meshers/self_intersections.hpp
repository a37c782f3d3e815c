// Self-intersections: the pairs of triangles of a mesh that meet where the mesh's connectivity
// says they should not. Candidate pairs are the triangles whose bounding boxes overlap, from a
// uniform grid when the triangles are of a size (meshers/box_pairs.hpp), else from Embree's
// rtcCollide over the boxes; each candidate is decided by exact geometric predicates, so the
// answer does not depend on rounding, thread count or triangle order (beyond the numbering of the
// output).
//
// What counts, for two non-degenerate triangles A and B (closed point sets):
//   share no vertex     A and B share any point (crossing, touching, a T-junction, coplanar
//                       overlap)
//   share one vertex v  A and B share a point other than v
//   share an edge       A and B overlap beyond the edge: they are coplanar and lie on the same
//                       side of it (a fold). Non-coplanar triangles on an edge meet only on it.
//   share all three     a duplicate face: always counts
// Vertices are shared when they have the same index or equal positions (all three coordinates
// compare equal), so soups and meshes with duplicated vertices are judged by geometry.
// Degenerate triangles (exactly zero area: collinear or coincident corners) take part in no
// pair; check_mesh() counts them. Its count uses a tolerance, so near-degenerate slivers it
// counts are still tested here, exactly.
//
// Pairs that share a vertex whose fan is certified embedded (meshers/embedded_fans.hpp: a
// projection of the fan that tiles a star around it, with a margin far above rounding) meet only
// where their connectivity says: they take no test. On a well-shaped closed mesh that is 99% of
// the candidates.
//
// Exactness: orientation tests are evaluated in double with a static error bound and, when the
// bound cannot decide the sign, recomputed exactly with floating-point expansion arithmetic
// (over the coordinate differences when those are exact, as for nearby vertices, else over the
// coordinates). Exact zeros that are common in meshes are decided without expansions: a point
// against a triangle lying in a coordinate plane is one comparison, and a determinant whose
// terms all have a zero factor is zero. Pairs sharing a vertex or an edge, and coplanar pairs,
// take a few orientation tests each (a wedge test at a shared corner, separating edge lines).
// The result is exact for finite coordinates whose products of three neither overflow nor
// underflow (magnitudes roughly within [1e-100, 1e100], or zero).
#pragma once

#include "meshers/triangle_mesh.hpp"

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace ht {

struct SelfIntersections {
  std::size_t pairs = 0;  ///< intersecting triangle pairs, each unordered pair once
  /// The first max_examples intersecting pairs as {i, j} with i < j, in increasing (i, j) order:
  /// the same for every run and thread count.
  std::vector<std::array<std::uint32_t, 2>> examples;
};

/// Finds the pairs of triangles of `mesh` whose closed point sets intersect beyond what their
/// shared vertices or edge imply (see the rules at the top of this file).
///
/// Indices must be valid and positions finite. Complexity: O(n + v) for the fans and the grid (O(n log n) for the
/// box hierarchy where the grid declines) plus O(k) exact tests for the k pairs of triangles
/// whose bounding boxes overlap (for a reasonable surface mesh k is a small multiple of n). Uses
/// the TBB thread pool (the grid's or Embree's pair search and a parallel loop over the
/// candidates); memory O(n + k). Thread safety: reads
/// `mesh` only, keeps no state; concurrent calls are safe. Throws std::runtime_error when Embree
/// cannot create its device or build its hierarchy.
SelfIntersections find_self_intersections(const TriangleMesh& mesh, std::size_t max_examples = 16);

/// The exact test find_self_intersections() applies to one candidate pair: true when triangles
/// `a` and `b` of `mesh` intersect by the rules above. False when a == b or either is degenerate.
/// O(1); thread-safe. Exposed for tests and for checking single pairs.
bool triangles_intersect(const TriangleMesh& mesh, std::uint32_t a, std::uint32_t b);

}  // namespace ht
