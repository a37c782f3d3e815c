// Mesh leaves: triangle meshes as skeletons of a compact-support field.
//
// A MeshLeaf is loaded once per file (MeshCache) and shared by every node that names it. It
// answers two questions, both without a loop over triangles:
//   - the distance dM(p) to the nearest triangle, through an Embree point query whose radius is
//     the caller's support radius (points farther away cost one BVH root test);
//   - whether p is inside the solid. For a closed mesh (MeshInside::Closed, the default): from the
//     angle-weighted pseudo-normal of the closest feature when a triangle is within the radius
//     (Baerentzen & Aanaes 2005), and by ray parity with a majority over three rays otherwise.
//     For MeshInside::Winding (open, non-manifold, self-intersecting meshes): generalized winding
//     number > 1/2 (nodes/winding.hpp), decided exactly; the distance part is the same.
// The field is the paper's pseudo-distance (section 3.1.2), exactly as SCENE_FORMAT.md defines it.
#pragma once

#include "meshers/triangle_mesh.hpp"
#include "nodes/mesh_inside.hpp"
#include "runtime/aabb.hpp"

#include <glm/vec3.hpp>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <span>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

namespace ht {

class TriMeshHolder;  // the OpenMesh mesh, see nodes/trimesh.hpp
class WindingTree;    // nodes/winding.hpp

/// Thrown when a mesh cannot be used; what() says what is wrong and where (file, counts).
struct MeshError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// What loading found and changed. A mesh whose faces all point inward is the same solid: it
/// is flipped and `inverted` says so. The defect counts are of the mesh as read (a closed leaf
/// is refused when any of boundary_edges, nonmanifold_edges, intersecting_shells is nonzero,
/// unless repair closes its holes); a winding leaf keeps them all and reports them.
struct MeshReport {
  MeshInside inside = MeshInside::Closed;
  std::size_t boundary_edges = 0;      ///< edges with one face
  std::size_t holes = 0;               ///< boundary loops (connected sets of boundary edges)
  std::size_t nonmanifold_edges = 0;   ///< edges with more than two faces
  std::size_t duplicate_vertices = 0;  ///< vertices at the position of an earlier one
  std::size_t intersecting_shells = 0; ///< pairs of shells that cross (checked for closed leaves)
  std::size_t pinched_vertices = 0;    ///< closed leaves: vertices where shells touch (fans sharing no edge)
  std::size_t input_faces = 0;       ///< faces as read (polygons count once)
  std::size_t vertices = 0;
  std::size_t triangles = 0;
  std::size_t components = 0;        ///< edge-connected shells (closed ones for a closed leaf)
  bool inverted = false;             ///< every face pointed inward; flipped on load
  std::size_t reoriented_faces = 0;  ///< faces flipped to make each shell consistent (0 normally;
                                     ///< a winding leaf keeps each shell's majority orientation)
  std::size_t holes_closed = 0;      ///< only with repair
  std::size_t triangles_added = 0;   ///< only with repair
};

class MeshLeaf {
 public:
  /// Reads OFF, OBJ, PLY or STL (OFF and OBJ itself, PLY and STL through OpenMesh after checking
  /// their headers and records) and validates it: at least one triangle, finite coordinates
  /// within 1e18, valid indices; for MeshInside::Closed also no open or non-manifold
  /// edges (unless `repair`, which closes holes of up to 64 boundary edges and reports it) and
  /// no crossing shells. MeshInside::Winding takes the triangles as they are (each shell made
  /// consistent with its majority orientation) and reports the defects; `repair` must be false
  /// then. Throws MeshError naming the defect.
  static std::shared_ptr<const MeshLeaf> load(const std::filesystem::path& file, bool repair = false,
                                              MeshInside inside = MeshInside::Closed);

  /// The same validation on triangles given in memory (tests, and the ffd node's deformed mesh).
  /// `name` is used in error messages. `intersection_free`: the caller has searched the triangles
  /// and no two intersect (the ffd node does, to unfold its folds), so the search for crossing
  /// shells, which would find nothing, is not made again.
  static std::shared_ptr<const MeshLeaf> from_triangles(std::vector<glm::dvec3> positions,
                                                        std::vector<glm::uvec3> triangles,
                                                        std::string name, bool repair = false,
                                                        MeshInside inside = MeshInside::Closed,
                                                        bool intersection_free = false);
  ~MeshLeaf();
  MeshLeaf(const MeshLeaf&) = delete;
  MeshLeaf& operator=(const MeshLeaf&) = delete;

