// Procedural scenes shared by the CLI, the tests and the benchmarks.
#pragma once

#include "runtime/builder.hpp"

#include <cstdint>
#include <memory>
#include <string>

namespace ht::scenes {

/// A snake-like character made of `count` blended curve primitives, the analogue of the
/// paper's 250-spline snake-woman: a sinuous body that thins toward the tail, a head, and
/// small fins along the back. Deterministic for a given count and seed.
NodeId snake(Builder& b, int count = 250, std::uint64_t seed = 1);

/// The same as scene-format JSON text (for `hybridtree generate` and the CLI tests).
std::string snake_json(int count = 250, std::uint64_t seed = 1);

/// One node of every kind but ffd (every skeleton, a mesh leaf on `mesh`, blend, the three
/// Booleans in both modes, local blend, crop, affine, twist, taper, bend), about 2 units wide.
NodeId every_kind(Builder& b, std::shared_ptr<const MeshLeaf> mesh);

/// A mesh leaf blended with primitives that touch it (the paper's Figure 4 set-up).
NodeId mesh_with_primitives(Builder& b, std::shared_ptr<const MeshLeaf> mesh);

/// `count` small primitives of every skeleton scattered in a cube (side 1.6 * cbrt(count) units,
/// so they overlap here and there), one in ten under a rotating, scaling affine map, written as
/// a user who adds them one by one would: a left-deep chain of binary blends, in random order.
/// What the optimizer (runtime/optimize.hpp) is for. Deterministic for a given count and seed.
NodeId scatter(Builder& b, int count = 900, std::uint64_t seed = 1);

/// count point primitives of radius 0.6 on a grid of unit spacing, blended.
NodeId point_grid(Builder& b, int count);

}  // namespace ht::scenes
