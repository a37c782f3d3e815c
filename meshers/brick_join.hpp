// Joining a polygonization's bricks (meshers/polygonize.cpp): the bricks' vertices on shared
// grid edges become one vertex each, and their triangles one mesh.
#pragma once

#include "meshers/brick_extract.hpp"
#include "meshers/triangle_mesh.hpp"

#include <vector>

namespace ht::brick {

/// One vertex per edge key across bricks (the lowest brick's copy, among those with a normal if
/// any has one), numbered in key order; the bricks' triangles renumbered into `mesh`, brick by
/// brick. Returns the vertices kept, in mesh order. Consumes `outputs` (the bricks' vertices are
/// let go once the kept ones are copied, each brick's triangles once renumbered, so that they and
/// the mesh are not all held at the peak of a polygonization) and leaves it empty. The same at any thread count; parallel inside.
std::vector<EdgeVertex> join_bricks(std::vector<BrickOutput>&& outputs, TriangleMesh& mesh);

}  // namespace ht::brick
