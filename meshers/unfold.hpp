// The last resort against folds: where triangles still intersect after the crease step and its
// untangling (meshers/relax.hpp), edges of the intersecting triangles collapse until none do.
//
// The folds left are slivers between crease points almost together that no edge joins (a crease
// through grid points, where two grid edges' crossings fall a hundredth of a cell apart), and
// pieces of three-sheet corners. Each intersecting triangle gives up its shortest edge that
// OpenMesh may collapse (is_collapse_ok) without turning a surviving face by more than 60
// degrees or leaving it degenerate; a crease point survives the collapse where one end is one,
// so the crease keeps its place. A round works on the intersecting triangles and one ring around
// them, taken out of the mesh (meshers/submesh.hpp); the next round searches again.
#pragma once

#include "meshers/batch_field.hpp"
#include "meshers/triangle_mesh.hpp"

#include <array>
#include <cstdint>
#include <vector>

namespace ht {

struct UnfoldStats {
  std::size_t pairs_before = 0;  ///< intersecting pairs found first
  std::size_t pairs_after = 0;   ///< intersecting pairs left
  std::size_t collapses = 0;
  int rounds = 0;
  double seconds = 0;  ///< wall time, searches included

  UnfoldStats& operator+=(const UnfoldStats& o) {
    pairs_before += o.pairs_before, pairs_after += o.pairs_after, collapses += o.collapses, rounds += o.rounds;
    seconds += o.seconds;
    return *this;
  }
};

/// Collapses edges of the intersecting triangles `pairs` (every intersecting pair of the mesh,
/// as untangle returns them: meshers/relax.hpp), then of those found again around what changed,
/// at most `rounds` rounds; a round that would leave more pairs than it found is undone.
/// `pairs` receives the pairs left. `crease` (one flag per vertex, may be empty) follows the renumbering.
/// The mesh stays closed, oriented and manifold; surviving vertices keep their order
/// (meshers/submesh.hpp put_back). Deterministic. Cost: a search around the changed vertices per
/// round (meshers/relax.hpp intersections_near) plus the region's work.
UnfoldStats unfold(TriangleMesh& mesh, std::vector<std::uint8_t>& crease,
                   std::vector<std::array<std::uint32_t, 2>>& pairs, int rounds = 4);

/// A folded triangle is within this many degrees of the outward normal at none of its corners.
inline constexpr double kFoldAgreeDegrees = 60.0;
/// Triangles folded over onto their neighbours: the normal points against the (area-weighted)
/// vertex normals at two or more of its corners and against the surface's outward normal at its
/// centre (`gradient`: the field grows inward), and it is within kFoldAgreeDegrees of the
/// outward normal at none of its corners. A sound triangle across a sharp crease lies along one
/// of the sheets it spans. Increasing order. Cost: one pass over the triangles, four gradients
/// a candidate.
std::vector<std::uint32_t> folded_triangles(const TriangleMesh& mesh, const BatchGradient& gradient);

/// Collapses an edge of each folded triangle (as unfold() does for intersecting ones, the same
/// rules: a crease point collapses only into another), for at most `rounds` rounds; a round that
/// leaves as many folded triangles as it found or makes triangles intersect is undone, and then,
/// when `may_widen`, the next may reach further (any edge at the corners, crease points too:
/// unfold()'s second rules). Where folds are still left, their corners a ring or more from crease
/// points relax toward their neighbours' centroid and back onto {f = T} (meshers/relax.hpp
/// relax_vertices), kept when that leaves fewer and crosses nothing and no triangle around them
/// is thinner than the thinnest was. Returns the collapses made, and in pairs_before /
/// pairs_after the folded triangles found and left (a relaxation kept shows only there).
/// `crease` as for unfold(). A closed, oriented manifold stays one.
UnfoldStats unfold_folded(TriangleMesh& mesh, std::vector<std::uint8_t>& crease, const BatchGradient& gradient, double T,
                          bool may_widen = true, int rounds = 4);

}  // namespace ht
