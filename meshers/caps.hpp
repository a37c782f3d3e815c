// Planar caps: closing the openings that a box leaves in a mesh it cuts (the crop's local
// strategy, the paper's wings cut out of the Victory; the crop cuts one face's plane at a time
// and caps after each). Every boundary loop of the cut mesh lies on one face of the box; each is
// closed by a triangulation of the polygon it bounds in that plane: ear clipping, then Lawson
// edge flips to the constrained Delaunay triangulation, then interior edges split at their
// midpoints and flipped again, down to a size. The caps use the loops' own vertices, so the
// seam is exact and the crease along it stays sharp; loop vertices are set onto their plane.
#pragma once

#include "meshers/triangle_mesh.hpp"
#include "runtime/aabb.hpp"

#include <stdexcept>

namespace ht {

struct CapError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct CapStats {
  std::size_t loops = 0, triangles = 0, flips = 0;
};

/// Closes `mesh` (an oriented mesh whose boundary loops lie on the faces of `box`, within
/// `tolerance`) with planar caps facing out of the box. With max_edge > 0, the caps' interior
/// edges longer than that are split at their midpoints (new vertices in the plane) and flipped
/// back to Delaunay, so a cap is made of triangles of about the mesh's own size. Throws CapError when a loop leaves its
/// face (a cap across an edge of the box), when a face's loops nest (a cap with a hole), or when
/// a loop is not a simple polygon.
void cap_box_openings(TriangleMesh& mesh, const Aabb& box, double tolerance, double max_edge = 0.0,
                      CapStats* stats = nullptr);

}  // namespace ht
