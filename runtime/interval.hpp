// The interval rules one node applies, shared by the graph-level analysis (field_interval,
// runtime/interval.cpp) and the tape-level one (narrow_tape, runtime/tape_narrow.cpp): a leaf's
// range over a box, the box a warp's child sees, and each operator's range from its operands'.
// Every rule is conservative (it holds the exact range) and follows a formula of SCENE_FORMAT.md.
#pragma once

#include "runtime/aabb.hpp"
#include "runtime/graph.hpp"
#include "runtime/tape.hpp"

namespace ht::interval {

/// A primitive, a mesh leaf or a prepared ffd (its deformed mesh) over `box`.
Interval leaf(const Graph& g, NodeId n, double T, const Aabb& box);
/// The box in which a warp's child is asked when its parent is asked in `box` (w^-1(box)), or
/// false when no bound is known (bend).
bool warp_child_region(const Graph& g, NodeId n, const Aabb& box, Aabb& out);
/// A crop node whose child ranges over `child`, its frame over `box`.
Interval crop(const Graph& g, NodeId n, double T, const Aabb& box, Interval child);

Interval add(Interval a, Interval b);
Interval unite(Interval a, Interval b, double T, bool rfunction);
Interval intersect(Interval a, Interval b, double T, bool rfunction);
/// A minus B.
Interval subtract(Interval a, Interval b, double T, bool rfunction);
/// The local blend of A and B with weight field r (clamped to [0, 1]).
Interval local_blend(Interval a, Interval b, Interval r, double T, bool rfunction);

}  // namespace ht::interval
