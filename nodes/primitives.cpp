// Exact skeleton distances. References: Ericson, "Real-Time Collision Detection" (2005), 5.1.5
// for the closest point on a triangle by Voronoi regions; Bloomenthal & Wyvill, "Interactive
// techniques for implicit modeling" (1990) for skeletal primitives.
#include "nodes/primitives.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>

namespace ht {
namespace {

glm::dvec3 vec_at(const double* s, int i) { return {s[i], s[i + 1], s[i + 2]}; }

// Distance from p to a circle (curve) or a disc (surface) of radius rho: work in the plane of
// the skeleton with h the height above it and r the distance to the axis.
double distance_to_circle_or_disc(const double* s, const glm::dvec3& p, bool filled) {
  const glm::dvec3 q = p - vec_at(s, 0);
  const glm::dvec3 n = vec_at(s, 3);
  const double rho = s[6];
  const double h = glm::dot(q, n);
  const double r = glm::length(q - h * n);
  double radial = r - rho;
  if (filled) radial = std::max(radial, 0.0);
  return std::sqrt(h * h + radial * radial);
}

double distance_to_box(const double* s, const glm::dvec3& p) {
  const glm::dvec3 lo = vec_at(s, 0), hi = vec_at(s, 3);
  const glm::dvec3 outside = glm::max(glm::max(lo - p, p - hi), glm::dvec3(0.0));
  return glm::length(outside);
}

double distance_to_cylinder(const double* s, const glm::dvec3& p) {
  const glm::dvec3 a = vec_at(s, 0), b = vec_at(s, 3);
  const double rho = s[6];
  const glm::dvec3 axis = b - a;
  const double len = glm::length(axis);
  const glm::dvec3 u = axis / len;
  const double t = glm::dot(p - a, u);
  const double r = glm::length((p - a) - t * u);
  const double radial = std::max(r - rho, 0.0);
  const double along = std::max({-t, t - len, 0.0});
  return std::sqrt(radial * radial + along * along);
}

// The convex hull of two spheres: in the half-plane (x along a->b, y radial) its boundary is
// an arc of each circle joined by the common outer tangent, whose outward normal makes angle
// alpha with the radial direction, sin(alpha) = (ra - rb) / L.
double distance_to_cone_sphere(const double* s, const glm::dvec3& p) {
  const glm::dvec3 a = vec_at(s, 0), b = vec_at(s, 3);
  const double ra = s[6], rb = s[7];
  const glm::dvec3 axis = b - a;
  const double len = glm::length(axis);
  if (len <= std::abs(ra - rb)) {  // one sphere holds the other: the hull is the larger sphere
    const bool a_big = ra >= rb;
    return std::max(glm::length(p - (a_big ? a : b)) - (a_big ? ra : rb), 0.0);
  }
  const glm::dvec3 u = axis / len;
  const double x = glm::dot(p - a, u);
  const double y = glm::length((p - a) - x * u);
  const double sin_a = (ra - rb) / len;
  const double cos_a = std::sqrt(1.0 - sin_a * sin_a);
  // The tangent line has normal (sin, cos) in (x, y); it touches circle a at ra*(sin, cos) and
  // circle b at L*cos farther along its direction (cos, -sin). The normals at the two contacts
  // pass through the centres and split the half-plane into the regions of a, the line, and b.
  const double along = x * cos_a - y * sin_a;
  double signed_dist;
  if (along < 0.0)
    signed_dist = std::sqrt(x * x + y * y) - ra;
  else if (along > len * cos_a)
    signed_dist = std::sqrt((x - len) * (x - len) + y * y) - rb;
  else
    signed_dist = y * cos_a + x * sin_a - ra;
  return std::max(signed_dist, 0.0);
}

// |p - nearest point of [a, b]|^2, computed as distance_to_segment() computes it before its root.
double distance2_to_segment(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b) {
  const glm::dvec3 ab = b - a;
  const double len2 = glm::dot(ab, ab);
  const double t = len2 > 0.0 ? std::clamp(glm::dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
  const glm::dvec3 d = p - (a + t * ab);
  return glm::dot(d, d);
}

double distance_to_polyline(const double* s, const glm::dvec3& p) {
  const auto n = static_cast<std::size_t>(s[0]);
  const double* pts = s + 1;
  if (n == 1) return glm::length(p - vec_at(pts, 0));
  // The least squared distance, then one square root: the same bits as the least of the
  // distances (a correctly rounded square root keeps order), one root instead of dozens.
  double best2 = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const auto k = static_cast<int>(3 * i);
    best2 = std::min(best2, distance2_to_segment(p, vec_at(pts, k), vec_at(pts, k + 3)));
  }
  return std::sqrt(best2);
}

}  // namespace

double primitive_r0(double R, double F, double T) {
  if (!(F > T)) return 0.0;
  return R * std::sqrt(1.0 - std::cbrt(T / F));
}

double distance_to_segment(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b) {
  return std::sqrt(distance2_to_segment(p, a, b));
}

double distance_to_triangle(const glm::dvec3& p, const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
  return glm::length(p - closest_on_triangle(p, a, b, c).point);
}

double skeleton_distance(NodeKind kind, const double* s, const glm::dvec3& p) {
  switch (kind) {
    case NodeKind::Point: return glm::length(p - vec_at(s, 0));
    case NodeKind::Segment: return distance_to_segment(p, vec_at(s, 0), vec_at(s, 3));
    case NodeKind::Circle: return distance_to_circle_or_disc(s, p, false);
    case NodeKind::Disc: return distance_to_circle_or_disc(s, p, true);
    case NodeKind::Triangle: return distance_to_triangle(p, vec_at(s, 0), vec_at(s, 3), vec_at(s, 6));
    case NodeKind::Curve: return distance_to_polyline(s, p);
    case NodeKind::Box: return distance_to_box(s, p);
    case NodeKind::Cylinder: return distance_to_cylinder(s, p);
    case NodeKind::ConeSphere: return distance_to_cone_sphere(s, p);
    default: return std::numeric_limits<double>::infinity();
  }
}

Aabb skeleton_bounds(NodeKind kind, const double* s) {
  Aabb box;
  switch (kind) {
    case NodeKind::Point: box.grow(vec_at(s, 0)); break;
    case NodeKind::Segment:
      box.grow(vec_at(s, 0));
      box.grow(vec_at(s, 3));
      break;
    case NodeKind::Circle:
    case NodeKind::Disc: {
      // A circle of radius rho with unit normal n reaches rho*sqrt(1 - n_i^2) along axis i.
      const glm::dvec3 n = vec_at(s, 3);
      const glm::dvec3 reach = s[6] * glm::sqrt(glm::max(glm::dvec3(1.0) - n * n, glm::dvec3(0.0)));
      box.grow(vec_at(s, 0) - reach);
      box.grow(vec_at(s, 0) + reach);
      break;
    }
    case NodeKind::Triangle:
      for (int i = 0; i < 9; i += 3) box.grow(vec_at(s, i));
      break;
    case NodeKind::Curve: {
      const auto n = static_cast<int>(s[0]);
      for (int i = 0; i < n; ++i) box.grow(vec_at(s + 1, 3 * i));
      break;
    }
    case NodeKind::Box:
      box.grow(vec_at(s, 0));
      box.grow(vec_at(s, 3));
      break;
    case NodeKind::Cylinder: {
      const glm::dvec3 a = vec_at(s, 0), b = vec_at(s, 3);
      const glm::dvec3 u = glm::normalize(b - a);
      const glm::dvec3 reach = s[6] * glm::sqrt(glm::max(glm::dvec3(1.0) - u * u, glm::dvec3(0.0)));
      box.grow(a - reach);
      box.grow(a + reach);
      box.grow(b - reach);
      box.grow(b + reach);
      break;
    }
    case NodeKind::ConeSphere: {
      const glm::dvec3 a = vec_at(s, 0), b = vec_at(s, 3);
      box.grow(a - s[6]);
      box.grow(a + s[6]);
      box.grow(b - s[7]);
      box.grow(b + s[7]);
      break;
    }
    default: break;
  }
  return box;
}

glm::dvec3 catmull_rom(std::span<const glm::dvec3> pts, std::size_t i, double t) {
  const std::size_t n = pts.size();
  const glm::dvec3 p0 = pts[i == 0 ? 0 : i - 1], p1 = pts[i], p2 = pts[std::min(i + 1, n - 1)],
                   p3 = pts[std::min(i + 2, n - 1)];
  const double t2 = t * t, t3 = t2 * t;
  return 0.5 * (2.0 * p1 + (p2 - p0) * t + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * t2 +
                (-p0 + 3.0 * p1 - 3.0 * p2 + p3) * t3);
}

std::vector<glm::dvec3> curve_polyline(std::span<const glm::dvec3> pts, double tolerance) {
  std::vector<glm::dvec3> out;
  const std::size_t n = pts.size();
  if (n == 0) return out;
  out.push_back(pts[0]);
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const glm::dvec3 p0 = pts[i == 0 ? 0 : i - 1], p1 = pts[i], p2 = pts[i + 1],
                     p3 = pts[std::min(i + 2, n - 1)];
    // C''(t) = (2p0 - 5p1 + 4p2 - p3) + 3(-p0 + 3p1 - 3p2 + p3) t is linear in t, so its norm
    // peaks at an end of the span.
    const glm::dvec3 c2 = 2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3;
    const glm::dvec3 c3 = 3.0 * (-p0 + 3.0 * p1 - 3.0 * p2 + p3);
    const double peak = std::max(glm::length(c2), glm::length(c2 + c3));
    const double chords = std::ceil(std::sqrt(peak / (8.0 * tolerance)));
    const int count = static_cast<int>(std::clamp(chords, 1.0, 4096.0));
    for (int k = 1; k <= count; ++k) out.push_back(catmull_rom(pts, i, double(k) / count));
  }
  return out;
}

}  // namespace ht
