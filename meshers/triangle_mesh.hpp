// The mesh every mesher returns: flat arrays, 32-bit indices, counter-clockwise triangles seen
// from outside. Conversion to OpenMesh lives in meshers/mesh_io.hpp.
#pragma once

#include <glm/vec3.hpp>

#include <cstdint>
#include <vector>

namespace ht {

struct TriangleMesh {
  std::vector<glm::dvec3> positions;
  std::vector<glm::uvec3> triangles;
};

/// Appends `from`'s vertices and triangles to `to`, renumbered; returns the index of `from`'s
/// first vertex in `to`.
inline std::uint32_t append(TriangleMesh& to, const TriangleMesh& from) {
  const auto base = static_cast<std::uint32_t>(to.positions.size());
  to.positions.insert(to.positions.end(), from.positions.begin(), from.positions.end());
  to.triangles.reserve(to.triangles.size() + from.triangles.size());
  for (const glm::uvec3& t : from.triangles) to.triangles.push_back(t + glm::uvec3(base));
  return base;
}

}  // namespace ht
