// Internal to the mesh leaf's three files (nodes/mesh_read.cpp: reading; nodes/mesh_build.cpp:
// validation, orientation and repair; nodes/mesh_leaf.cpp: the Embree acceleration and the
// queries). Not part of the public interface: nodes/mesh_leaf.hpp is.
#pragma once

#include "nodes/mesh_leaf.hpp"
#include "nodes/primitives.hpp"

#include <embree3/rtcore.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace ht::mesh_detail {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr std::size_t kMaxHoleEdges = 64;
// Embree works in float and asserts (aborting the process) on a ray whose origin lies past about
// 1.8e18 (fuzz_mesh_off: a vertex at 5.5e24 put a shell's probe ray there). Meshes stay inside
// this; points beyond it are answered without Embree.
constexpr double kMaxCoordinate = 1e18;

inline double largest_coordinate(const glm::dvec3& p) { return std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)}); }

[[noreturn]] inline void fail(const std::string& name, const std::string& what) {
  throw MeshError(name + ": " + what);
}

inline std::string edge_text(std::uint32_t a, std::uint32_t b) {
  return "between vertices " + std::to_string(a) + " and " + std::to_string(b);
}

// ---------------------------------------------------------------------------------------------
// Edge topology. Half-edge h = 3t + k runs from tri[t][k] to tri[t][(k+1)%3]; nbr[h] is the
// triangle across it (kNone on a boundary).

struct Topology {
  std::vector<std::uint32_t> nbr;
  std::vector<std::uint8_t> open;  // 1 for half-edges of boundary edges (one face), per half-edge
  std::size_t boundary = 0, nonmanifold = 0;
  std::uint32_t first_boundary = kNone, first_nonmanifold = kNone;  // a half-edge, face order
};

inline std::uint32_t corner(const glm::uvec3& t, std::uint32_t k) { return t[static_cast<glm::length_t>(k % 3)]; }

Topology edge_topology(const std::vector<glm::uvec3>& tris);

struct Shells {
  std::vector<std::uint32_t> of;  // shell of each triangle
  std::uint32_t count = 0;
};

// Closest points on triangles come from nodes/primitives.hpp, with the feature they lie on.
using Nearest = TrianglePoint;
constexpr int kFace = kTriangleFace, kEdge = kTriangleEdge, kVertex = kTriangleVertex;

// Fixed, non-axis-aligned ray directions for the parity vote: meshes are often built on axis
// planes and diagonals, where rays would graze edges.
constexpr std::array<std::array<float, 3>, 3> kRayDirs = {
    {{0.5219f, 0.7231f, 0.4527f}, {-0.6873f, 0.2129f, 0.6946f}, {0.3197f, -0.8141f, 0.4847f}}};

struct DeviceRelease {
  void operator()(RTCDevice d) const { rtcReleaseDevice(d); }
};
struct SceneRelease {
  void operator()(RTCScene s) const { rtcReleaseScene(s); }
};
// What a point query reads of each triangle Embree hands over, stored in Embree's (shell,
// primID) order, which follows a Morton curve: a query's visits then touch neighbouring records
// instead of scattered arrays (those cache misses were most of a query's time). Most visits end
// at the sphere or the disc; the few that pass read the corners from the mesh's arrays, which
// is why the record does not copy them (48 bytes a triangle instead of 144). The sphere and the
// disc only reject: their centre is rounded to float and their sizes are measured from that
// centre and rounded up, so they still hold the whole triangle and answers stay bit for bit.
struct TriRecord {
  glm::dvec3 normal;  // the face normal: unit, or zero when degenerate; with the sphere, a disc
  glm::vec3 centre;   // the centroid in float; with reach, a ball that rejects far triangles early
  float reach;        // the corners' largest distance from `centre`, rounded up
  float thickness;    // their largest distance from the plane through `centre` (rounded up)
  std::uint32_t tri;  // index into triangles_
};
static_assert(sizeof(TriRecord) == 48);

}  // namespace ht::mesh_detail

