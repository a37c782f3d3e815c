// A blend's patch sampled operand by operand (PolygonizeOptions::region_operands): the
// polygonizer learns, at every grid point of a brick, whether two operands act there, and
// meshes only the cells with a corner where they do. Internal to the polygonizer (meshers/polygonize.cpp),
// beside the per-brick extraction of meshers/brick_extract.hpp.
#pragma once

#include "meshers/brick_extract.hpp"
#include "runtime/tape.hpp"

#include <cstdint>
#include <memory>
#include <span>

namespace ht::brick {

/// Samples the operands' tapes (`operands`, one per operand, in the blend's order) at n <= kBlock
/// points: value[i] gets their sum, the blend's field (summed in operand order), and region[i]
/// the sum of their |f| but the largest, positive exactly where two operands act at once.
void sum_operands(std::span<const std::shared_ptr<const Tape>> operands, const float* xs, const float* ys,
                  const float* zs, int n, float* value, float* region);

/// Which of a brick's kCells^3 cells (x fastest) to mesh, from its grid points' region values
/// (kBrickPoints, x fastest; NaN where not sampled): those with a corner where two operands act
/// (the value is positive). Fields vanish outside their supports, so a cell none of whose
/// corners lies in two supports is at most grazed by their overlap, where the patch's cut (at
/// 1e-3 T, meshers/local_blends.cpp) keeps nothing: a support reaches that far into a cell
/// between its corners only when its radius is about a cell.
void region_cells(const float* region, std::uint8_t* keep);

}  // namespace ht::brick
