// Spatial regrouping for the optimizer (the paper's section 4: reorganize the tree "with
// respect to a spatial criterion of minimizing the overlapping volume between objects"): the
// operands of an n-ary blend or min/max Boolean, as boxes, split top-down into a hierarchy of
// small groups whose boxes overlap little. Each split picks the axis and the place along it that
// minimize the summed volume of the two sides' boxes weighted by their operand counts (a
// volume form of the surface-area heuristic: the expected operands a random point meets).
// Large sets split in parallel (TBB); the result depends only on the boxes, never on threads.
#pragma once

#include "runtime/aabb.hpp"

#include <cstdint>
#include <span>
#include <vector>

namespace ht::optimize_detail {

/// A node of the hierarchy: a group of operands (items, indices into the boxes, in increasing
/// order) or a group of groups (parts, at most `fanout` of them).
struct Group {
  std::vector<std::uint32_t> items;
  std::vector<Group> parts;
};

/// The hierarchy over every box; groups hold at most `fanout` (>= 2) operands or parts.
Group spatial_groups(std::span<const Aabb> boxes, int fanout);

}  // namespace ht::optimize_detail
