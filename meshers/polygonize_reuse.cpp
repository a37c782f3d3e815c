#include "meshers/polygonize_reuse.hpp"

#include "runtime/subtree_hash.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <bit>
#include <cmath>
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

QualityReuse::Scope field_scope(const BrickView& view, const Aabb& box) {
  const Grid& grid = *view.grid;
  const glm::dvec3 dlo = brick_of(grid, box.lo), dhi = brick_of(grid, box.hi);
  QualityReuse::Scope scope;
  // A box past the grid or over very many bricks is not worth keying (nothing is kept).
  const glm::dvec3 span = dhi - dlo + 1.0;
  if (!(span.x * span.y * span.z <= 1e6) || !in_grid(grid, glm::ivec3(dlo)) || !in_grid(grid, glm::ivec3(dhi))) return scope;
  const glm::ivec3 lo(dlo), hi(dhi);
  std::uint64_t k = hash_mix(0x53636f7065000000ull, 1);  // "Scope"
  for (int z = lo.z; z <= hi.z; ++z)
    for (int y = lo.y; y <= hi.y; ++y)
      for (int x = lo.x; x <= hi.x; ++x) {
        const std::size_t i = grid.brick_index({x, y, z});
        const bool active = (*view.state)[i] == kActive && (*view.slot)[i] != kNone;
        k = hash_mix(k, active ? view.tape_hash[(*view.slot)[i]] : 0x5a);
      }
  // The field is the same wherever the bricks are: their place is the box's, which the piece's
  // input (its positions) already fixes; the grid's origin and cell are hashed for the lattice.
  for (int i = 0; i < 3; ++i) k = hash_mix(hash_mix(mix_double(k, grid.origin[i]), std::uint64_t(lo[i])), std::uint64_t(hi[i]));
  scope.key = mix_double(k, grid.h);
  scope.covers = [&view, lo, hi](const glm::dvec3& p) {
    const Grid& g = *view.grid;
    const glm::dvec3 c = brick_of(g, p);
    if (!(c.x >= lo.x && c.y >= lo.y && c.z >= lo.z && c.x <= hi.x && c.y <= hi.y && c.z <= hi.z)) return false;
    const std::size_t i = g.brick_index(glm::ivec3(c));
    return (*view.state)[i] == kActive && (*view.slot)[i] != kNone;
  };
  return scope;
}

std::size_t kept_bytes(const KeptBrick& k) {
  return 96 + k.out.vertices.size() * sizeof(EdgeVertex) + k.out.triangles.size() * sizeof(k.out.triangles[0]);
}

}  // namespace ht::brick
