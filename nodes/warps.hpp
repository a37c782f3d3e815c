// Warps: a warp w maps its child's space to world space; the warped field is
// f(p) = f_child(w^-1(p)) (the paper, section 3.3). Affine maps and Barr's twist, taper and
// bend (Barr 1984) have closed-form inverses; the free-form deformation (Sederberg & Parry 1986)
// has none, so its field goes through its deformed mesh (SCENE_FORMAT.md).
//
// Parameter layouts in the graph's pool (doubles):
//   affine  forward 3x4 row-major (12), then inverse 3x4 row-major (12)
//   twist   axis(0|1|2) center(3) rate
//   taper   axis center(3) h0 h1 s0 s1
//   bend    axis center(3) h0 h1 rate
//   ffd     min(3) max(3) l m n radius strength, then (l+1)(m+1)(n+1) control points (x fastest)
// For twist, taper and bend, h = (p - center)[axis]; the two other coordinates, taken in the
// cyclic order after the axis (for z: x then y), form the plane that turns by the right-hand
// rule. Bend curves the axis toward the first of them (for z: toward +x when rate > 0).
#pragma once

#include "nodes/kinds.hpp"
#include "runtime/aabb.hpp"

#include <glm/vec3.hpp>

namespace ht {

inline constexpr int kAffineParams = 24;
inline constexpr int kTwistParams = 5;
inline constexpr int kTaperParams = 8;
inline constexpr int kBendParams = 7;
inline constexpr int kFfdHeader = 11;
/// An ffd lattice has at most this many intervals along each axis (the scene format and the
/// builder refuse more; the deformation keeps one Bernstein basis an axis on the stack).
inline constexpr int kFfdMaxDim = 64;

/// w(p) for affine, twist, taper, bend and ffd.
glm::dvec3 warp_forward(NodeKind kind, const double* params, const glm::dvec3& p);
/// w^-1(p) for affine, twist, taper and bend. Bend is inverted exactly where it is one-to-one:
/// points nearer to the axis than the radius of curvature, within half a turn.
glm::dvec3 warp_inverse(NodeKind kind, const double* params, const glm::dvec3& p);
/// A box holding w(child_box) (conservative; exact for affine corners and Barr's rigid parts).
Aabb warp_bounds(NodeKind kind, const double* params, const Aabb& child_box);

/// Largest entry of an affine map's linear part times the largest of its inverse's: past this
/// the map and its inverse do not round-trip points to the scene format's tolerance.
inline constexpr double kMaxAffineCondition = 1e12;

/// Fills `forward` (12) and `inverse` (12) from a 3x4 row-major forward matrix; false when the
/// linear part is singular in doubles (no finite inverse, or a condition past kMaxAffineCondition).
bool affine_from_matrix(const double* forward3x4, double* out24);

/// Barr's bend of coordinates (u along the axis, v toward which it bends) for curvature k on
/// [h0, h1]: exposed for the tests and the meshers.
void bend_forward(double h0, double h1, double k, double& u, double& v);
void bend_inverse(double h0, double h1, double k, double& u, double& v);

}  // namespace ht
