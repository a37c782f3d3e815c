// What the global polygonizer (meshers/polygonize.hpp) takes from earlier runs, brick by brick
// (incremental re-meshing, issue 15). Internal to the polygonizer.
//
// A brick's extraction (its triangles and vertices, meshers/brick_extract.hpp) reads its own
// tape's values at its grid points, the values its + neighbours' tapes give at the points they
// own, or their inside/outside states where they are not sampled, and the grid and options. Its
// key hashes all of these, tapes by content (instructions, constants, mesh leaves' contents), so
// a brick whose key is in the PieceCache has the same output as when it is extracted, and is not
// sampled or extracted again.
//
// The quality pass's pieces (meshers/quality.hpp QualityReuse) see the field as these bricks:
// a piece is taken again when the bricks it evaluated the field in still have the same tapes.
//
// With a disk level (`hybridtree mesh --cache DIR`), kept bricks and clean regions are files of
// DIR too (meshers/disk_cache.hpp), one per brick (meshers/cache_parts.hpp encode_kept), checked
// when read back.
#pragma once

#include "meshers/brick_extract.hpp"
#include "meshers/polygonize.hpp"
#include "meshers/quality.hpp"
#include "runtime/tape.hpp"

#include <cstdint>
#include <memory>
#include <vector>

namespace ht {
class PieceCache;
}

namespace ht::brick {

/// A brick's extraction as the cache keeps it.
struct KeptBrick {
  BrickOutput out;
  bool reaches_boundary = false;  ///< a grid point on the grid's outer faces is inside
};

/// The polygonizer's bricks as the keys see them: the grid, each brick's state (0 outside,
/// 1 inside, 2 active: meshers/polygonize.cpp), each active brick's slot and tape.
struct BrickView {
  const Grid* grid = nullptr;
  const std::vector<std::uint8_t>* state = nullptr;
  const std::vector<std::uint32_t>* slot = nullptr;  ///< by brick index; kNone where not active
  std::vector<std::uint64_t> tape_hash;              ///< by slot
};

/// Content hashes of the active bricks' tapes (meshes by their contents, each hashed once).
std::vector<std::uint64_t> tape_hashes(const std::vector<std::shared_ptr<const Tape>>& tapes);

/// The key of active brick `b`'s extraction with these options and threshold.
std::uint64_t brick_key(const BrickView& view, glm::ivec3 b, double T, const PolygonizeOptions& options);

/// The quality pass's reuse over these bricks: parts are active bricks (their index), keyed by
/// their tapes' hashes; points in other bricks have none; the grid is the context. Holds `view`
/// and `cache` by reference.
QualityReuse quality_reuse(const BrickView& view, PieceCache& cache);

/// Whether `mesh` has no self-intersecting pair (meshers/self_intersections.hpp), told region by
/// region: across the mesh's longest axis, slabs `thickness` thick at fixed places, each region
/// the triangles whose boxes meet its slab (two triangles that meet share a point, which lies in
/// some slab). A region found clean before, the same bit for bit, is not tested again; a region
/// found clean now is kept. False when some region has a pair (then find them all over the
/// mesh) or the regions would be too many.
bool clean_by_regions(const TriangleMesh& mesh, double thickness, PieceCache& cache);

/// The bytes a kept brick is charged in the cache.
std::size_t kept_bytes(const KeptBrick& k);

/// The extraction kept under `key`: from memory, else from the cache's disk level (then kept in
/// memory too), else null.
std::shared_ptr<const KeptBrick> find_kept(PieceCache& cache, std::uint64_t key);
/// Keeps `brick` under `key`, in memory and on the cache's disk level.
void keep(PieceCache& cache, std::uint64_t key, std::shared_ptr<const KeptBrick> brick);

}  // namespace ht::brick
