// Procedural scenes shared by the CLI, the tests and the benchmarks.
#pragma once

#include "runtime/builder.hpp"

#include <cstdint>
#include <string>

namespace ht::scenes {

/// A snake-like character made of `count` blended curve primitives, the analogue of the
/// paper's 250-spline snake-woman: a sinuous body that thins toward the tail, a head, and
/// small fins along the back. Deterministic for a given count and seed.
NodeId snake(Builder& b, int count = 250, std::uint64_t seed = 1);

/// The same as scene-format JSON text (for `hybridtree generate` and the CLI tests).
std::string snake_json(int count = 250, std::uint64_t seed = 1);

}  // namespace ht::scenes
