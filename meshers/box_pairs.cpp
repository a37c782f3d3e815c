#include "meshers/box_pairs.hpp"

#include <glm/common.hpp>
#include <glm/vector_relational.hpp>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace ht {
namespace {

using glm::dvec3;

// Cells this many average box sides large: a box meets about (1 + 1 / kCellSides)^3 cells, and
// the grid's arrays stay small enough to be read from cache.
constexpr double kCellSides = 2.0;

// Cells of side `cell` from `origin`, dims[k] along axis k. A coordinate's cell is the floor of
// (x - origin) / cell clamped to the grid: rounding is monotone, so a larger x never gets a
// smaller cell, which is all the reporting rule needs.
struct Grid {
  dvec3 origin;
  double cell;
  std::size_t dims[3];

  std::uint32_t axis(double x, int k) const {
    const double f = std::floor((x - origin[k]) / cell);
    return std::uint32_t(std::clamp(f, 0.0, double(dims[k] - 1)));
  }
  std::size_t index(std::size_t x, std::size_t y, std::size_t z) const { return x + dims[0] * (y + dims[1] * z); }
};

bool overlap(const dvec3& alo, const dvec3& ahi, const dvec3& blo, const dvec3& bhi) {
  for (int k = 0; k < 3; ++k)
    if (ahi[k] < blo[k] || bhi[k] < alo[k]) return false;
  return true;
}

// The grid for the boxes not skipped: cells kCellSides times their average longest side, over their
// bounds; nullopt when it would have more than max_cells_per_box cells a box.
std::optional<Grid> grid_for(std::span<const dvec3> lo, std::span<const dvec3> hi, std::span<const std::uint8_t> skip,
                             double max_cells_per_box) {
  dvec3 all_lo(std::numeric_limits<double>::max()), all_hi(-std::numeric_limits<double>::max());
  double sides = 0.0;
  std::size_t count = 0;
  for (std::size_t i = 0; i < lo.size(); ++i) {
    if (skip[i]) continue;
    all_lo = glm::min(all_lo, lo[i]), all_hi = glm::max(all_hi, hi[i]);
    const dvec3 d = hi[i] - lo[i];
    sides += std::max(d.x, std::max(d.y, d.z));
    ++count;
  }
  Grid g{all_lo, count ? kCellSides * sides / double(count) : 0.0, {1, 1, 1}};
  if (!(g.cell > 0.0) || !std::isfinite(g.cell)) return std::nullopt;
  double cells = 1.0;
  for (int k = 0; k < 3; ++k) {
    const double n = std::floor((all_hi[k] - all_lo[k]) / g.cell) + 1.0;
    if (!(n < double(1 << 21))) return std::nullopt;
    g.dims[k] = std::size_t(n);
    cells *= n;
  }
  if (cells > max_cells_per_box * double(count) + 1024.0) return std::nullopt;
  return g;
}

}  // namespace

std::optional<std::vector<std::vector<std::uint64_t>>> grid_box_pairs(std::span<const dvec3> lo, std::span<const dvec3> hi,
                                                                      std::span<const std::uint8_t> skip,
                                                                      const BoxPairOptions& options) {
  tbb::enumerable_thread_specific<std::vector<std::uint64_t>> found;
  const bool gridded = grid_box_pairs(
      lo, hi, skip,
      [&](std::span<const std::uint64_t> batch) {
        auto& out = found.local();
        out.insert(out.end(), batch.begin(), batch.end());
      },
      options);
  if (!gridded) return std::nullopt;
  std::vector<std::vector<std::uint64_t>> lists;
  for (auto& v : found) lists.push_back(std::move(v));
  return lists;
}

bool grid_box_pairs(std::span<const dvec3> lo, std::span<const dvec3> hi, std::span<const std::uint8_t> skip,
                    const std::function<void(std::span<const std::uint64_t>)>& each, const BoxPairOptions& options) {
  // A batch is handed over at this many pairs: one cell that many boxes meet (the hub of a fan of
  // 20,000 long thin triangles) has the square of them, 2 GB of pairs held at once before.
  constexpr std::size_t kBatchPairs = std::size_t(1) << 16;
  const std::optional<Grid> grid = grid_for(lo, hi, skip, options.max_cells_per_box);
  if (!grid) return false;
  const Grid& g = *grid;
  // The cells each box meets, from its lower corner's to its upper corner's.
  const std::size_t n = lo.size(), cells = g.dims[0] * g.dims[1] * g.dims[2];
  std::vector<glm::u32vec3> first(n), last(n);
  tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) {
    for (int k = 0; k < 3; ++k) first[i][k] = g.axis(lo[i][k], k), last[i][k] = g.axis(hi[i][k], k);
  });
  auto for_cells = [&](std::size_t i, auto&& f) {
    for (std::uint32_t z = first[i].z; z <= last[i].z; ++z)
      for (std::uint32_t y = first[i].y; y <= last[i].y; ++y)
        for (std::uint32_t x = first[i].x; x <= last[i].x; ++x) f(g.index(x, y, z));
  };
  // Each box filed in its cells by a counting sort, a cell listing its boxes in increasing order:
  // start[c + 1] counts cell c's boxes, then (summed) ends its run; filling from the last box
  // down moves it to the run's start, which is where cell c - 1's run ends.
  std::vector<std::uint32_t> start(cells + 2, 0);
  double entries = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    if (skip[i]) continue;
    for_cells(i, [&](std::size_t c) { ++start[c + 1], ++entries; });
    if (entries > options.max_entries_per_box * double(n) + 1024.0 || entries > 4e9) return false;
  }
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<std::uint32_t> boxes(start.back());
  for (std::size_t i = n; i-- > 0;)
    if (!skip[i]) for_cells(i, [&](std::size_t c) { boxes[--start[c + 1]] = std::uint32_t(i); });
  start.erase(start.begin());
  // The pairs of each cell whose intersection's lower corner lies in it: that corner is the
  // larger of the two lower corners, and its cell (the cell function being monotone) the larger
  // of their cells, axis by axis.
  // A cell's boxes are copied together first: the pairs then read them from cache, not from
  // wherever their triangles lie in the mesh.
  struct Local {
    dvec3 lo, hi;
    glm::u32vec3 first;
    std::uint32_t box;
  };
  struct Scratch {
    std::vector<std::uint64_t> found;
    std::vector<Local> cell;
  };
  tbb::enumerable_thread_specific<Scratch> scratch;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cells, 4096), [&](const tbb::blocked_range<std::size_t>& range) {
    Scratch& s = scratch.local();
    s.found.clear();
    for (std::size_t c = range.begin(); c != range.end(); ++c) {
      if (start[c + 1] - start[c] < 2) continue;
      const glm::u32vec3 at(c % g.dims[0], (c / g.dims[0]) % g.dims[1], c / (g.dims[0] * g.dims[1]));
      s.cell.clear();
      for (std::uint32_t a = start[c]; a < start[c + 1]; ++a) {
        const std::uint32_t i = boxes[a];
        s.cell.push_back({lo[i], hi[i], first[i], i});
      }
      for (std::size_t a = 0; a < s.cell.size(); ++a)
        for (std::size_t b = a + 1; b < s.cell.size(); ++b) {
          const Local &p = s.cell[a], &q = s.cell[b];
          if (glm::max(p.first, q.first) == at && overlap(p.lo, p.hi, q.lo, q.hi)) {
            s.found.push_back(std::uint64_t(p.box) << 32 | q.box);
            if (s.found.size() == kBatchPairs) each(s.found), s.found.clear();
          }
        }
    }
    if (!s.found.empty()) each(s.found);
  });
  return true;
}

}  // namespace ht
