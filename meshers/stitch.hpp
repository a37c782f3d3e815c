// Stitching: the paper's crack fixing (section 3.2.3), done by conforming merge instead of
// bridging. The local strategies trim their operands' meshes along level sets
// (meshers/cut.hpp), so the open pieces they hand over have boundaries that lie on the same
// curves, sampled differently on each side. Stitching makes the samplings agree:
//   1. every boundary vertex finds the nearest point on another piece's boundary;
//   2. a vertex whose partner point is within a fraction of the local edge length of a
//      partner vertex is welded to it (union-find across pieces);
//   3. every other boundary vertex is inserted into its partner edge: the triangle that owns the
//      edge is split into a fan, so both sides end up with one polyline and no T-junction.
// Nothing but boundary vertices moves, and only onto a partner within `max_gap`: interior
// vertices keep their positions bit for bit. The paper's bridging fails where the facing edges'
// lengths differ; insertion does not care.
//
// The caller checks the result (meshers/mesh_checks.hpp): stitching does not promise a closed
// manifold when the pieces do not fit (a boundary with no partner raises StitchError).
#pragma once

#include "meshers/triangle_mesh.hpp"

#include <cstdint>
#include <span>
#include <stdexcept>
#include <vector>

namespace ht {

struct StitchOptions {
  /// A boundary vertex farther than this from every other piece's boundary fails the stitch.
  double max_gap = 0.0;
  /// ... or farther than this fraction of its partner edge's length, when that is more (a long
  /// chord of a coarse mesh may cut a curved seam short).
  double chord_fraction = 0.3;
  /// Weld a vertex to a partner vertex within this fraction of the shorter local boundary edge.
  double weld_fraction = 0.3;
  /// Move the vertices inserted into an earlier piece's edges onto that edge, so that the seam is
  /// the earlier piece's polyline exactly: needed where pieces meet almost tangentially (blends),
  /// where a zigzag between two samplings of one curve would fold triangles; not at creases.
  bool onto_earlier = true;
  /// Leave the boundary vertices that have no partner within max_gap on the boundary instead
  /// of failing (a seam that ends where the pieces part, to be closed by something else).
  bool allow_open = false;
};

struct StitchStats {
  std::size_t boundary_vertices = 0, welded = 0, inserted = 0, fans = 0, left_open = 0;
  double largest_gap = 0;  ///< the largest distance from a boundary vertex to its partner
};

struct StitchError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// One mesh from oriented pieces whose boundaries face each other. Earlier pieces win: a welded
/// vertex takes the position of its copy in the earliest piece. Deterministic; parallel over
/// boundary vertices.
/// With `seam`, receives one flag per output vertex: 1 on a seam (a piece's boundary).
TriangleMesh stitch(std::span<const TriangleMesh* const> pieces, const StitchOptions& options,
                    StitchStats* stats = nullptr, std::vector<std::uint8_t>* seam = nullptr);
/// The same, taking the pieces: each is freed as soon as it is copied in, so the peak memory
/// holds the pieces once instead of twice.
TriangleMesh stitch(std::vector<TriangleMesh>&& pieces, const StitchOptions& options,
                    StitchStats* stats = nullptr, std::vector<std::uint8_t>* seam = nullptr);

}  // namespace ht
