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

namespace {

// One span of the spline, C(t) = a + b t + c t^2 + d t^3 on [0, 1], and its derivatives.
struct Span {
  glm::dvec3 a, b, c, d;
  glm::dvec3 at(double t) const { return a + t * (b + t * (c + t * d)); }
  glm::dvec3 bend(double t) const { return 2.0 * c + 6.0 * t * d; }  // C''
};

// Whether the chord of [t0, t1] lies within `tolerance` of the span there, both ways. Two bounds
// on e(t) = C(t) - chord(t), which is 0 at both ends: |e| <= dt^2/8 max|C''| (the chord error of a
// C2 curve), and, where C moves forward along the chord all the way (C' . u > 0, so every point
// of the piece and of the chord has a partner with the same projection on it), the distance is
// the part of e across the chord, bounded the same way by the part of C'' across it: near 0 on a
// straight stretch however unevenly the spline runs along it (its repeated end points). C'' is
// linear in t, so its norms peak at the ends; C' . u is quadratic.
bool chord_fits(const Span& s, double t0, double t1, double tolerance) {
  const double reach = (t1 - t0) * (t1 - t0) / 8.0;
  const glm::dvec3 b0 = s.bend(t0), b1 = s.bend(t1);
  if (reach * std::max(glm::length(b0), glm::length(b1)) <= tolerance) return true;
  const glm::dvec3 chord = s.at(t1) - s.at(t0);
  const double length = glm::length(chord);
  if (!(length > 0.0)) return false;
  const glm::dvec3 u = chord / length;
  // C'(t) . u = q0 + q1 t + q2 t^2: its least value on [t0, t1].
  const double q0 = glm::dot(s.b, u), q1 = 2.0 * glm::dot(s.c, u), q2 = 3.0 * glm::dot(s.d, u);
  double least = std::min(q0 + t0 * (q1 + t0 * q2), q0 + t1 * (q1 + t1 * q2));
  if (q2 != 0.0) {
    const double v = -q1 / (2.0 * q2);
    if (v > t0 && v < t1) least = std::min(least, q0 + v * (q1 + v * q2));
  }
  if (!(least > 0.0)) return false;
  auto across = [&u](const glm::dvec3& x) { return glm::length(x - glm::dot(x, u) * u); };
  return reach * std::max(across(b0), across(b1)) <= tolerance;
}

// The chords of [t0, t1], halved until each fits (at most 2^12 of them a span).
void chords(const Span& s, double t0, double t1, double tolerance, int depth, std::vector<glm::dvec3>& out) {
  if (depth >= 12 || chord_fits(s, t0, t1, tolerance)) {
    out.push_back(s.at(t1));
    return;
  }
  const double mid = 0.5 * (t0 + t1);
  chords(s, t0, mid, tolerance, depth + 1, out);
  chords(s, mid, t1, tolerance, depth + 1, out);
}

}  // namespace

std::vector<glm::dvec3> curve_polyline(std::span<const glm::dvec3> pts, double tolerance) {
  std::vector<glm::dvec3> out;
  const std::size_t n = pts.size();
  if (n == 0) return out;
  out.push_back(pts[0]);
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const glm::dvec3 p0 = pts[i == 0 ? 0 : i - 1], p1 = pts[i], p2 = pts[i + 1],
                     p3 = pts[std::min(i + 2, n - 1)];
    const Span span{p1, 0.5 * (p2 - p0), 0.5 * (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3),
                    0.5 * (-p0 + 3.0 * p1 - 3.0 * p2 + p3)};
    chords(span, 0.0, 1.0, tolerance, 0, out);
    out.back() = p2;  // the span's end exactly (the spline passes through its points)
  }
  return out;
}

}  // namespace ht