  struct Closest {
    double distance;  ///< dM(p), or +infinity when no triangle lies within the radius
    bool inside;      ///< p is inside the solid (exact for any p, whatever the radius)
    glm::dvec3 point{0.0};  ///< the nearest point on the mesh, when distance is finite
    /// When distance is finite: the unit outward angle-weighted pseudo-normal of the feature
    /// (face, edge or vertex) the nearest point lies on (Baerentzen & Aanaes 2005); within
    /// surface_band() of the mesh, of the feature it lies on within the band (a vertex before
    /// an edge before a face). Never zero (a degenerate feature falls back to a neighbouring
    /// face's normal).
    glm::dvec3 normal{0.0};
  };
  /// Distance to the nearest triangle if it is closer than `radius`, and the inside test.
  /// `bound`, when given, is a distance the nearest triangle is known to lie within (the distance
  /// from p to a neighbouring point's nearest point): the search starts there instead of at
  /// `radius`, which only saves work; the answer is the same. `side_if_none`, when 0 (outside) or
  /// 1 (inside), is p's side as the caller knows it should no triangle lie within the radius: a
  /// neighbour within half the radius found none either and was on that side (a closed surface
  /// does not cross the empty ball around it); it spares the rays, and a winding leaf ignores it.
  Closest query(const glm::dvec3& p, double radius, double bound = std::numeric_limits<double>::infinity(),
                int side_if_none = -1) const;
  /// query() over a run of neighbouring points taken in order (a block's, a brick's): each
  /// point's search is bounded by the previous point's nearest point, and a point that finds no
  /// triangle within the radius passes its side to the next within half the radius. Answers are
  /// query(p, radius)'s, bit for bit. Holds a reference to the leaf; one per thread and run.
  class Neighbours {
   public:
    Neighbours(const MeshLeaf& leaf, double radius) : leaf_(leaf), radius_(radius) {}
    Closest next(const glm::dvec3& p);

   private:
    const MeshLeaf& leaf_;
    double radius_;
    glm::dvec3 last_{0.0}, far_at_{0.0};  // the previous point's nearest point; the previous point
    bool have_last_ = false;
    int far_side_ = -1;  // the previous point's side when it found no triangle, else -1
  };
  /// Inside test alone.
  bool inside(const glm::dvec3& p) const;
  /// For a winding leaf: +1 when every point of the box is inside, 0 when none is, -1 when that
  /// is not certified (nodes/winding.hpp WindingTree::box_side; outside the mesh's box is
  /// outside). For a closed leaf -1 always (its callers use query() there). Thread-safe.
  int box_side(const Aabb& box) const;
  MeshInside inside_mode() const { return report_.inside; }
  /// For a winding leaf, the generalized winding number at p to within `tolerance`
  /// (nodes/winding.hpp WindingTree::estimate); NaN for a closed leaf. Thread-safe.
  double winding_number(const glm::dvec3& p, double tolerance) const;
  /// Batched form of query() for float lanes: n points as three coordinate arrays; writes
  /// distance[i] (+infinity beyond radius) and inside[i] (0/1). Thread-safe; no allocation.
  /// A block of points (a polygonizer brick's) farther than the radius from the surface costs
  /// one query and one inside test, not one each (closed leaves).
  void query_batch(const float* xs, const float* ys, const float* zs, std::size_t n, float radius,
                   float* distance, std::uint8_t* inside) const;

  const std::vector<glm::dvec3>& positions() const { return surface_->positions; }
  const std::vector<glm::uvec3>& triangles() const { return surface_->triangles; }  ///< oriented outward
  /// The mesh itself, shared: what a mesh leaf answers when asked for its mesh (never copied).
  /// For a winding leaf this is the input, not the surface of its solid (open, maybe crossing):
  /// the mesh plan polygonizes such a leaf instead.
  std::shared_ptr<const TriangleMesh> surface() const { return surface_; }
  /// surface() as a manifold, for output: the same triangles in the same order, with each fan of
  /// faces after the first at a vertex where shells touch (MeshReport::pinched_vertices) on a copy
  /// of that vertex appended after the others. surface() itself when there is none.
  std::shared_ptr<const TriangleMesh> manifold_surface() const { return manifold_ ? manifold_ : surface_; }
  const Aabb& bounds() const { return bounds_; }
  /// Points nearer to the mesh than this (world units) count as on it for gradients: there the
  /// gradient follows Closest::normal, the one-sided limit from outside, instead of the
  /// direction from the nearest point, which float rounding makes meaningless so close.
  /// kSurfaceBand times the largest coordinate magnitude of the mesh.
  double surface_band() const { return surface_band_; }
  static constexpr double kSurfaceBand = 1e-5;
  const MeshReport& report() const { return report_; }
  const std::string& name() const { return name_; }
  /// The file load() read (as it was named to load(): relative paths are relative to the
  /// working folder then), and whether repair was asked for; empty for meshes made in memory.
  /// What a scene writer names (runtime/scene_write.hpp).
  const std::filesystem::path& file() const { return file_; }
  bool repair_requested() const { return repair_requested_; }
  /// Bytes held: vertex and index arrays, pseudo-normals and the Embree BVH estimate.
  std::size_t bytes() const;
  /// The OpenMesh form (nodes/trimesh.hpp), built on first use and shared.
  const class TriMeshHolder& openmesh() const;

