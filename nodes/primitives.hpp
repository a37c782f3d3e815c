// Skeletal implicit primitives: the nine skeletons of SCENE_FORMAT.md, their exact distance
// functions, their support boxes, and the compact-support falloff g (the paper, section 3.1.1).
//
// A primitive's parameters live in the graph's parameter pool as plain doubles:
//   [0] R (radius of influence)   [1] F (strength)   [2...] the skeleton, laid out below.
// The skeleton layouts (offsets relative to [2]):
//   point        center(3)
//   segment      a(3) b(3)
//   circle       center(3) unit normal(3) circle_radius
//   disc         center(3) unit normal(3) disc_radius
//   triangle     a(3) b(3) c(3)
//   curve        n, then n control points(3n). Distances read a derived block instead (the
//                graph keeps it apart): m, then m polyline points(3m), the Catmull-Rom spline
//                sampled within kCurveTolerance*R (see curve_polyline).
//   box          min(3) max(3)
//   cylinder     a(3) b(3) cylinder_radius
//   cone_sphere  a(3) b(3) radius_a radius_b
#pragma once

#include "nodes/kinds.hpp"
#include "runtime/aabb.hpp"

#include <glm/vec3.hpp>

#include <span>
#include <vector>

namespace ht {

inline constexpr int kPrimR = 0;
inline constexpr int kPrimF = 1;
inline constexpr int kPrimSkeleton = 2;

/// The curve's distance is the distance to a polyline within this fraction of R of the spline.
inline constexpr double kCurveTolerance = 0.5e-4;

/// g(d) = F (1 - d^2/R^2)^3 for d < R, exactly 0 at and beyond R.
inline double falloff(double d, double R, double F) {
  if (!(d < R)) return 0.0;
  const double u = 1.0 - (d * d) / (R * R);
  return F * u * u * u;
}

/// r0 = g^-1(T): the distance from the skeleton of a lone primitive to its surface; 0 when the
/// primitive is not visible on its own (F <= T).
double primitive_r0(double R, double F, double T);

/// Euclidean distance from p to the skeleton of a primitive of kind `kind` (0 on it, and inside
/// it for the volume skeletons). `skeleton` points at the layout above (for a curve: at its
/// polyline block, Graph::skeleton_of).
double skeleton_distance(NodeKind kind, const double* skeleton, const glm::dvec3& p);

/// The box holding the skeleton (not expanded by R).
Aabb skeleton_bounds(NodeKind kind, const double* skeleton);

/// Samples the uniform Catmull-Rom spline through `points` (end points repeated) into a polyline
/// whose Hausdorff distance to the spline is at most `tolerance`: per span, n chords with
/// n = ceil(sqrt(max|C''| / (8 tolerance))), the chord error bound of a C2 curve.
std::vector<glm::dvec3> curve_polyline(std::span<const glm::dvec3> points, double tolerance);

/// The point of the uniform Catmull-Rom spline on span i (0 <= i < n-1) at t in [0, 1].
glm::dvec3 catmull_rom(std::span<const glm::dvec3> points, std::size_t span, double t);

/// Exact distance helpers, shared with the tests and the meshers.
double distance_to_segment(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b);
double distance_to_triangle(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b,
                            const glm::dvec3& c);

}  // namespace ht
