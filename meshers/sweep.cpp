// The sweep mesher; see meshers/sweep.hpp.
// References: Bloomenthal & Wyvill, "Interactive techniques for implicit modeling" (1990) for
// skeletal primitives; Ronchi, Iacono & Paolucci, "The cubed sphere" (1996) for the equiangular
// cube-sphere map; Wang, Juettler, Zheng & Liu, "Computation of rotation minimizing frames"
// (ACM TOG 2008) for the double-reflection frames; Christiansen & Sederberg (1978) for zipping
// two contours by the shorter diagonal; Lawson (1977) for flipping edges toward Delaunay.
#include "meshers/sweep.hpp"

#include "meshers/polygonize.hpp"
#include "meshers/sweep_stack.hpp"
#include "nodes/primitives.hpp"

#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace ht {
namespace {

using namespace sweep;

// ---------------------------------------------------------------------------------------------
// The nine surfaces

void sphere(TriangleMesh& m, const dvec3& center, double r, double h) {
  Profile p{kRowSpacing * h, {}, {}};
  p.arc(0.0, 0.0, r, 0.0, kPi, 2);  // pole to pole: at least one ring between
  p.rho.back() = 0.0;
  revolve(m, frame_around(center, dvec3(0, 0, 1)), p, h, false);
}

void capsule(TriangleMesh& m, const dvec3& a, const dvec3& b, double r, double h) {
  const double len = glm::length(b - a);
  if (!(len > 1e-12 * r)) return sphere(m, a, r, h);  // within 1e-12 r of the true offset
  Profile p{kRowSpacing * h, {}, {}};
  p.arc(0.0, len, r, 0.0, 0.5 * kPi);
  p.line(r, len, r, 0.0);
  p.arc(0.0, 0.0, r, 0.5 * kPi, kPi);
  p.rho.back() = 0.0;
  revolve(m, frame_around(a, (b - a) / len), p, h, false);
}

void torus(TriangleMesh& m, const double* s, double r, double h) {
  const Frame f = frame_around(vec_at(s, 0), vec_at(s, 3));
  const double rho = s[6];
  Profile p{kRowSpacing * h, {}, {}};
  if (r < rho) {
    // The whole cross-section; an even count keeps the half-step stagger consistent all round.
    int n = cells_for(2.0 * kPi * r, p.step, 4);
    n += n % 2;
    for (int j = 0; j < n; ++j) {
      const double psi = 2.0 * kPi * (double(j) / n);
      p.push(rho + r * std::sin(psi), r * std::cos(psi));
    }
    return revolve(m, f, p, h, true);
  }
  // The apple: the arc of the cross-section outside the axis, from pole to pole.
  const double reach = std::asin(rho / r), pole = std::sqrt(std::max(r * r - rho * rho, 0.0));
  p.arc(rho, 0.0, r, -reach, kPi + reach, 2);
  p.rho.front() = p.rho.back() = 0.0;
  p.z.front() = pole;
  p.z.back() = -pole;
  revolve(m, f, p, h, false);
}

void rounded_disc(TriangleMesh& m, const double* s, double r, double h) {
  const double rho = s[6];
  Profile p{kRowSpacing * h, {}, {}};
  p.line(0.0, r, rho, r);
  p.arc(rho, 0.0, r, 0.0, kPi);
  p.line(rho, -r, 0.0, -r);
  p.rho.back() = 0.0;
  revolve(m, frame_around(vec_at(s, 0), vec_at(s, 3)), p, h, false);
}

void rounded_cylinder(TriangleMesh& m, const double* s, double r, double h) {
  const dvec3 a = vec_at(s, 0), b = vec_at(s, 3);
  const double rho = s[6], len = glm::length(b - a);
  Profile p{kRowSpacing * h, {}, {}};
  p.line(0.0, len + r, rho, len + r);
  p.arc(rho, len, r, 0.0, 0.5 * kPi);
  p.line(rho + r, len, rho + r, 0.0);
  p.arc(rho, 0.0, r, 0.5 * kPi, kPi);
  p.line(rho, -r, 0.0, -r);
  p.rho.back() = 0.0;
  revolve(m, frame_around(a, (b - a) / len), p, h, false);
}

void cone_sphere(TriangleMesh& m, const double* s, double r, double h) {
  const dvec3 a = vec_at(s, 0), b = vec_at(s, 3);
  const double ra = s[6] + r, rb = s[7] + r, len = glm::length(b - a);
  if (len <= std::abs(ra - rb)) return ra >= rb ? sphere(m, a, ra, h) : sphere(m, b, rb, h);
  // The common tangent's normal leans toward b by alpha, sin(alpha) = (ra - rb) / len; it
  // touches each sphere at psi = pi/2 - alpha from the axis.
  const double alpha = std::asin((ra - rb) / len), touch = 0.5 * kPi - alpha;
  Profile p{kRowSpacing * h, {}, {}};
  p.arc(0.0, len, rb, 0.0, touch);
  p.line(rb * std::cos(alpha), len + rb * std::sin(alpha), ra * std::cos(alpha), ra * std::sin(alpha));
  p.arc(0.0, 0.0, ra, touch, kPi);
  p.rho.back() = 0.0;
  revolve(m, frame_around(a, (b - a) / len), p, h, false);
}

// The triangle's offset as a loop stack around its normal: the top pole at the incentre, flat
// loops (the triangle shrunk toward the incentre, every sqrt(3)/2 h of inradius), the triangle
// itself at +r, rim loops (the triangle offset in its plane by r sin(psi), at height r cos(psi):
// straight runs along the edges, arcs around the corners), the triangle at -r, flat loops, the
// bottom pole. Flat loops nest strictly inside each other and the triangle is convex, so every
// zipped triangle is properly oriented.
void rounded_triangle(TriangleMesh& m, const double* s, double r, double h) {
  const std::array<dvec3, 3> c = {vec_at(s, 0), vec_at(s, 3), vec_at(s, 6)};
  std::array<double, 3> len{};
  for (int i = 0; i < 3; ++i) len[i] = glm::length(c[(i + 1) % 3] - c[i]);
  const int longest = int(std::max_element(len.begin(), len.end()) - len.begin());
  const dvec3 cross = glm::cross(c[1] - c[0], c[2] - c[0]);
  const double area2 = glm::length(cross);
  // A triangle this flat is its longest edge to within 1e-10 of the mesh's size.
  if (!(area2 > 1e-10 * len[longest] * (len[longest] + r)))
    return capsule(m, c[longest], c[(longest + 1) % 3], r, h);

  const dvec3 n = cross / area2;
  std::array<dvec3, 3> out{};  // outward normal of edge i (c[i] -> c[i+1]) in the plane
  for (int i = 0; i < 3; ++i) out[i] = glm::normalize(glm::cross(c[(i + 1) % 3] - c[i], n));
  const double perimeter = len[0] + len[1] + len[2];
  const dvec3 incentre = (len[1] * c[0] + len[2] * c[1] + len[0] * c[2]) / perimeter;
  const double inradius = area2 / perimeter, step = kRowSpacing * h;

  std::vector<Loop> loops;
  auto flat_loop = [&](double scale, double z) {
    Loop loop{vertex_count(m), 0};
    for (int i = 0; i < 3; ++i) {
      const dvec3 p = incentre + scale * (c[i] - incentre), q = incentre + scale * (c[(i + 1) % 3] - incentre);
      const int cells = cells_for(scale * len[i], h, 1);
      for (int j = 0; j < cells; ++j) m.positions.push_back(p + (q - p) * (double(j) / cells) + z * n);
    }
    loop.count = vertex_count(m) - loop.first;
    loops.push_back(loop);
  };
  auto rim_loop = [&](double offset, double z) {
    Loop loop{vertex_count(m), 0};
    for (int i = 0; i < 3; ++i) {
      const dvec3 from = out[(i + 2) % 3], to = out[i], side = glm::cross(n, from);
      const double turn = std::atan2(glm::dot(glm::cross(from, to), n), glm::dot(from, to));
      // A corner of almost 180 degrees gets no arc: its two ends would nearly coincide.
      const int arc_cells = turn * offset > 1e-6 * h ? cells_for(turn * offset, h, 1) : 0;
      for (int j = 0; j < arc_cells; ++j) {
        const double phi = turn * (double(j) / arc_cells);
        m.positions.push_back(c[i] + offset * (std::cos(phi) * from + std::sin(phi) * side) + z * n);
      }
      const dvec3 edge = c[(i + 1) % 3] - c[i];
      const int cells = cells_for(len[i], h, 1);
      for (int j = 0; j < cells; ++j) m.positions.push_back(c[i] + offset * to + edge * (double(j) / cells) + z * n);
    }
    loop.count = vertex_count(m) - loop.first;
    loops.push_back(loop);
  };
  auto pole = [&](double z) {
    loops.push_back({vertex_count(m), 1});
    m.positions.push_back(incentre + z * n);
  };

  const int rings = cells_for(inradius, step, 1), rows = cells_for(kPi * r, step, 2);
  pole(r);
  for (int j = 1; j < rings; ++j) flat_loop(double(j) / rings, r);
  flat_loop(1.0, r);
  for (int j = 1; j < rows; ++j) {
    const double psi = kPi * (double(j) / rows);
    rim_loop(r * std::sin(psi), r * std::cos(psi));
  }
  flat_loop(1.0, -r);
  for (int j = rings - 1; j >= 1; --j) flat_loop(double(j) / rings, -r);
  pole(-r);
  // The faces (pole to triangle) are zipped apart from the rim so that their flips can work on
  // their own triangles.
  const std::span<const Loop> stack(loops);
  const std::size_t face = std::size_t(rings) + 1, t0 = m.triangles.size();
  zip_stack(m, stack.first(face), false);
  const std::size_t t1 = m.triangles.size();
  zip_stack(m, stack.subspan(face - 1, stack.size() - 2 * (face - 1)), false);
  const std::size_t t2 = m.triangles.size();
  zip_stack(m, stack.last(face), false);
  flip_flat_quads(m, t0, t1);
  flip_flat_quads(m, t2, m.triangles.size());
}

// The curve's polyline, with its cumulative arc length and unit tangents at its points (the
// mean of the two segments' directions; a segment's at the ends).
struct Polyline {
  std::vector<dvec3> points, tangents;
  std::vector<double> arc;

