// Bridging: the paper's crack fixing (section 3.2.3), for seams where two pieces meet smoothly
// (blends). The operands' meshes are trimmed exactly (meshers/cut.hpp); the patch that the
// polygonizer made of the blend is trimmed at the same level set and then pulled back by one
// ring of triangles, so that a band about one patch triangle wide separates every operand loop
// from a patch loop. Each pair of facing loops is joined by a strip of triangles that advances
// along whichever loop gives the shorter diagonal (Fuchs, Kedem & Uselton's greedy contour
// stitching). Unlike welding two samplings of one curve, a band tolerates the patch's chords
// deviating from the exact operand by more than its triangles' height.
//
// Every vertex of every piece is kept bit for bit; the band adds triangles only (and one vertex
// for each speck of the cut it closes, below).
#pragma once

#include "meshers/triangle_mesh.hpp"

#include <cstdint>
#include <span>
#include <stdexcept>
#include <vector>

namespace ht {

struct BridgeError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct BridgeStats {
  std::size_t loops = 0;             ///< pairs of loops bridged
  std::size_t holes_closed = 0;      ///< small patch loops that faced no operand loop, closed by a fan
  std::size_t band_triangles = 0;
  double widest = 0;                 ///< the longest band edge
};

/// The boundary loops of an oriented mesh, each in the direction its triangles run along it.
/// Throws BridgeError where the boundary touches itself at a vertex.
std::vector<std::vector<std::uint32_t>> boundary_loops(const TriangleMesh& mesh);

/// Removes the fans of the vertices where the boundary touches itself (two boundary edges leave
/// them), round after round (at most 8) until none is left: what bridge() cannot pair, a few
/// triangles nearer the band. Returns whether any went;
/// `renumber` (if given) receives each old vertex's new index, ~0u for those removed.
bool drop_pinched_fans(TriangleMesh& mesh, std::vector<std::uint32_t>* renumber = nullptr);

/// The mesh without the triangles that touch its boundary (one ring pulled back), unused
/// vertices removed; then without the pieces left with no vertex off their boundary (a lone
/// triangle whose neighbours all went). A closed mesh is returned unchanged.
TriangleMesh pull_back_boundary(const TriangleMesh& mesh);

/// Joins the operands' pieces and the patch: every boundary loop of an operand piece is bridged
/// to the patch loop that faces it (each patch loop to at most one operand loop). A patch loop
/// that no operand loop faces, shorter than max_width / 4 and a hole in a piece that has a loop
/// an operand loop faces, is a speck of the cut: it is closed by a fan (around a new vertex at its centroid when
/// longer than three edges, which the caller puts on the surface). Throws BridgeError when the
/// loops do not pair up so or a band would be wider than `max_width`.
/// Parallel over loop pairs; deterministic.
/// The result's vertices are the operands' in order, then the patch's: `patch_begin` (if given)
/// receives the index of the patch's first vertex.
TriangleMesh bridge(std::span<const TriangleMesh* const> operands, const TriangleMesh& patch, double max_width,
                    BridgeStats* stats = nullptr, std::uint32_t* patch_begin = nullptr);

}  // namespace ht
