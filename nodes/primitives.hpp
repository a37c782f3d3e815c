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

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <algorithm>

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
/// whose Hausdorff distance to the spline is at most `tolerance`: each span's chords halved until
/// each fits, by the chord error bound of a C2 curve (dt^2/8 max|C''|), or, where the spline runs
/// forward along the chord, by the same bound on the part of C'' across it (a straight stretch is
/// one chord however unevenly its parameter runs). At most 4096 chords a span.
std::vector<glm::dvec3> curve_polyline(std::span<const glm::dvec3> points, double tolerance);

/// The point of the uniform Catmull-Rom spline on span i (0 <= i < n-1) at t in [0, 1].
glm::dvec3 catmull_rom(std::span<const glm::dvec3> points, std::size_t span, double t);

/// The closest point of triangle (a, b, c) to p and the feature it lies on: kTriangleFace,
/// kTriangleEdge + k (the edge from corner k to k+1) or kTriangleVertex + k. A zero-area
/// triangle has no face: its closest point is on one of its edges.
struct TrianglePoint {
  glm::dvec3 point;
  int feature;
};
inline constexpr int kTriangleFace = 0, kTriangleEdge = 1, kTriangleVertex = 4;

namespace detail {
inline TrianglePoint closest_on_segment(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b, int k) {
  const glm::dvec3 ab = b - a;
  const double len2 = glm::dot(ab, ab);
  const double s = len2 > 0 ? glm::dot(p - a, ab) / len2 : 0.0;
  if (s <= 0) return {a, kTriangleVertex + k};
  if (s >= 1) return {b, kTriangleVertex + (k + 1) % 3};
  return {a + s * ab, kTriangleEdge + k};
}
}  // namespace detail

// Inline: it is the inner step of every mesh-leaf point query.
inline TrianglePoint closest_on_triangle(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
  // Walk the Voronoi regions of the vertices, then the edges, then the face. A zero-area
  // triangle has no face region and its region tests round badly: it is its three edges.
  const glm::dvec3 ab = b - a, ac = c - a, ap = p - a;
  const double scale2 = std::max({glm::dot(ab, ab), glm::dot(ac, ac), glm::dot(c - b, c - b)});
  const glm::dvec3 n = glm::cross(ab, ac);
  if (!(glm::dot(n, n) > 1e-24 * scale2 * scale2)) {
    TrianglePoint best = detail::closest_on_segment(p, a, b, 0);
    double bd = glm::dot(p - best.point, p - best.point);
    for (const TrianglePoint& q : {detail::closest_on_segment(p, b, c, 1), detail::closest_on_segment(p, c, a, 2)}) {
      const double d = glm::dot(p - q.point, p - q.point);
      if (d < bd) bd = d, best = q;
    }
    return best;
  }
  const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return {a, kTriangleVertex + 0};
  const glm::dvec3 bp = p - b;
  const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return {b, kTriangleVertex + 1};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return {a + (d1 / (d1 - d3)) * ab, kTriangleEdge + 0};
  const glm::dvec3 cp = p - c;
  const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return {c, kTriangleVertex + 2};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return {a + (d2 / (d2 - d6)) * ac, kTriangleEdge + 2};
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
    return {b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b), kTriangleEdge + 1};
  const double denom = va + vb + vc;
  return {a + (vb / denom) * ab + (vc / denom) * ac, kTriangleFace};
}

/// Exact distance helpers, shared with the tests and the meshers.
double distance_to_segment(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b);
double distance_to_triangle(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b,
                            const glm::dvec3& c);

}  // namespace ht