  explicit Polyline(const double* s) {
    const auto count = static_cast<std::size_t>(s[0]);
    points.resize(count);
    arc.resize(count);
    for (std::size_t i = 0; i < count; ++i) {
      points[i] = vec_at(s + 1, static_cast<int>(3 * i));
      arc[i] = i == 0 ? 0.0 : arc[i - 1] + glm::length(points[i] - points[i - 1]);
    }
  }
  double length() const { return arc.empty() ? 0.0 : arc.back(); }
  // Fills `tangents`; needs a positive length.
  void find_tangents() {
    const std::size_t count = points.size();
    // Segment directions; a repeated point borrows its neighbour's.
    std::vector<dvec3> dir(count - 1, dvec3(0.0));
    for (std::size_t i = 0; i + 1 < count; ++i)
      if (arc[i + 1] > arc[i]) dir[i] = glm::normalize(points[i + 1] - points[i]);
    for (std::size_t i = 1; i < dir.size(); ++i)
      if (dir[i] == dvec3(0.0)) dir[i] = dir[i - 1];
    for (std::size_t i = dir.size() - 1; i-- > 0;)
      if (dir[i] == dvec3(0.0)) dir[i] = dir[i + 1];
    tangents.resize(count);
    tangents[0] = dir.front();
    tangents[count - 1] = dir.back();
    for (std::size_t i = 1; i + 1 < count; ++i) {
      const dvec3 mean = dir[i - 1] + dir[i];
      tangents[i] = glm::dot(mean, mean) > 1e-24 ? glm::normalize(mean) : dir[i];
    }
  }
  std::size_t segment_at(double t) const {
    return std::min<std::size_t>(std::upper_bound(arc.begin(), arc.end(), t) - arc.begin(), arc.size() - 1) - 1;
  }
  // The point at arc length t, clamped to the ends.
  dvec3 at(double t) const {
    if (points.size() == 1 || t <= 0.0) return points.front();
    const std::size_t i = segment_at(t);
    const double span = arc[i + 1] - arc[i];
    return span > 0.0 ? points[i] + (points[i + 1] - points[i]) * std::min((t - arc[i]) / span, 1.0) : points[i];
  }
  // The tangent at arc length t, interpolated between the points' tangents: it turns gradually
  // along each segment, as the spline's does, so rings spaced finer than the polyline do not
  // jump at its corners.
  dvec3 tangent_at(double t) const {
    if (t <= 0.0) return tangents.front();
    const std::size_t i = segment_at(t);
    const double span = arc[i + 1] - arc[i];
    const double u = span > 0.0 ? std::clamp((t - arc[i]) / span, 0.0, 1.0) : 0.0;
    const dvec3 mixed = (1.0 - u) * tangents[i] + u * tangents[i + 1];
    return glm::dot(mixed, mixed) > 1e-24 ? glm::normalize(mixed) : tangents[i + 1];
  }
  // Segments [first, last) that reach within `reach` of arc length t.
  std::pair<std::size_t, std::size_t> window(double t, double reach) const {
    const auto lo = std::lower_bound(arc.begin(), arc.end(), t - reach) - arc.begin();
    const auto hi = std::upper_bound(arc.begin(), arc.end(), t + reach) - arc.begin();
    const std::size_t first = lo > 0 ? std::size_t(lo) - 1 : 0;
    const std::size_t last = std::clamp<std::size_t>(std::size_t(hi), first + 1, points.size() - 1);
    return {first, last};
  }
  // Squared distance from x to segment i, and the vector from its closest point to x.
  double distance2(std::size_t i, const dvec3& x, dvec3& from_segment) const {
    const dvec3 a = points[i], ab = points[i + 1] - a;
    const double len2 = glm::dot(ab, ab);
    const double t = len2 > 0.0 ? std::clamp(glm::dot(x - a, ab) / len2, 0.0, 1.0) : 0.0;
    from_segment = x - (a + t * ab);
    return glm::dot(from_segment, from_segment);
  }
};

// Distance from x to the segments listed in `segments`, and the unit direction from the
// closest point.
double distance_to(const Polyline& line, std::span<const std::uint32_t> segments, const dvec3& x, dvec3& away) {
  double best2 = std::numeric_limits<double>::infinity();
  dvec3 nearest(0.0), d;
  for (std::uint32_t i : segments) {
    const double dist2 = line.distance2(i, x, d);
    if (dist2 < best2) best2 = dist2, nearest = d;
  }
  const double best = std::sqrt(best2);
  away = best > 0.0 ? nearest / best : dvec3(0.0);
  return best;
}

// Moves x = o + t ray to where its distance to `segments` is r, from t = r (x's start: o is a
// point of the polyline at distance r from x). The distance along the ray is 0 at o and at most
// r at t = r, so the crossing lies beyond: Newton steps, kept inside the bracket found so far,
// bisection when they leave it. Returns false when no crossing lies within 4 r (a fold).
bool solve_along_ray(const Polyline& line, std::span<const std::uint32_t> segments, const dvec3& o,
                     const dvec3& ray, double r, double& t) {
  const double tolerance = 1e-14 * (r + glm::length(o));
  double lo = 0.0, hi = std::numeric_limits<double>::infinity();
  t = r;
  for (int iteration = 0; iteration < 100; ++iteration) {
    dvec3 away;
    const double f = distance_to(line, segments, o + t * ray, away) - r;
    if (std::abs(f) <= tolerance) break;
    (f < 0.0 ? lo : hi) = t;
    const double slope = glm::dot(away, ray);
    double next = slope > 1e-3 ? t - f / slope : std::numeric_limits<double>::quiet_NaN();
    if (!(next > lo && next < hi)) next = std::isfinite(hi) ? 0.5 * (lo + hi) : 2.0 * t;
    if (next > 4.0 * r) return false;
    if (next == t) break;
    t = next;
  }
  return true;
}

// Moves vertex x, at distance r from o on the polyline, along the ray from o to the distance r
// from the window's segments. Newton only needs the segments that can be nearest: those within
// `margin` of the nearest at x stay candidates as long as the vertex moves less than margin / 4
// (distances are 1-Lipschitz); a longer move is redone against the whole window.
void push_to_offset(dvec3& x, const dvec3& o, double r, const Polyline& line, std::span<const std::uint32_t> window,
                    std::vector<double>& dist2, std::vector<std::uint32_t>& candidates) {
  const dvec3 ray = glm::normalize(x - o);
  const double margin = 0.1 * r;
  dist2.resize(window.size());
  double nearest2 = std::numeric_limits<double>::infinity();
  dvec3 d;
  for (std::size_t k = 0; k < window.size(); ++k) nearest2 = std::min(nearest2, dist2[k] = line.distance2(window[k], x, d));
  const double keep = (std::sqrt(nearest2) + margin) * (std::sqrt(nearest2) + margin);
  candidates.clear();
  for (std::size_t k = 0; k < window.size(); ++k)
    if (dist2[k] <= keep) candidates.push_back(window[k]);
  double t = r;
  bool found = solve_along_ray(line, candidates, o, ray, r, t);
  if (!found || std::abs(t - r) > 0.25 * margin) found = solve_along_ray(line, window, o, ray, r, t);
  if (found) x = o + t * ray;
}

// A tube along the curve: the start cap's rings, one ring every sqrt(3)/2 h of arc length, the
// end cap's rings; frames carried along by double reflection so the tube does not twist.
void tube(TriangleMesh& m, const double* s, double r, double h) {
  Polyline line(s);
  const double length = line.length();
  if (line.points.size() < 2 || !(length > 1e-12 * r)) return sphere(m, line.points.front(), r, h);
  line.find_tangents();

  // Where the curvature radius stays above r, the polyline within r of a vertex lies within
  // pi r of arc length of its ring's centre.
  const double step = kRowSpacing * h, reach = kPi * r + 2.0 * h;
  const int spans = cells_for(length, step, 1);
  std::vector<double> where(spans + 1);
  std::vector<dvec3> centre(spans + 1), tangent(spans + 1), normal(spans + 1);
  for (int k = 0; k <= spans; ++k) {
    where[k] = k == spans ? length : length * (double(k) / spans);
    centre[k] = line.at(where[k]);
    tangent[k] = line.tangent_at(where[k]);
  }
  normal[0] = frame_around(centre[0], tangent[0]).u;
  for (int k = 0; k < spans; ++k) {
    // Double reflection: reflect the frame in the bisector plane of the chord, then in the one
    // that maps the reflected tangent onto the next tangent.
    const dvec3 v1 = centre[k + 1] - centre[k];
    const double c1 = glm::dot(v1, v1);
    dvec3 rl = normal[k], tl = tangent[k];
    if (c1 > 0.0) {
      rl -= (2.0 / c1) * glm::dot(v1, rl) * v1;
      tl -= (2.0 / c1) * glm::dot(v1, tl) * v1;
    }
    const dvec3 v2 = tangent[k + 1] - tl;
    const double c2 = glm::dot(v2, v2);
    if (c2 > 0.0) rl -= (2.0 / c2) * glm::dot(v2, rl) * v2;
    normal[k + 1] = glm::normalize(rl - glm::dot(rl, tangent[k + 1]) * tangent[k + 1]);
  }

  // The stack runs from the start's pole to the end's: its "top" is -tangent, and rings turn
  // counter-clockwise around it (u x v = cross(T x U, U) = -T).
  std::vector<Loop> loops;
  std::vector<int> loop_centre;
  auto ring = [&](int k, double rho, double z) {
    const Frame f{centre[k], -tangent[k], glm::cross(tangent[k], normal[k]), normal[k]};
    loops.push_back(add_ring(m, f, rho, z, h, loops.size() % 2 == 1));
    loop_centre.push_back(k);
  };
  const int cap_rows = cells_for(0.5 * kPi * r, step, 1);
  ring(0, 0.0, r);
  for (int j = 1; j < cap_rows; ++j) {
    const double psi = 0.5 * kPi * (double(j) / cap_rows);
    ring(0, r * std::sin(psi), r * std::cos(psi));
  }
  for (int k = 0; k <= spans; ++k) ring(k, r, 0.0);
  for (int j = 1; j < cap_rows; ++j) {
    const double psi = 0.5 * kPi * (1.0 + double(j) / cap_rows);
    ring(spans, r * std::sin(psi), r * std::cos(psi));
  }
  ring(spans, 0.0, -r);

  // Onto the polyline's offset, loop by loop in parallel (each vertex on its own: deterministic).
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, loops.size(), 8), [&](const auto& range) {
    std::vector<std::uint32_t> window, candidates;
    std::vector<double> dist2;
    for (std::size_t l = range.begin(); l != range.end(); ++l) {
      const int k = loop_centre[l];
      const auto [first, last] = line.window(where[k], reach);
      window.resize(last - first);
      for (std::size_t i = first; i < last; ++i) window[i - first] = static_cast<std::uint32_t>(i);
      for (std::uint32_t v = loops[l].first; v < loops[l].first + loops[l].count; ++v)
        push_to_offset(m.positions[v], centre[k], r, line, window, dist2, candidates);
    }
  });
  zip_stack(m, loops, false);
}

