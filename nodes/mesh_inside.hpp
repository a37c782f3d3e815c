// How a mesh leaf decides "inside" (SCENE_FORMAT.md, the mesh leaf's "inside" key), and how a
// mesh file is asked for: their own header, so the builder's interface can name them without the
// mesh leaf's.
#pragma once

#include <cstdint>
#include <filesystem>

namespace ht {

enum class MeshInside : std::uint8_t {
  Closed,   ///< a closed, manifold mesh is required; inside by pseudo-normals and ray parity
  Winding,  ///< any triangles; inside where the generalized winding number exceeds 1/2
};
inline const char* to_string(MeshInside m) { return m == MeshInside::Closed ? "closed" : "winding"; }

/// A mesh file as a mesh leaf reads it (MeshLeaf::load's arguments).
struct MeshFileRequest {
  std::filesystem::path file;
  bool repair = false;
  MeshInside inside = MeshInside::Closed;
};

}  // namespace ht
