// Affine maps as the optimizer sees them: composing two affine nodes into one, and folding a
// similarity (rotation, reflection, uniform scale, translation) into a primitive's parameters.
// A primitive's field is g(distance to its skeleton); under a similarity of scale s the
// distance scales by s, so moving the skeleton and scaling R (and the skeleton's own radii) by
// s gives exactly the warped field (nodes/primitives.hpp has the layouts).
#pragma once

#include "nodes/kinds.hpp"

#include <span>
#include <vector>

namespace ht::optimize_detail {

/// The affine node's 24 parameters (nodes/warps.hpp) for outer applied after inner
/// (world = outer(inner(p))); false when the product is singular.
bool compose_affine(std::span<const double> outer24, std::span<const double> inner24, std::vector<double>& out24);

/// Whether the affine map is the identity (to 1e-15 relative).
bool affine_is_identity(std::span<const double> params24);

/// The primitive's parameters moved by the affine map, or false when the map is not a
/// similarity that kind can take (a box takes only a positive uniform scale and a translation).
bool fold_affine(NodeKind kind, std::span<const double> affine24, std::span<const double> primitive,
                 std::vector<double>& out);

}  // namespace ht::optimize_detail
