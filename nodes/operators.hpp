// Blends, Booleans, local blend and crop: how a node combines its children's field values
// (the paper, sections 3.2.1-3.2.3; exact formulas in SCENE_FORMAT.md, crop's in docs/crop.md).
#pragma once

#include "nodes/kinds.hpp"
#include "runtime/aabb.hpp"

#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>

namespace ht {

// R-functions shifted to threshold T and weighted so the result keeps a compact support:
// with a = fA - T, b = fB - T, both vanish where fA = fB = 0.
inline constexpr double kRUnionWeight = 1.0 / (2.0 - 1.4142135623730950488);
inline constexpr double kRIntersectionWeight = 1.0 / (2.0 + 1.4142135623730950488);

inline double union_field(double fa, double fb, double T, bool rfunction) {
  if (!rfunction) return std::max(fa, fb);
  const double a = fa - T, b = fb - T;
  return T + (a + b + std::sqrt(a * a + b * b)) * kRUnionWeight;
}

inline double intersection_field(double fa, double fb, double T, bool rfunction) {
  if (!rfunction) return std::min(fa, fb);
  const double a = fa - T, b = fb - T;
  return T + (a + b - std::sqrt(a * a + b * b)) * kRIntersectionWeight;
}

/// A - B = max(0, A intersect complement(B)), with f(complement B) = 2T - fB.
inline double difference_field(double fa, double fb, double T, bool rfunction) {
  return std::max(0.0, intersection_field(fa, 2.0 * T - fb, T, rfunction));
}

/// fR (fA + fB) + (1 - fR) f(A union B), with fR clamped to [0, 1].
inline double local_blend_field(double fa, double fb, double fr, double T, bool rfunction) {
  const double w = std::clamp(fr, 0.0, 1.0);
  return w * (fa + fb) + (1.0 - w) * union_field(fa, fb, T, rfunction);
}

/// Crop keeps the child's solid inside the box [lo, hi]:
///   f = max(0, min(f_child, h)),  h(p) = T (1 - s(p) / L),
/// with s the signed distance to the box (negative inside) and L half the box's smallest side.
/// h = T on the box's faces, so the surface is the child's surface cut by the box; f is
/// continuous, 0 wherever the child is 0, and 0 farther than L outside the box.
double crop_box_field(const double* box6, double T, const glm::dvec3& p);
/// The distance beyond the box at which crop reaches 0: L.
double crop_reach(const double* box6);

/// True when the `auto` Boolean rule picks R-functions: under a blend or local blend.
inline bool use_rfunction(BooleanMode mode, bool under_blend) {
  return mode == BooleanMode::RFunction || (mode == BooleanMode::Auto && under_blend);
}

}  // namespace ht
