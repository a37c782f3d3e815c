// Marching tetrahedra in one brick of the global polygonizer's grid (meshers/polygonize.hpp),
// and the placement of its vertices on the surface: the per-brick work, which the polygonizer
// runs on many bricks at once. Internal to the polygonizer; the grid and brick layout live here
// so both files agree on them.
#pragma once

#include "meshers/features.hpp"
#include "runtime/aabb.hpp"

#include <glm/vec3.hpp>
#include <glm/gtc/type_precision.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace ht {

class TapeEvaluator;

namespace brick {

inline constexpr int kCells = 8;              // cells per brick side
inline constexpr int kPoints = kCells + 1;    // grid points per brick side
inline constexpr int kBrickPoints = kPoints * kPoints * kPoints;

/// What interval analysis says of a brick: the surface stays off it (outside or inside the
/// solid) or may cross it (active: sampled and extracted).
enum State : std::uint8_t { kOutside = 0, kInside = 1, kActive = 2 };

/// The polygonizer's grid: bricks of kCells^3 cells of side h from `origin`.
struct Grid {
  glm::dvec3 origin;
  double h;
  glm::ivec3 bricks;     // bricks per axis
  glm::i64vec3 points;   // grid points per axis: 8 * bricks + 1

  std::size_t brick_count() const { return std::size_t(bricks.x) * std::size_t(bricks.y) * std::size_t(bricks.z); }
  std::size_t brick_index(glm::ivec3 b) const {
    return std::size_t(b.x) + std::size_t(bricks.x) * (std::size_t(b.y) + std::size_t(bricks.y) * std::size_t(b.z));
  }
  glm::ivec3 brick_at(std::size_t i) const {
    return {int(i % std::size_t(bricks.x)), int((i / std::size_t(bricks.x)) % std::size_t(bricks.y)),
            int(i / (std::size_t(bricks.x) * std::size_t(bricks.y)))};
  }
  Aabb box(glm::ivec3 lo, glm::ivec3 hi) const {  // bricks [lo, hi)
    return {origin + glm::dvec3(lo) * (kCells * h), origin + glm::dvec3(hi) * (kCells * h)};
  }
  std::uint64_t point_index(glm::i64vec3 p) const {
    return std::uint64_t(p.x + points.x * (p.y + points.y * p.z));
  }
  glm::i64vec3 point_at(std::uint64_t index) const {  // the inverse of point_index
    const auto px = std::uint64_t(points.x), py = std::uint64_t(points.y);
    return {std::int64_t(index % px), std::int64_t((index / px) % py), std::int64_t(index / (px * py))};
  }
  glm::dvec3 position(glm::i64vec3 p) const { return origin + glm::dvec3(p) * h; }
};

/// A vertex on a grid edge, keyed by the edge: lower grid point * 8 + direction (x = 1, y = 2,
/// z = 4, monotone diagonals combine them).
/// 48 bytes, no padding: a global run holds every brick's vertices at once (its peak).
struct EdgeVertex {
  std::uint64_t key;
  glm::dvec3 position;
  glm::vec3 normal;  // outward unit normal where a crease is suspected, else zero
  std::uint32_t brick;
};

/// A brick has fewer than 7 kPoints^3 = 5103 edges (three axes, three face diagonals, one body
/// diagonal a point): its triangles index its own vertices in 16 bits (6 bytes a triangle, not
/// the 24 of three edge keys).
using LocalTriangle = std::array<std::uint16_t, 3>;

/// One brick's extraction: its vertices sorted by key, each vector sized exactly.
struct BrickOutput {
  std::vector<EdgeVertex> vertices;
  std::vector<LocalTriangle> triangles;  // indices into vertices, oriented outward
};


/// Working arrays of one brick's extraction, kept per thread so that the steady state allocates
/// nothing (their capacity grows to the largest brick and stays).
struct Scratch {
  std::vector<std::uint64_t> keys;        // edge keys in order of creation: 3 i + k is triangle i's corner k
  std::vector<std::uint16_t> vertex_of;   // the vertex each of them became (place_vertices)
  std::vector<std::array<int, 2>> ends;   // their local grid points
  std::vector<std::uint32_t> cell_begin;  // triangles of each cell, x fastest
  std::vector<std::size_t> order, unique;
  std::vector<glm::dvec3> pa, pb;
  std::vector<double> fa, fb, t, span, ta, tb;
  std::vector<std::uint8_t> probed;     // a value exactly T was probed past once
  std::vector<double> slope;             // the field's slope along each edge at its first guess (NaN: unknown)
  std::vector<float> xs, ys, zs, fv;
  std::vector<std::uint32_t> live;
  std::vector<std::int8_t> side;
  std::vector<std::uint8_t> wanted;
  std::vector<glm::dvec3> at, grad;
};

/// How vertices are placed: false-position steps and tolerance (meshers/polygonize.hpp).
struct Refine {
  int steps = 24;
  double tolerance = 1e-3;
};

/// The triangles of brick `b` (keys of their vertices' edges, oriented outward) from the
/// inside labels of its kPoints^3 grid points (x fastest), into scratch: the edges met, three a
/// triangle, and each cell's first triangle. When `cells` is given (kCells^3 flags, x fastest), a cell
/// whose flag is 0 gets no triangles.
void march(const Grid& grid, glm::ivec3 b, const std::uint8_t* label, Scratch& scratch,
           const std::uint8_t* cells = nullptr);

/// One vertex per distinct edge of march(): false position along the edge on `eval` (the
/// brick's tape) from the brick's samples `own`, threshold T; fills out.vertices, sorted by key,
/// and out.triangles (march's, in its order, as indices into them). A NaN sample is a point not
/// evaluated (outside, PolygonizeOptions::brick_filter): a vertex on an edge to it stays at the
/// edge's midpoint. Returns the number of field values it evaluated.
std::size_t place_vertices(const Grid& grid, glm::ivec3 b, std::uint32_t brick_index, const float* own,
                    const std::uint8_t* label, const TapeEvaluator& eval, double T, const Refine& refine,
                    Scratch& scratch, BrickOutput& out);

/// The octants of a brick (bit i + 2 j + 4 k: the upper half of x when i is 1, and so on, as
/// PolygonizeOptions::brick_filter names them) whose closed boxes hold local grid point (i, j, k).
std::uint8_t octants_at(int i, int j, int k);

/// Takes out of brick b's output (as march() and place_vertices() left it, with `scratch`) the
/// triangles of the cells outside the octants `octants` names (PolygonizeOptions::brick_filter)
/// and those with a vertex on an edge to a point not sampled (NaN in `own`), then the vertices
/// only they used: their sign changes are not the surface's. Returns how many triangles went.
std::size_t drop_unsampled(const Grid& grid, glm::ivec3 b, const float* own, std::uint8_t octants,
                           const Scratch& scratch, BrickOutput& out);

/// Exact outward normals (forward-mode gradients on `eval`) for the vertices of the cells whose
/// sampled gradients spread (meshers/features.hpp mark_suspect_cells); the others keep none.
void crease_normals(const float* own, const TapeEvaluator& eval, const FeatureOptions& options, Scratch& scratch,
                    BrickOutput& out);

}  // namespace brick
}  // namespace ht
