// The quality pass over a whole mesh (meshers/quality.hpp): slabs at fixed places, then the bands
// between them, each worked on by improve_whole (meshers/quality_whole.hpp) in parallel, or taken
// from a PieceCache when its input and field were seen before.
#include "meshers/quality.hpp"

#include "meshers/cache_parts.hpp"
#include "meshers/disk_cache.hpp"
#include "meshers/piece_cache.hpp"
#include "meshers/quality_whole.hpp"
#include "meshers/relax.hpp"
#include "meshers/submesh.hpp"
#include "meshers/union_find.hpp"
#include "runtime/subtree_hash.hpp"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <utility>
#include <vector>

namespace ht {
namespace {

constexpr int kBandRings = 3;             // rings around the triangles between slabs, reworked after
constexpr double kSmallComponentCells = 2.0;  // components smaller than this many h across stay as they are
constexpr std::uint64_t kPieceVersion = 1;  // of what a cached piece holds and how its key is made

// The bytes a piece is charged in the cache.
std::size_t piece_bytes(const QualityPiece& p) {
  return 128 + 24 * p.mesh.positions.size() + 12 * p.mesh.triangles.size() + 4 * p.origin.size() + 16 * p.parts.size();
}

std::uint64_t mix_double(std::uint64_t k, double v) { return hash_mix(k, std::bit_cast<std::uint64_t>(v)); }

// The hash of everything a piece's work reads but the field: its input mesh, flags and options.
std::uint64_t piece_key(const TriangleMesh& in, std::span<const std::uint8_t> keep, std::span<const std::uint8_t> crease,
                        double T, double h, const QualityOptions& o) {
  std::uint64_t k = hash_mix(0x5175616c50696563ull, kPieceVersion);  // "QualPiec"
  k = mix_double(mix_double(k, T), h);
  k = hash_mix(hash_mix(hash_mix(k, o.enabled), std::uint64_t(o.iterations)), std::uint64_t(o.newton_steps));
  k = mix_double(k, o.off_step_cells);
  k = hash_bytes(k, in.positions.data(), in.positions.size() * sizeof(glm::dvec3));
  k = hash_bytes(k, in.triangles.data(), in.triangles.size() * sizeof(glm::uvec3));
  k = hash_bytes(k, keep.data(), keep.size());
  return hash_bytes(k, crease.data(), crease.size());
}

// The parts of the field a piece's work evaluated it in, recorded from any thread.
class PartRecorder {
 public:
  explicit PartRecorder(const QualityReuse& reuse) : reuse_(reuse) {}
  void add(std::span<const glm::dvec3> points) {
    std::vector<std::uint64_t> local;
    local.reserve(points.size());
    for (const glm::dvec3& p : points) local.push_back(reuse_.part_of(p));
    std::sort(local.begin(), local.end());
    local.erase(std::unique(local.begin(), local.end()), local.end());
    const std::lock_guard lock(mutex_);
    parts_.insert(parts_.end(), local.begin(), local.end());
  }
  // The parts with their keys now, by part; false when some point had none.
  bool take(std::vector<std::pair<std::uint64_t, std::uint64_t>>& out) {
    std::sort(parts_.begin(), parts_.end());
    parts_.erase(std::unique(parts_.begin(), parts_.end()), parts_.end());
    if (!parts_.empty() && parts_.back() == QualityReuse::kNoPart) return false;
    out.clear();
    for (const std::uint64_t part : parts_) out.emplace_back(part, reuse_.part_key(part));
    return true;
  }

