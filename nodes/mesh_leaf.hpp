// Mesh leaves: closed triangle meshes as skeletons of a compact-support field.
//
// A MeshLeaf is loaded once per file (MeshCache) and shared by every node that names it. It
// answers two questions, both without a loop over triangles:
//   - the distance dM(p) to the nearest triangle, through an Embree point query whose radius is
//     the caller's support radius (points farther away cost one BVH root test);
//   - whether p is inside the solid: from the angle-weighted pseudo-normal of the closest feature
//     when a triangle is within the radius (Baerentzen & Aanaes 2005), and by ray parity with a
//     majority over three rays otherwise.
// The field is the paper's pseudo-distance (section 3.1.2), exactly as SCENE_FORMAT.md defines it.
#pragma once

#include "meshers/triangle_mesh.hpp"
#include "runtime/aabb.hpp"

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

namespace ht {

class TriMeshHolder;  // the OpenMesh mesh, see nodes/trimesh.hpp

/// Thrown when a mesh cannot be used; what() says what is wrong and where (file, counts).
struct MeshError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// What loading found and changed. A mesh whose faces all point inward is the same solid: it
/// is flipped and `inverted` says so.
struct MeshReport {
  std::size_t input_faces = 0;       ///< faces as read (polygons count once)
  std::size_t vertices = 0;
  std::size_t triangles = 0;
  std::size_t components = 0;        ///< closed connected shells
  bool inverted = false;             ///< every face pointed inward; flipped on load
  std::size_t reoriented_faces = 0;  ///< faces flipped to make each shell consistent (0 normally)
  std::size_t holes_closed = 0;      ///< only with repair
  std::size_t triangles_added = 0;   ///< only with repair
};

class MeshLeaf {
 public:
  /// Reads OFF, OBJ, PLY or STL (OFF itself, the others through OpenMesh) and validates it: at
  /// least one triangle, finite coordinates within 1e18, no open or non-manifold edges (unless
  /// `repair`, which closes holes of up to 64 boundary edges and reports it). Throws MeshError.
  static std::shared_ptr<const MeshLeaf> load(const std::filesystem::path& file, bool repair = false);

  /// The same validation on triangles given in memory (tests, and the ffd node's deformed mesh).
  /// `name` is used in error messages.
  static std::shared_ptr<const MeshLeaf> from_triangles(std::vector<glm::dvec3> positions,
                                                        std::vector<glm::uvec3> triangles,
                                                        std::string name, bool repair = false);
  ~MeshLeaf();
  MeshLeaf(const MeshLeaf&) = delete;
  MeshLeaf& operator=(const MeshLeaf&) = delete;

  struct Closest {
    double distance;  ///< dM(p), or +infinity when no triangle lies within the radius
    bool inside;      ///< p is inside the solid (exact for any p, whatever the radius)
    glm::dvec3 point{0.0};  ///< the nearest point on the mesh, when distance is finite
  };
  /// Distance to the nearest triangle if it is closer than `radius`, and the inside test.
  Closest query(const glm::dvec3& p, double radius) const;
  /// Inside test alone.
  bool inside(const glm::dvec3& p) const;
  /// Batched form of query() for float lanes: n points as three coordinate arrays; writes
  /// distance[i] (+infinity beyond radius) and inside[i] (0/1). Thread-safe; no allocation.
  void query_batch(const float* xs, const float* ys, const float* zs, std::size_t n, float radius,
                   float* distance, std::uint8_t* inside) const;

  const std::vector<glm::dvec3>& positions() const { return surface_->positions; }
  const std::vector<glm::uvec3>& triangles() const { return surface_->triangles; }  ///< oriented outward
  /// The mesh itself, shared: what a mesh leaf answers when asked for its mesh (never copied).
  std::shared_ptr<const TriangleMesh> surface() const { return surface_; }
  const Aabb& bounds() const { return bounds_; }
  const MeshReport& report() const { return report_; }
  const std::string& name() const { return name_; }
  /// Bytes held: vertex and index arrays, pseudo-normals and the Embree BVH estimate.
  std::size_t bytes() const;
  /// The OpenMesh form (nodes/trimesh.hpp), built on first use and shared.
  const class TriMeshHolder& openmesh() const;

 private:
  MeshLeaf() = default;
  /// Validation, orientation, repair and acceleration shared by load() and from_triangles().
  static std::shared_ptr<const MeshLeaf> build(std::vector<glm::dvec3> positions,
                                               std::vector<glm::uvec3> triangles, std::size_t input_faces,
                                               std::string name, bool repair);
  /// query() for a point past the range Embree handles (nodes/mesh_leaf.cpp kMaxCoordinate).
  Closest far_query(const glm::dvec3& p, double radius) const;
  struct Accel;  // Embree device, scene and pseudo-normals
  std::string name_;
  std::shared_ptr<TriangleMesh> surface_ = std::make_shared<TriangleMesh>();
  Aabb bounds_;
  MeshReport report_;
  std::unique_ptr<Accel> accel_;
  mutable std::once_flag openmesh_once_;
  mutable std::unique_ptr<TriMeshHolder> openmesh_;
};

/// The scene format's pseudo-distance field parameters for a mesh leaf (|F| > T required).
struct MeshFieldParams {
  double R = 0, F = 0, T = 0;
  double kernel_radius = 0;  ///< R' = R / (1 - c)
  double r0 = 0;             ///< c * R'
  double query_radius = 0;   ///< max(R, r0): beyond it f is 0 outside and F inside
};
MeshFieldParams mesh_field_params(double R, double F, double T);

/// f(p) exactly as SCENE_FORMAT.md defines it for a mesh leaf.
double mesh_field(const MeshLeaf& mesh, const MeshFieldParams& params, const glm::dvec3& p);

/// Loads each file once, however many nodes name it. Keyed by canonical path and repair flag.
class MeshCache {
 public:
  std::shared_ptr<const MeshLeaf> get(const std::filesystem::path& file, bool repair);
  std::size_t size() const { return meshes_.size(); }

 private:
  std::unordered_map<std::string, std::shared_ptr<const MeshLeaf>> meshes_;
};

}  // namespace ht
