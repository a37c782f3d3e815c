#include "meshers/mesh_io.hpp"

#include "meshers/openmesh_link.hpp"
#include "nodes/openmesh_io.hpp"
#include "nodes/trimesh.hpp"

#include <OpenMesh/Core/IO/MeshIO.hh>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <mutex>
#include <random>
#include <string>
#include <system_error>

namespace ht {

namespace {
std::string lower_extension(const std::filesystem::path& file) {
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return char(std::tolower(ch)); });
  return ext;
}
}  // namespace

bool supported_mesh_extension(const std::filesystem::path& file) {
  const std::string ext = lower_extension(file);
  return ext == ".ply" || ext == ".obj" || ext == ".off" || ext == ".stl";
}

void to_openmesh(const TriangleMesh& mesh, TriMeshHolder& out) {
  TriMesh& m = out.mesh;
  m.clear();
  m.reserve(mesh.positions.size(), 3 * mesh.triangles.size() / 2, mesh.triangles.size());
  std::vector<TriMesh::VertexHandle> vh;
  vh.reserve(mesh.positions.size());
  for (const auto& p : mesh.positions) vh.push_back(m.add_vertex(TriMesh::Point(p.x, p.y, p.z)));
  // A manifold (every mesh the mesher returns) is linked in bulk, as add_face would link it
  // (meshers/openmesh_link.hpp; add_face cost 2,800 instructions a face in Debian's build); what
  // is not goes face by face, add_face keeping what OpenMesh can hold.
  if (link_manifold_triangles(m, mesh.triangles)) return;
  for (const auto& t : mesh.triangles) m.add_face(vh[t[0]], vh[t[1]], vh[t[2]]);
}

namespace {

// OFF or OBJ from the doubles themselves, each coordinate in the 17 significant digits that read
// back to the same bits: OpenMesh's ASCII writers go through float vertices (about 8 digits), so
// a mesh leaf's exact surface came out moved by up to 3e-8 of its size. False on any write error.
bool write_text(const TriangleMesh& mesh, const std::filesystem::path& file, bool off) {
  std::FILE* f = std::fopen(file.c_str(), "wb");
  if (!f) return false;
  bool ok = !off || std::fprintf(f, "OFF\n%zu %zu 0\n", mesh.positions.size(), mesh.triangles.size()) > 0;
  const char* vertex = off ? "%.17g %.17g %.17g\n" : "v %.17g %.17g %.17g\n";
  for (std::size_t i = 0; ok && i < mesh.positions.size(); ++i)
    ok = std::fprintf(f, vertex, mesh.positions[i].x, mesh.positions[i].y, mesh.positions[i].z) > 0;
  const unsigned base = off ? 0u : 1u;  // OBJ counts from 1
  const char* face = off ? "3 %u %u %u\n" : "f %u %u %u\n";
  for (std::size_t i = 0; ok && i < mesh.triangles.size(); ++i) {
    const glm::uvec3& t = mesh.triangles[i];
    ok = std::fprintf(f, face, t[0] + base, t[1] + base, t[2] + base) > 0;
  }
  ok = ok && std::fflush(f) == 0 && !std::ferror(f);
  return std::fclose(f) == 0 && ok;
}

}  // namespace

std::filesystem::path output_target(const std::filesystem::path& file) {
  std::error_code ec;
  // What the path names, links followed as the kernel follows them: /dev/stdout and
  // /proc/self/fd/N name a pipe through links whose text ("pipe:[N]") is no path.
  const auto named = std::filesystem::status(file, ec);
  if (std::filesystem::exists(named) && !std::filesystem::is_regular_file(named) && !std::filesystem::is_directory(named))
    throw MeshWriteError(file.string() + ": is not a regular file (a device or a pipe); write to a file");
  std::filesystem::path target = file;
  // Link by link (a dangling link's target is to be made): at most 40, as the kernel allows.
  for (int hops = 0; std::filesystem::is_symlink(std::filesystem::symlink_status(target, ec)); ++hops) {
    const std::filesystem::path next = std::filesystem::read_symlink(target, ec);
    if (ec || hops == 40) throw MeshWriteError(file.string() + ": cannot follow the link" + (ec ? ": " + ec.message() : ""));
    target = next.is_absolute() ? next : target.parent_path() / next;
  }
  const auto st = std::filesystem::status(target, ec);
  if (std::filesystem::exists(st) && !std::filesystem::is_regular_file(st) && !std::filesystem::is_directory(st))
    throw MeshWriteError(file.string() + ": is not a regular file (a device or a pipe); write to a file");
  return target;
}

void write_mesh(const TriangleMesh& mesh, const std::filesystem::path& requested) {
  // The format is the requested name's; a link only says where the file goes.
  if (!supported_mesh_extension(requested))
    throw MeshWriteError(requested.string() + ": unsupported extension (use .ply, .obj, .off or .stl)");
  const std::filesystem::path file = output_target(requested);
  const std::filesystem::path dir = file.parent_path().empty() ? std::filesystem::path(".") : file.parent_path();
  if (!std::filesystem::is_directory(dir)) throw MeshWriteError(file.string() + ": folder " + dir.string() + " does not exist");
  if (std::filesystem::is_directory(file)) throw MeshWriteError(file.string() + ": is a folder, not a file");
  TriMeshHolder holder;
  to_openmesh(mesh, holder);
  if (holder.mesh.n_faces() != mesh.triangles.size())
    throw MeshWriteError(file.string() + ": the mesh is not a manifold OpenMesh can hold (" +
                         std::to_string(mesh.triangles.size() - holder.mesh.n_faces()) + " faces rejected)");
  const std::string ext = lower_extension(requested);
  OpenMesh::IO::Options options;
  if (ext == ".ply" || ext == ".stl") options += OpenMesh::IO::Options::Binary;
  std::random_device rd;
  const std::filesystem::path tmp = dir / (file.stem().string() + ".partial-" + std::to_string(rd()) + ext);
  bool ok;
  if (ext == ".off" || ext == ".obj") {
    ok = write_text(mesh, tmp, ext == ".off");
  } else {
    // The same lock as MeshLeaf::load's reads: OpenMesh's IO registry is process-wide.
    QuietOpenMesh quiet;
    ok = OpenMesh::IO::write_mesh(holder.mesh, tmp.string(), options, 17);
  }
  std::error_code ec;
  if (!ok) {
    std::filesystem::remove(tmp, ec);
    throw MeshWriteError(file.string() + ": cannot write (disk full, or no permission?)");
  }
  std::filesystem::rename(tmp, file, ec);
  if (ec) {
    const std::string why = ec.message();  // before remove() reuses ec
    std::filesystem::remove(tmp, ec);
    throw MeshWriteError(file.string() + ": cannot move the finished file into place: " + why);
  }
}

}  // namespace ht