 private:
  const QualityReuse& reuse_;
  std::mutex mutex_;
  std::vector<std::uint64_t> parts_;
};

// The piece under `key`: from memory, else from the disk level (then in memory too), else null.
std::shared_ptr<const QualityPiece> find_piece(PieceCache& cache, std::uint64_t key, std::size_t inputs) {
  if (auto hit = cache.find<QualityPiece>(key)) return hit;
  DiskCache* disk = cache.disk();
  if (!disk) return nullptr;
  auto piece = std::make_shared<QualityPiece>();
  if (!disk->find_part(CacheKind::QualityPiece, key,
                       [&](std::string_view payload, std::string& why) { return decode_piece(payload, inputs, *piece, why); }))
    return nullptr;
  cache.insert<QualityPiece>(key, piece, piece_bytes(*piece));
  return piece;
}

bool still_valid(const QualityPiece& piece, const QualityReuse& reuse) {
  for (const auto& [part, key] : piece.parts)
    if (reuse.part_key(part) != key) return false;
  return true;
}

// improve_whole on one piece, or its result from the cache. Takes the piece's mesh (its input is
// not held beside the result). `origin` receives the piece's local indices (~0u for new vertices).
void improve_or_reuse(TriangleMesh&& in, std::span<const std::uint8_t> keep, std::span<const std::uint8_t> crease,
                      const BatchField& field, double T, double h, const QualityOptions& options,
                      const QualityReuse* reuse, TriangleMesh& out, std::vector<std::uint32_t>& origin,
                      QualityStats& st) {
  if (!reuse || !reuse->cache || !reuse->part_of || !reuse->part_key) {
    out = std::move(in);
    improve_whole(out, keep, crease, field, T, h, options, st, origin);
    return;
  }
  const std::uint64_t key = hash_mix(piece_key(in, keep, crease, T, h, options), reuse->context);
  const std::size_t inputs = in.positions.size();
  out = std::move(in);
  if (const auto hit = find_piece(*reuse->cache, key, inputs); hit && still_valid(*hit, *reuse)) {
    out = hit->mesh;
    origin = hit->origin;
    st = hit->stats;
    ++st.pieces_reused;
    return;
  }
  PartRecorder recorder(*reuse);
  const BatchField recorded = [&](std::span<const glm::dvec3> p, std::span<double> v) {
    recorder.add(p);
    field(p, v);
  };
  improve_whole(out, keep, crease, recorded, T, h, options, st, origin);
  auto piece = std::make_shared<QualityPiece>(QualityPiece{out, origin, st, {}});
  if (!recorder.take(piece->parts)) return;
  if (DiskCache* disk = reuse->cache->disk()) disk->store_part(CacheKind::QualityPiece, key, encode_piece(*piece));
  const std::size_t bytes = piece_bytes(*piece);
  reuse->cache->insert<QualityPiece>(key, std::move(piece), bytes);
}

// `count` parts improved on their own, in parallel, their rims locked; put back in part order
// after the untaken triangles `rest`. part(i) makes part i when its work starts, and its mesh is
// given to the work, so that no part's input is held beside its result. renumber[v] receives each
// old vertex's new index, ~0u for the collapsed.
template <class Part>
void improve_parts(TriangleMesh& mesh, std::size_t count, Part&& part, std::span<const glm::uvec3> rest,
                   std::span<const std::uint8_t> locked, std::span<const std::uint8_t> crease, const BatchField& field,
                   double T, double h, const QualityOptions& options, const QualityReuse* reuse, QualityStats& st,
                   std::vector<std::uint32_t>& renumber) {
  std::vector<TriangleMesh> changed(count);
  std::vector<std::vector<std::uint32_t>> origin(count);
  std::vector<QualityStats> part_stats(count);
  tbb::parallel_for(std::size_t(0), count, [&](std::size_t i) {
    Submesh sub = part(i);
    if (sub.mesh.triangles.empty()) return;  // a slab no vertex lies in
    std::vector<std::uint8_t> keep(sub.origin.size()), on_crease(crease.empty() ? 0 : sub.origin.size());
    for (std::size_t v = 0; v < keep.size(); ++v) keep[v] = sub.rim[v] ? 1 : locked.empty() ? 0 : locked[sub.origin[v]];
    for (std::size_t v = 0; v < on_crease.size(); ++v) on_crease[v] = crease[sub.origin[v]];
    improve_or_reuse(std::move(sub.mesh), keep, on_crease, field, T, h, options, reuse, changed[i], origin[i],
                     part_stats[i]);
    ++part_stats[i].pieces;
    for (std::uint32_t& o : origin[i])
      if (o != ~0u) o = sub.origin[o];
  });
  for (const QualityStats& p : part_stats) st += p;
  put_back(mesh, rest, changed, origin, &renumber);
}

// `locked` with every vertex of a component less than kSmallComponentCells precisions across
// added. Such a blob (a primitive about the size of a cell) has too few triangles to improve:
// collapsing or relaxing them folds it into itself, so it stays as extracted.
std::vector<std::uint8_t> lock_small_components(const TriangleMesh& mesh, std::span<const std::uint8_t> locked,
                                                double h) {
  const std::size_t n = mesh.positions.size();
  UnionFind parts(n);
  for (const glm::uvec3& t : mesh.triangles) parts.unite(t[0], t[1]), parts.unite(t[0], t[2]);
  std::vector<glm::dvec3> lo(n, glm::dvec3(std::numeric_limits<double>::max())), hi(n, -lo[0]);
  for (std::uint32_t v = 0; v < n; ++v) {
    const std::uint32_t r = parts.find(v);
    lo[r] = glm::min(lo[r], mesh.positions[v]);
    hi[r] = glm::max(hi[r], mesh.positions[v]);
  }
  std::vector<std::uint8_t> out(n, 0);
  if (!locked.empty()) std::copy(locked.begin(), locked.end(), out.begin());
  const double small = kSmallComponentCells * h;
  for (std::uint32_t v = 0; v < n; ++v) {
    const glm::dvec3 size = hi[parts.find(v)] - lo[parts.find(v)];
    if (size.x < small && size.y < small && size.z < small) out[v] = 1;
  }
  return out;
}

}  // namespace

void improve_quality(TriangleMesh& mesh, std::span<const std::uint8_t> locked, std::span<const std::uint8_t> crease,
                     const BatchField& field, double threshold, double h, const QualityOptions& options,
                     QualityStats* stats, std::vector<std::uint8_t>* crease_after, const QualityReuse* reuse) {
  const auto t0 = std::chrono::steady_clock::now();
  QualityStats st;
  if (crease_after) crease_after->assign(crease.begin(), crease.end());
  if (options.enabled && !mesh.triangles.empty()) {
    // Slabs first, in parallel, their rims locked; then the band of triangles between slabs.
    std::size_t count = 1;
    const std::vector<std::uint32_t> slab = slab_of_vertices(mesh, kSlabCells * h, count);
    std::vector<std::uint32_t> piece_of(mesh.triangles.size());
    for (std::size_t t = 0; t < piece_of.size(); ++t) {
      const glm::uvec3 tri = mesh.triangles[t];
      piece_of[t] = slab[tri[0]] == slab[tri[1]] && slab[tri[0]] == slab[tri[2]] ? slab[tri[0]] : ~0u;
    }
    // Each slab is taken out when its work starts: at most one a thread is held beside the mesh.
    const PiecePlan plan = plan_pieces(mesh, std::move(piece_of), count);
    std::vector<std::uint8_t> band(mesh.positions.size(), 0);
    for (const glm::uvec3& t : plan.rest) band[t[0]] = band[t[1]] = band[t[2]] = 1;
    std::vector<std::uint32_t> renumber;
    const std::vector<std::uint8_t> kept = lock_small_components(mesh, locked, h);
    locked = kept;
    const bool bands = !plan.rest.empty();
    {
      tbb::enumerable_thread_specific<std::vector<std::uint32_t>> locals(mesh.positions.size(), ~0u);
      const TriangleMesh& whole = mesh;
      improve_parts(
          mesh, count, [&](std::size_t i) { return take_part(whole, plan, i, locals.local()); }, plan.rest, locked,
          crease, field, threshold, h, options, reuse, st, renumber);
    }
    // The band's vertices were rims, locked: they survive, under new indices.
    auto moved = [&](std::span<const std::uint8_t> flags) { return renumbered(flags, renumber, mesh.positions.size()); };
    if (crease_after && !crease.empty()) *crease_after = moved(crease);
    if (bands) {
      // Three rings around it: the slabs' rims and their neighbours did not move, nor will a
      // region's rim and its neighbours.
      std::vector<std::uint8_t> region = moved(band);
      const std::vector<std::uint8_t> any(region.size(), 1), around = rings_around(mesh, region, any, kBandRings);
      for (std::size_t v = 0; v < region.size(); ++v) region[v] |= around[v];
      const std::vector<std::uint8_t> locked2 = moved(locked), crease2 = moved(crease);
      Pieces between = take_region(mesh, region, true);
      improve_parts(
          mesh, between.parts.size(), [&](std::size_t i) { return std::move(between.parts[i]); }, between.rest, locked2,
          crease2, field, threshold, h, options, reuse, st, renumber);
      if (crease_after && !crease.empty()) *crease_after = moved(crease2);
    }
  }
  st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (stats) *stats = st;
}

}  // namespace ht