// An upper bound of the offset surface's area.
double area_bound(NodeKind kind, const double* s, double r) {
  const double ball = 4.0 * kPi * r * r;
  switch (kind) {
    case NodeKind::Point: return ball;
    case NodeKind::Segment: return 2.0 * kPi * r * glm::length(vec_at(s, 3) - vec_at(s, 0)) + ball;
    case NodeKind::Circle: return 4.0 * kPi * kPi * s[6] * r + ball;
    case NodeKind::Disc: return 2.0 * kPi * s[6] * s[6] + 2.0 * kPi * kPi * s[6] * r + ball;
    case NodeKind::Triangle: {
      const dvec3 a = vec_at(s, 0), b = vec_at(s, 3), c = vec_at(s, 6);
      const double perimeter = glm::length(b - a) + glm::length(c - b) + glm::length(a - c);
      return glm::length(glm::cross(b - a, c - a)) + kPi * r * perimeter + ball;
    }
    case NodeKind::Curve: return 2.0 * kPi * r * Polyline(s).length() + ball;
    case NodeKind::Box: {
      const dvec3 e = vec_at(s, 3) - vec_at(s, 0);
      return 2.0 * (e.x * e.y + e.y * e.z + e.z * e.x) + kPi * r * (e.x + e.y + e.z) + ball;
    }
    case NodeKind::Cylinder: {
      const double rho = s[6], len = glm::length(vec_at(s, 3) - vec_at(s, 0));
      return 2.0 * kPi * rho * rho + 2.0 * kPi * (rho + r) * len + 2.0 * kPi * kPi * (rho + r) * r + ball;
    }
    case NodeKind::ConeSphere: {
      const double ra = s[6] + r, rb = s[7] + r, len = glm::length(vec_at(s, 3) - vec_at(s, 0));
      return 4.0 * kPi * (ra * ra + rb * rb) + kPi * (ra + rb) * len;
    }
    default: return 0.0;
  }
}

