// The mesh every mesher returns: flat arrays, 32-bit indices, counter-clockwise triangles seen
// from outside. Conversion to OpenMesh lives in meshers/mesh_io.hpp.
#pragma once

#include <glm/vec3.hpp>

#include <vector>

namespace ht {

struct TriangleMesh {
  std::vector<glm::dvec3> positions;
  std::vector<glm::uvec3> triangles;
};

}  // namespace ht
