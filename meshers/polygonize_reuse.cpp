#include "meshers/polygonize_reuse.hpp"

#include "meshers/cache_parts.hpp"
#include "meshers/disk_cache.hpp"
#include "meshers/piece_cache.hpp"
#include "meshers/self_intersections.hpp"
#include "runtime/subtree_hash.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cassert>
#include <atomic>
#include <bit>
#include <cmath>
#include <limits>
#include <unordered_map>

namespace ht::brick {
namespace {

constexpr std::uint64_t kBrickVersion = 1;  // of what a kept brick holds and how its key is made

std::uint64_t mix_double(std::uint64_t k, double v) { return hash_mix(k, std::bit_cast<std::uint64_t>(v)); }

std::uint64_t tape_hash(const Tape& t, const std::unordered_map<const MeshLeaf*, std::uint64_t>& meshes) {
  std::uint64_t k = hash_mix(0x546170654861736eull, 1);  // "TapeHash"
  k = hash_bytes(k, t.code.data(), t.code.size() * sizeof(Instruction));
  k = hash_bytes(k, t.constants.data(), t.constants.size() * sizeof(float));
  for (const MeshLeaf* m : t.meshes) k = hash_mix(k, meshes.at(m));
  k = hash_mix(hash_mix(k, t.registers), t.result);
  return hash_mix(k, std::bit_cast<std::uint32_t>(t.threshold));
}

// The brick holding p, as meshers/surface_field.cpp bins points (same expression, same bits).
glm::dvec3 brick_of(const Grid& grid, const glm::dvec3& p) { return glm::floor((p - grid.origin) / (kCells * grid.h)); }

bool in_grid(const Grid& grid, glm::ivec3 b) {
  return b.x >= 0 && b.y >= 0 && b.z >= 0 && b.x < grid.bricks.x && b.y < grid.bricks.y && b.z < grid.bricks.z;
}

}  // namespace

std::vector<std::uint64_t> tape_hashes(const std::vector<std::shared_ptr<const Tape>>& tapes) {
  std::vector<const MeshLeaf*> leaves;
  for (const auto& t : tapes) leaves.insert(leaves.end(), t->meshes.begin(), t->meshes.end());
  std::sort(leaves.begin(), leaves.end());
  leaves.erase(std::unique(leaves.begin(), leaves.end()), leaves.end());
  std::vector<std::uint64_t> leaf_hash(leaves.size());
  tbb::parallel_for(std::size_t(0), leaves.size(), [&](std::size_t i) { leaf_hash[i] = mesh_contents_hash(*leaves[i]); });
  std::unordered_map<const MeshLeaf*, std::uint64_t> by_leaf;
  for (std::size_t i = 0; i < leaves.size(); ++i) by_leaf.emplace(leaves[i], leaf_hash[i]);
  std::vector<std::uint64_t> out(tapes.size());
  tbb::parallel_for(std::size_t(0), tapes.size(), [&](std::size_t a) { out[a] = tape_hash(*tapes[a], by_leaf); });
  return out;
}

std::uint64_t brick_key(const BrickView& view, glm::ivec3 b, double T, const PolygonizeOptions& o) {
  const Grid& grid = *view.grid;
  std::uint64_t k = hash_mix(0x427269636b4f7574ull, kBrickVersion);  // "BrickOut"
  for (int i = 0; i < 3; ++i) k = hash_mix(mix_double(k, grid.origin[i]), std::uint64_t(grid.bricks[i]));
  k = mix_double(mix_double(k, grid.h), T);
  k = hash_mix(k, grid.brick_index(b));
  k = mix_double(hash_mix(k, std::uint64_t(o.refine_steps)), o.refine_tolerance);
  const FeatureOptions& f = o.features;
  k = hash_mix(k, o.sharp_features);
  for (double v : {f.sharp_angle_degrees, f.suspect_angle_degrees, f.max_error, f.snap}) k = mix_double(k, v);
  k = hash_mix(k, std::uint64_t(f.refine_rounds));
  // The brick and the + neighbours that own its shared points: their states, and the tapes that
  // sample those points where they are active.
  for (int n = 0; n < 8; ++n) {
    const glm::ivec3 c = b + glm::ivec3(n & 1, (n >> 1) & 1, (n >> 2) & 1);
    if (!in_grid(grid, c)) {
      k = hash_mix(k, 0xff);
      continue;
    }
    const std::size_t i = grid.brick_index(c);
    const std::uint8_t s = (*view.state)[i];
    k = hash_mix(k, s);
    if (s == kActive && (*view.slot)[i] != kNone) k = hash_mix(k, view.tape_hash[(*view.slot)[i]]);
  }
  return k;
}

QualityReuse quality_reuse(const BrickView& view, PieceCache& cache) {
  const Grid& grid = *view.grid;
  QualityReuse r;
  r.cache = &cache;
  std::uint64_t k = hash_mix(0x4772696450617274ull, kBrickVersion);  // "GridPart"
  for (int i = 0; i < 3; ++i) k = hash_mix(mix_double(k, grid.origin[i]), std::uint64_t(grid.bricks[i]));
  r.context = mix_double(k, grid.h);
  r.part_of = [&view](const glm::dvec3& p) {
    const Grid& g = *view.grid;
    const glm::dvec3 c = brick_of(g, p);
    if (!(c.x >= 0 && c.y >= 0 && c.z >= 0 && c.x < g.bricks.x && c.y < g.bricks.y && c.z < g.bricks.z))
      return QualityReuse::kNoPart;
    const std::size_t i = g.brick_index(glm::ivec3(c));
    const bool active = (*view.state)[i] == kActive && (*view.slot)[i] != kNone;
    return active ? std::uint64_t(i) : QualityReuse::kNoPart;
  };
  r.part_key = [&view](std::uint64_t part) {
    const std::uint32_t s = part < view.slot->size() ? (*view.slot)[part] : kNone;
    return s == kNone ? QualityReuse::kNoPart : view.tape_hash[s];
  };
  return r;
}

std::size_t kept_bytes(const KeptBrick& k) {
  return 96 + k.out.vertices.size() * sizeof(EdgeVertex) + k.out.triangles.size() * sizeof(k.out.triangles[0]);
}

namespace {

// A region's triangles as a mesh of their own: vertices numbered in increasing global order.
TriangleMesh region_mesh(const TriangleMesh& mesh, const std::vector<std::uint32_t>& triangles) {
  std::vector<std::uint32_t> used;
  used.reserve(3 * triangles.size());
  for (const std::uint32_t t : triangles)
    for (int k = 0; k < 3; ++k) used.push_back(mesh.triangles[t][k]);
  std::sort(used.begin(), used.end());
  used.erase(std::unique(used.begin(), used.end()), used.end());
  TriangleMesh out;
  out.positions.reserve(used.size());
  for (const std::uint32_t v : used) out.positions.push_back(mesh.positions[v]);
  out.triangles.reserve(triangles.size());
  auto local = [&](std::uint32_t v) { return std::uint32_t(std::lower_bound(used.begin(), used.end(), v) - used.begin()); };
  for (const std::uint32_t t : triangles)
    out.triangles.push_back({local(mesh.triangles[t][0]), local(mesh.triangles[t][1]), local(mesh.triangles[t][2])});
  return out;
}

// What a PieceCache keeps of a region found clean: nothing but the fact.
struct CleanRegion {};

}  // namespace

std::shared_ptr<const KeptBrick> find_kept(PieceCache& cache, std::uint64_t key) {
  if (auto hit = cache.find<KeptBrick>(key)) return hit;
  DiskCache* disk = cache.disk();
  if (!disk) return nullptr;
  auto brick = std::make_shared<KeptBrick>();
  if (!disk->find_part(CacheKind::Brick, key,
                       [&](std::string_view payload, std::string& why) { return decode_kept(payload, *brick, why); }))
    return nullptr;
  const std::size_t bytes = kept_bytes(*brick);
  cache.insert<KeptBrick>(key, brick, bytes);
  return brick;
}

void keep(PieceCache& cache, std::uint64_t key, std::shared_ptr<const KeptBrick> brick) {
  if (DiskCache* disk = cache.disk()) disk->store_part(CacheKind::Brick, key, encode_kept(*brick));
  const std::size_t bytes = kept_bytes(*brick);
  cache.insert<KeptBrick>(key, std::move(brick), bytes);
}

bool clean_by_regions(const TriangleMesh& mesh, double thickness, PieceCache& cache) {
  if (mesh.triangles.empty()) return true;
  glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
  for (const glm::dvec3& p : mesh.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
  const glm::dvec3 size = hi - lo;
  const int axis = size.x >= size.y && size.x >= size.z ? 0 : size.y >= size.z ? 1 : 2;
  const double first = std::floor(lo[axis] / thickness), last = std::floor(hi[axis] / thickness);
  if (!(last - first < 4096.0)) return false;  // too many regions to be worth it: the caller checks it all
  // Region k: the triangles whose boxes meet slab k. Two triangles that meet share a point,
  // which lies in some slab, so both are in that slab's region.
  std::vector<std::vector<std::uint32_t>> regions(std::size_t(last - first) + 1);
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    double a = std::numeric_limits<double>::max(), b = -a;
    for (int k = 0; k < 3; ++k) {
      const double x = mesh.positions[mesh.triangles[t][k]][axis];
      a = std::min(a, x), b = std::max(b, x);
    }
    for (double k = std::floor(a / thickness); k <= std::floor(b / thickness); ++k) regions[std::size_t(k - first)].push_back(t);
  }
  std::atomic<bool> clean{true};
  tbb::parallel_for(std::size_t(0), regions.size(), [&](std::size_t r) {
    if (regions[r].empty() || !clean.load(std::memory_order_relaxed)) return;
    const TriangleMesh sub = region_mesh(mesh, regions[r]);
    std::uint64_t key = hash_mix(0x436c65616e526567ull, kBrickVersion);  // "CleanReg"
    key = hash_bytes(key, sub.positions.data(), sub.positions.size() * sizeof(glm::dvec3));
    key = hash_bytes(key, sub.triangles.data(), sub.triangles.size() * sizeof(glm::uvec3));
    if (cache.find<CleanRegion>(key)) return;
    DiskCache* disk = cache.disk();
    auto empty = [](std::string_view payload, std::string& why) {
      why = payload.empty() ? "" : "a clean region's entry holds " + std::to_string(payload.size()) + " bytes";
      return payload.empty();
    };
    if (disk && disk->find_part(CacheKind::CleanRegion, key, empty)) {
      cache.insert<CleanRegion>(key, std::make_shared<const CleanRegion>(), 64);
      return;
    }
    if (find_self_intersections(sub, 0).pairs != 0) {
      clean = false;
      return;
    }
    if (disk) disk->store_part(CacheKind::CleanRegion, key, std::string());
    cache.insert<CleanRegion>(key, std::make_shared<const CleanRegion>(), 64);
  });
  return clean.load();
}

}  // namespace ht::brick