// How many triangles the mesh will have, at most about: near-equilateral triangles of side h
// cover sqrt(3)/4 h^2 each and the lattice's right triangles h^2 / 2, so 2.5 A / h^2 bounds both
// with room for rounding the cell counts up; when r is far below h, rings and strips keep at
// least 3 cells around, which the length term bounds.
double triangle_estimate(NodeKind kind, const double* s, double r, double h) {
  const double length = kind == NodeKind::Curve ? Polyline(s).length() : kPi * glm::length(skeleton_bounds(kind, s).size());
  return 2.5 * area_bound(kind, s, r) / (h * h) + 32.0 * length / h + 64.0;
}

}  // namespace

bool has_sweep_mesh(NodeKind kind) { return kind_family(kind) == Family::Primitive; }

namespace {

// The checks both entry points make; r0 of the primitive, 0 when it is not visible alone.
double checked_r0(const Graph& graph, NodeId node, double threshold, double precision) {
  if (node >= graph.size()) throw std::invalid_argument("sweep_mesh: node " + std::to_string(node) + " is not in the graph");
  if (!has_sweep_mesh(graph.kind[node]))
    throw std::invalid_argument("sweep_mesh: " + graph.label(node) + " is not a skeletal primitive");
  if (!(std::isfinite(precision) && precision > 0.0))
    throw std::invalid_argument("sweep_mesh: precision must be a finite number > 0");
  if (!(std::isfinite(threshold) && threshold > 0.0))
    throw std::invalid_argument("sweep_mesh: threshold must be a finite number > 0");
  const auto params = graph.params_of(node);
  const double r = primitive_r0(params[kPrimR], params[kPrimF], threshold);
  return r > 0.0 ? r : 0.0;
}

}  // namespace

