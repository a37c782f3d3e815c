#include "meshers/polygonize_passes.hpp"

#include "meshers/piece_cache.hpp"
#include "meshers/polygonize_reuse.hpp"
#include "meshers/relax.hpp"
#include "meshers/self_intersections.hpp"
#include "meshers/unfold.hpp"

#include <array>
#include <limits>
#include <string>

namespace ht {

namespace {

constexpr int kUntangleRounds = 4;  // of sliding crease points where the feature step folded
constexpr int kUnfoldRounds = 12;   // of collapsing the folds sliding left
constexpr double kFoldLockCells = 2.0;  // around a fold the quality pass left, kept as extracted on its second run
constexpr int kFoldTurns = 3;       // of collapsing, then relaxing, what stays folded

// Folds left by the crease step or the quality pass: collapsed (meshers/unfold.hpp), and where
// collapses are stuck, the vertices around them relaxed apart (meshers/relax.hpp untangle, crease
// points sliding along their crease), in turns. `pairs` holds every intersecting pair and
// receives those left.
void resolve_folds(TriangleMesh& mesh, std::vector<std::uint8_t>& crease, const TapeEvaluator& eval, double T, double h,
                   std::vector<std::array<std::uint32_t, 2>>& pairs, PolygonizeStats& stats) {
  for (int turn = 0; turn < kFoldTurns && !pairs.empty(); ++turn) {
    const UnfoldStats st = unfold(mesh, crease, pairs, kUnfoldRounds);
    stats.unfold.collapses += st.collapses;
    stats.unfold.seconds += st.seconds;
    if (pairs.empty()) break;
    Aabb near;
    for (const auto& pair : pairs)
      for (const std::uint32_t t : pair)
        for (int k = 0; k < 3; ++k) near.grow(mesh.positions[mesh.triangles[t][k]]);
    if (crease.size() != mesh.positions.size()) crease.resize(mesh.positions.size(), 0);
    const std::vector<std::uint8_t> none(mesh.positions.size(), 0);
    const auto left = untangle(mesh, none, gradient_of(eval), T, near.expanded(2.0 * h), kUntangleRounds, crease);
    // untangle searched only its region; the pairs outside it are those unfold left there.
    std::vector<std::array<std::uint32_t, 2>> all = left;
    for (const auto& pair : pairs) {
      bool inside = false;
      for (const std::uint32_t t : pair)
        for (int k = 0; k < 3; ++k) inside |= near.expanded(2.0 * h).contains(mesh.positions[mesh.triangles[t][k]]);
      if (!inside) all.push_back(pair);
    }
    pairs = std::move(all);
  }
  stats.crease_intersections = pairs.size();
}

}  // namespace

void crease_phase(RootField& field, const FeatureOptions& features, double h, TriangleMesh& mesh,
                  const std::vector<glm::vec3>& normals, std::vector<std::uint8_t>& on_crease, PolygonizeStats& stats) {
  bool any_normal = false;
  for (const glm::vec3& n : normals) any_normal |= n != glm::vec3(0.0f);
  if (!any_normal) return;
  const TapeEvaluator& eval = field.get();
  const CreaseStats crease = split_creases(mesh, normals, eval, field.T, h, features, &on_crease);
  stats.crease_edges = crease.split_edges;
  stats.crease_candidates = crease.candidate_edges;
  stats.crease_spread = crease.spread_edges;
  stats.corner_vertices = crease.corners;
  if (crease.split_edges + crease.corners == 0) return;
  Aabb near;
  for (std::size_t v = 0; v < on_crease.size(); ++v)
    if (on_crease[v]) near.grow(mesh.positions[v]);
  const std::vector<std::uint8_t> none(mesh.positions.size(), 0);
  // Every triangle the step cut has a crease point for a corner; the rest are as extracted.
  auto left = untangle(mesh, none, gradient_of(eval), field.T, near.expanded(2.0 * h), kUntangleRounds, on_crease,
                       on_crease);
  stats.unfold.pairs_before = stats.crease_intersections = left.size();
  resolve_folds(mesh, on_crease, eval, field.T, h, left, stats);
  // A piece that folded over without crossing anything (a sliver beside a crease whose corner
  // fell past the crease point) is no intersection; it goes here, before the quality pass (left
  // for after it, eight.off kept three folds, not one, and knot2.off's smallest angle fell to 0).
  stats.folds += unfold_folded(mesh, on_crease, gradient_of(eval), field.T);
}

RetryRequest quality_phase(SurfaceField& field, RootField& root_field, double h, const QualityOptions& options,
                           MemoryBudget& budget, TriangleMesh& mesh, const std::vector<std::uint8_t>& on_crease,
                           const QualityReuse* reuse, std::span<const Aabb> locks, PolygonizeStats& stats) {
  const MemoryReservation held(budget, kQualityBytesPerVertex * double(mesh.positions.size()),
                               "the quality pass on " + std::to_string(mesh.positions.size()) + " vertices");
  const double T = root_field.T;
  const BatchField on_bricks = [&field](std::span<const glm::dvec3> p, std::span<double> v) { field.values(p, v); };
  std::vector<std::uint8_t> keep = on_crease;
  if (!keep.empty()) {
    const std::vector<std::uint8_t> any(keep.size(), 1), near = rings_around(mesh, on_crease, any, 2);
    for (std::size_t v = 0; v < keep.size(); ++v)
      if (!keep[v] && near[v]) keep[v] = kNearCrease;
  }
  if (!locks.empty()) {
    keep.resize(mesh.positions.size(), 0);
    for (std::size_t v = 0; v < keep.size(); ++v)
      for (const Aabb& box : locks)
        if (box.contains(mesh.positions[v])) keep[v] = kPinned;
  }
  std::vector<std::uint8_t> crease_after;
  QualityStats st;
  improve_quality(mesh, keep, on_crease, on_bricks, T, h, options, &st, &crease_after, reuse);
  stats.quality += st;
  // With a cache, the regions of the mesh found clean by an earlier run are not searched again.
  const bool clean = reuse && brick::clean_by_regions(mesh, kSlabCells * h, *reuse->cache);
  auto left = clean ? std::vector<std::array<std::uint32_t, 2>>{}
                          : find_self_intersections(mesh, std::numeric_limits<std::size_t>::max()).examples;
  stats.quality_intersections += left.size();
  stats.crease_intersections = left.size();
  if (!left.empty()) resolve_folds(mesh, crease_after, root_field.get(), T, h, left, stats);
  RetryRequest retry;
  auto box_around = [&](std::span<const std::uint32_t> triangles, double cells) {
    Aabb box;
    for (const std::uint32_t t : triangles)
      for (int k = 0; k < 3; ++k) box.grow(mesh.positions[mesh.triangles[t][k]]);
    retry.boxes.push_back(box.expanded(cells * h));
  };
  if (locks.empty()) {  // a run with locks asks for no other
    for (const auto& pair : left) box_around(pair, kFoldLockCells);
    retry.crossing = !left.empty();
  }
  // After the boxes are taken: collapses renumber the triangles `left` names. What the crease
  // step left folded was the pass's to work on: what is left now is all there is.
  stats.folds.pairs_after = 0;
  const BatchGradient gradient = gradient_of(field);
  stats.folds += unfold_folded(mesh, crease_after, gradient, T);
  // Triangles left turned over that no collapse mends (beside a crease, where crease points stay)
  // are mostly the pass's doing: the extracted vertices in their boxes are kept on the next run,
  // whose result is taken when it has fewer folds and no smaller angle. (Boxes two
  // cells wide kept raw slivers of 0.2 degrees beside the folds of tests/data/stress/
  // folded_minmax_union.json; the triangle's own box mends them with its smallest angle 9 degrees.)
  if (locks.empty() && stats.folds.pairs_after > 0)
    for (const std::uint32_t t : folded_triangles(mesh, gradient)) box_around(std::span(&t, 1), 0.0);
  return retry;
}

}  // namespace ht
