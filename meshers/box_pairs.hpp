// The pairs of boxes that overlap, for boxes of about one size (a surface mesh's triangles): a
// uniform grid of cells about as large as the average box, each box filed in every cell it
// meets, and each overlapping pair reported from one cell only, the one holding the lower corner
// of the two boxes' intersection. Exact: boxes compare in double, closed (touching boxes
// overlap), and the cell of a coordinate is a monotone function of it, so that corner's cell is
// one both boxes were filed in.
//
// Quicker than a box hierarchy's self-collision on such boxes (no build, no leaf pairs to filter);
// for boxes of very different sizes or spread far apart (a grid that would hold too many cells or
// entries), it declines and the caller uses its hierarchy.
#pragma once

#include <glm/vec3.hpp>

#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <vector>

namespace ht {

struct BoxPairOptions {
  double max_entries_per_box = 16.0;  ///< decline when boxes meet more cells than this on average
  double max_cells_per_box = 64.0;    ///< decline when the grid has more cells than this per box
};

/// The pairs i < j with skip[i] == skip[j] == 0 whose closed boxes [lo, hi] overlap, each once,
/// as (i << 32) | j in lists (one per worker chunk, in no order); nullopt when the boxes are not
/// even enough for a grid (see above). lo, hi and skip have one entry per box; coordinates must
/// be finite. Uses the TBB thread pool; the set of pairs does not depend on the thread count.
std::optional<std::vector<std::vector<std::uint64_t>>> grid_box_pairs(std::span<const glm::dvec3> lo,
                                                                      std::span<const glm::dvec3> hi,
                                                                      std::span<const std::uint8_t> skip,
                                                                      const BoxPairOptions& options = {});

/// The same pairs handed over as they are found, batch by batch (a batch: the pairs of a range of
/// cells, at most 65,536, in no order), to `each`, called from TBB's worker threads, several at
/// once; nothing is stored beyond a batch. False (and no call) when the boxes are not even enough
/// for a grid.
bool grid_box_pairs(std::span<const glm::dvec3> lo, std::span<const glm::dvec3> hi, std::span<const std::uint8_t> skip,
                    const std::function<void(std::span<const std::uint64_t>)>& each, const BoxPairOptions& options = {});

}  // namespace ht
