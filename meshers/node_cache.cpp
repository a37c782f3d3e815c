#include "meshers/node_cache.hpp"

#include "meshers/disk_cache.hpp"
#include "runtime/subtree_hash.hpp"

#include <bit>

namespace ht {

namespace {

constexpr std::size_t kEntryOverhead = 256;  // report, list and map nodes, roughly

std::uint64_t mix_double(std::uint64_t h, double v) { return hash_mix(h, std::bit_cast<std::uint64_t>(v)); }

std::uint64_t mix_box(std::uint64_t h, const Aabb& b) {
  for (int i = 0; i < 3; ++i) h = mix_double(mix_double(h, b.lo[i]), b.hi[i]);
  return h;
}

}  // namespace

// A new option field must be hashed above (or said not to change output): these trip when one
// is added.
static_assert(sizeof(FeatureOptions) == 40, "hash the new FeatureOptions field");
static_assert(sizeof(QualityOptions) == 24, "hash the new QualityOptions field");

std::uint64_t mesh_options_hash(const MeshOptions& o) {
  std::uint64_t h = hash_mix(0x4d6573684f707473ull, 1);  // "MeshOpts", layout version 1
  h = mix_double(h, o.precision);
  h = hash_mix(h, static_cast<std::uint64_t>(o.strategy));
  h = mix_double(h, o.blend_overlap);
  h = hash_mix(h, o.remesh_seams);
  const PolygonizeOptions& p = o.polygonize;
  h = mix_double(h, p.precision);
  h = hash_mix(h, static_cast<std::uint64_t>(p.refine_steps));
  h = mix_double(h, p.refine_tolerance);
  h = hash_mix(h, p.sharp_features);
  h = hash_mix(h, p.snap);
  const FeatureOptions& f = p.features;
  for (double v : {f.sharp_angle_degrees, f.suspect_angle_degrees, f.max_error, f.snap}) h = mix_double(h, v);
  h = hash_mix(h, static_cast<std::uint64_t>(f.refine_rounds));
  h = hash_mix(h, p.quality.enabled);
  h = hash_mix(h, static_cast<std::uint64_t>(p.quality.iterations));
  h = hash_mix(h, static_cast<std::uint64_t>(p.quality.newton_steps));
  h = mix_double(h, p.quality.off_step_cells);
  return mix_box(h, p.clip);
}

std::size_t NodeCache::entry_bytes(const CachedJob& value) {
  const std::size_t v = value.mesh ? value.mesh->positions.size() : 0;
  const std::size_t t = value.mesh ? value.mesh->triangles.size() : 0;
  return kEntryOverhead + 24 * v + 12 * t + value.report.fallback_cause.size();
}

std::optional<CachedJob> NodeCache::find(std::uint64_t key) {
  if (const auto hit = jobs_.find<CachedJob>(key)) return *hit;
  if (!disk_) return std::nullopt;
  std::optional<CachedJob> found = disk_->find(key);  // file I/O, no lock held
  if (found) keep(key, *found);
  return found;
}

void NodeCache::insert(std::uint64_t key, CachedJob value) {
  if (disk_) disk_->store(key, value);
  keep(key, std::move(value));
}

void NodeCache::keep(std::uint64_t key, CachedJob value) {
  const std::size_t bytes = entry_bytes(value);
  jobs_.insert<CachedJob>(key, std::make_shared<const CachedJob>(std::move(value)), bytes);
}

void NodeCache::clear() {
  jobs_.clear();
  pieces_.clear();
}

}  // namespace ht
