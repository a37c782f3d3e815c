// Mesh output: .ply (binary) and .stl (binary, single precision by its format) through OpenMesh,
// .obj and .off (ASCII) written here with 17 significant digits from the doubles (OpenMesh's
// ASCII writers round to float), chosen by the file's extension. Writes are atomic: the mesh goes to a temporary
// file beside the target, which is renamed over it only when complete, so a failure never leaves
// a half-written file.
#pragma once

#include "meshers/triangle_mesh.hpp"

#include <filesystem>
#include <stdexcept>

namespace ht {

class TriMeshHolder;

struct MeshWriteError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Where a write to `file` lands: a symbolic link's final target, so that the rename replaces
/// the file and not the link, or the path itself. Throws MeshWriteError when that exists and is
/// not a regular file (a device such as /dev/full, a pipe): a rename over it would replace it
/// with a file (as root, /dev/full itself).
std::filesystem::path output_target(const std::filesystem::path& file);

/// True for the extensions write_mesh() accepts.
bool supported_mesh_extension(const std::filesystem::path& file);

/// Writes the mesh; throws MeshWriteError naming the file and the reason.
void write_mesh(const TriangleMesh& mesh, const std::filesystem::path& file);

/// The OpenMesh form of a mesh (shared vertices, the same triangle order).
void to_openmesh(const TriangleMesh& mesh, TriMeshHolder& out);

}  // namespace ht