namespace ht {

// ---------------------------------------------------------------------------------------------
// Acceleration: Embree scene over float copies of the vertices (geometry s = shell s), and the
// pseudo-normals, in double, of the final orientation. Built once, then read-only: every
// member function is safe to call from any number of threads.
struct MeshLeaf::Accel {
  using TriRecord = mesh_detail::TriRecord;
  // Embree reference-counts the device, so the scene may be released after or before it.
  std::unique_ptr<RTCDeviceTy, mesh_detail::DeviceRelease> device;
  std::unique_ptr<RTCSceneTy, mesh_detail::SceneRelease> scene;
  std::vector<float> vertices;            // xyz per vertex, plus padding Embree reads past the end
  std::vector<std::uint32_t> order;       // while building: triangles grouped by shell, (shell, primID) -> triangle
  std::vector<std::uint32_t> offset;      // start of each shell's records
  std::vector<std::uint32_t> slot;        // triangle -> its record (`order` inverted, then dropped)
  std::vector<glm::dvec3> vertex_normal;  // angle-weighted sum of incident face normals
  std::vector<std::uint8_t> complex_vertex;  // several fans meet there (see compute_normals)
  std::vector<std::uint32_t> nbr;         // triangle across each half-edge: edge normal = sum of two
  std::vector<TriRecord> records;        // Embree's (shell, primID) order, see TriRecord
  double scale = 0;                       // largest coordinate magnitude, for float slack

  Accel(const std::string& name, const std::vector<glm::dvec3>& pos, const std::vector<glm::uvec3>& tris,
        const mesh_detail::Shells& shells);
  // Orders each shell's triangles along a Morton curve of their centroids (10 bits per axis
  // over the mesh's box), so that triangles near in space are near in memory.
  void morton_sort_shells(const std::vector<glm::dvec3>& pos, const std::vector<glm::uvec3>& tris);

  // Calls visit(geomID) for every surface crossing along the ray from p. Each call restarts
  // just past the previous hit, so hits of the two triangles of an edge at the same t count once.
  template <class Visit>
  void crossings(const glm::dvec3& p, const std::array<float, 3>& dir, Visit&& visit) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    RTCRayHit rh{};
    rh.ray.org_x = static_cast<float>(p.x);
    rh.ray.org_y = static_cast<float>(p.y);
    rh.ray.org_z = static_cast<float>(p.z);
    rh.ray.dir_x = dir[0];
    rh.ray.dir_y = dir[1];
    rh.ray.dir_z = dir[2];
    rh.ray.tnear = 0.0f;
    rh.ray.mask = ~0u;
    for (std::size_t guard = 0; guard <= offset.back(); ++guard) {
      rh.ray.tfar = std::numeric_limits<float>::infinity();
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(scene.get(), &ctx, &rh);
      if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return;
      visit(rh.hit.geomID);
      rh.ray.tnear = std::nextafter(rh.ray.tfar, std::numeric_limits<float>::infinity());
    }
  }

  void compute_normals(const std::vector<glm::dvec3>& pos, const std::vector<glm::uvec3>& tris,
                       std::vector<std::uint32_t> neighbours);
  // True when the closest point is (within rounding) a vertex where several fans meet: the
  // closest feature may then be reported as an edge or face of either fan, and only parity
  // tells inside from outside.
  bool needs_parity(std::uint32_t t, int feature, const glm::dvec3& closest, const std::vector<glm::dvec3>& pos,
                    const std::vector<glm::uvec3>& tris) const;
  /// The angle-weighted pseudo-normal of feature `feature` of triangle t (not normalized).
  glm::dvec3 pseudo_normal(std::uint32_t t, int feature, const std::vector<glm::uvec3>& tris) const;
  /// `pseudo` (from pseudo_normal) made unit, or where it is zero or meaningless (`parity`:
  /// fans meet at the nearest point) the normal of triangle t or of its corners: never zero.
  glm::dvec3 unit_normal(const glm::dvec3& pseudo, std::uint32_t t, bool parity,
                         const std::vector<glm::uvec3>& tris) const;
  /// Triangle t's unit normal, zero when degenerate (its record's).
  const glm::dvec3& face_normal(std::uint32_t t) const { return records[slot[t]].normal; }
  std::size_t bytes() const;
};

}  // namespace ht