double sweep_triangle_estimate(const Graph& graph, NodeId node, double threshold, double precision) {
  const double r = checked_r0(graph, node, threshold, precision);
  return r > 0.0 ? triangle_estimate(graph.kind[node], graph.skeleton_of(node), r, precision) : 0.0;
}

TriangleMesh sweep_mesh(const Graph& graph, NodeId node, double threshold, double precision) {
  const double r = checked_r0(graph, node, threshold, precision);
  const NodeKind kind = graph.kind[node];
  TriangleMesh mesh;
  if (!(r > 0.0)) return mesh;
  const double* s = graph.skeleton_of(node);

  const double estimate = triangle_estimate(kind, s, r, precision);
  if (!(estimate <= kSweepMaxTriangles))
    throw PolygonizeError("sweep_mesh: precision " + std::to_string(precision) + " would need about " +
                          std::to_string(estimate) + " triangles for " + graph.label(node) +
                          " (at most 50 million)");

  switch (kind) {
    case NodeKind::Point: sphere(mesh, vec_at(s, 0), r, precision); break;
    case NodeKind::Segment: capsule(mesh, vec_at(s, 0), vec_at(s, 3), r, precision); break;
    case NodeKind::Circle: torus(mesh, s, r, precision); break;
    case NodeKind::Disc: rounded_disc(mesh, s, r, precision); break;
    case NodeKind::Triangle: rounded_triangle(mesh, s, r, precision); break;
    case NodeKind::Curve: tube(mesh, s, r, precision); break;
    case NodeKind::Box: {
      const dvec3 lo = vec_at(s, 0), hi = vec_at(s, 3);
      rounded_box(mesh, 0.5 * (lo + hi), 0.5 * (hi - lo), r, precision);
      break;
    }
    case NodeKind::Cylinder: rounded_cylinder(mesh, s, r, precision); break;
    case NodeKind::ConeSphere: cone_sphere(mesh, s, r, precision); break;
    default: break;
  }
  return mesh;
}

}  // namespace ht