 private:
  MeshLeaf() = default;
  /// Validation, orientation, repair and acceleration shared by load() and from_triangles().
  static std::shared_ptr<MeshLeaf> build(std::vector<glm::dvec3> positions,
                                               std::vector<glm::uvec3> triangles, std::size_t input_faces,
                                               std::string name, bool repair, MeshInside inside,
                                               bool intersection_free = false);
  /// query_batch's shared answer for a block the surface's radius does not reach; false when it
  /// does (then every point is queried).
  bool shared_far_block(const float* xs, const float* ys, const float* zs, std::size_t n, float radius,
                        float* distance, std::uint8_t* inside) const;
  /// query() for a point past the range Embree handles (nodes/mesh_internal.hpp kMaxCoordinate).
  Closest far_query(const glm::dvec3& p, double radius) const;
  struct Accel;  // Embree device, scene and pseudo-normals
  std::string name_;
  std::filesystem::path file_;
  bool repair_requested_ = false;
  std::shared_ptr<TriangleMesh> surface_ = std::make_shared<TriangleMesh>();
  std::shared_ptr<const TriangleMesh> manifold_;  ///< with MeshReport::pinched_vertices > 0 only
  Aabb bounds_;
  double surface_band_ = 0;
  MeshReport report_;
  std::unique_ptr<Accel> accel_;
  std::unique_ptr<WindingTree> winding_;  // winding leaves only
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

/// The gradient of the pseudo-distance d(p) (SCENE_FORMAT.md) from a query's answer at p:
/// (p - nearest) / dM outside, its opposite inside, and within `band` of the mesh
/// (MeshLeaf::surface_band()) the unit outward pseudo-normal of the nearest feature, the
/// one-sided limit from outside (exactly on the mesh d = r0 and the outside formula holds).
/// Unit length wherever dM is finite; zero when it is not (d constant there).
glm::dvec3 pseudo_distance_gradient(const MeshLeaf::Closest& c, const glm::dvec3& p, double band);

struct MeshFieldSample {
  double value = 0;
  glm::dvec3 gradient{0.0};
};
/// f(p) and its exact gradient: f'(d) times pseudo_distance_gradient(). On the mesh the gradient
/// is the one-sided limit from outside: f'(r0) times the outward pseudo-normal, so along the
/// inward pseudo-normal for F > 0 (outward for a carving F < 0), of magnitude
/// |f'(r0)| = 6 |F| r0 / R'^2 (1 - r0^2/R'^2)^2, never zero. Thread-safe.
MeshFieldSample mesh_field_gradient(const MeshLeaf& mesh, const MeshFieldParams& params, const glm::dvec3& p);

/// Loads each file once, however many nodes name it. Keyed by canonical path, repair flag and
/// inside mode.
class MeshCache {
 public:
  std::shared_ptr<const MeshLeaf> get(const std::filesystem::path& file, bool repair,
                                      MeshInside inside = MeshInside::Closed);
  std::size_t size() const { return meshes_.size(); }

  /// Loads the files asked for that are not held yet, in parallel (a scene's meshes are
  /// independent). A file that fails to load is left out, silently: get() loads it again and
  /// throws its error where the caller can say where it was named.
  void prefetch(std::span<const MeshFileRequest> requests);

 private:
  static std::string key(const std::filesystem::path& file, bool repair, MeshInside inside);
  std::unordered_map<std::string, std::shared_ptr<const MeshLeaf>> meshes_;
};

}  // namespace ht
