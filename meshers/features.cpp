// Crease splitting; see meshers/features.hpp.
#include "meshers/features.hpp"

#include "runtime/tape.hpp"
#include "runtime/tape_eval.hpp"

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

namespace ht {
namespace {

constexpr double kOnPlane = 0.05;  // an end this near the other end's tangent plane (in edge lengths) is on the crease
// The share of the ends' normal difference that must remain between the first probes (a third
// of the way from the crease estimate to each end): a crease keeps all of it, an even bend a
// third. Measured on bunny00 at h = 0.01 (a faceted scan whose facets turn 10-25 degrees each):
// the seams of its Booleans keep 0.9-1.1, its bumps mostly 0.3-0.8.
constexpr double kConcentrated = 0.8;
// The normal at a crease point says what meets there. At a seam of a Boolean or a crop one
// operand wins, so it is one sheet's (measured at the seams of bunny00's Booleans and of
// examples/carved_box.json: within 0.4 degrees for nine in ten, within 5 but for a few corners).
// On a mesh leaf's sharp edge the point lies on the edge, where the normal is the two facets'
// bisector (their pseudo-normal) and their planes meet on the surface exactly. Anything in
// between (bunny00: 9 to 20 degrees from either sheet, up to max_error off the surface) is a
// strip of facets turning together, a bend.
constexpr double kSheetDegrees = 5.0;
constexpr double kBisectorDegrees = 2.0;
constexpr double kBetweenDegrees = 10.0;  // off the sheets' plane of normals: a third sheet (a corner), no bend
constexpr double kOnEdge = 0.005;  // of a cell: how far off the surface a mesh edge's crease point may be

double cos_degrees(double d) { return std::cos(d * std::numbers::pi / 180.0); }

using Edge = std::array<std::uint32_t, 2>;  // lower index first

Edge edge_of(std::uint32_t a, std::uint32_t b) { return {std::min(a, b), std::max(a, b)}; }

double triangle_quality(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
  // The smallest angle's sine over the longest edge is a cheap quality measure: larger is better.
  const double area2 = glm::length(glm::cross(b - a, c - a));
  const double l = std::max({glm::dot(b - a, b - a), glm::dot(c - b, c - b), glm::dot(a - c, a - c)});
  return l > 0 ? area2 / l : 0.0;
}

// The point nearest m on the line where the planes (p1, n1) and (p2, n2) meet:
// x = m + alpha n1 + beta n2 with n_i . x = n_i . p_i. False for nearly parallel planes.
bool crease_point(const glm::dvec3& p1, const glm::dvec3& n1, const glm::dvec3& p2, const glm::dvec3& n2,
                  const glm::dvec3& m, glm::dvec3& x) {
  const double c = glm::dot(n1, n2), det = 1.0 - c * c;
  if (!(det > 1e-6)) return false;
  const double r1 = glm::dot(n1, p1 - m), r2 = glm::dot(n2, p2 - m);
  x = m + ((r1 - c * r2) / det) * n1 + ((r2 - c * r1) / det) * n2;
  return true;
}

// Whether the unit normal n lies between the sheets' normals a and b: in their plane (off it by
// more than kBetweenDegrees is a third sheet's: a corner) and within kSheetDegrees of neither.
bool between_sheets(const glm::dvec3& n, const glm::dvec3& a, const glm::dvec3& b) {
  const glm::dvec3 across = glm::normalize(glm::cross(a, b));
  return std::max(glm::dot(n, a), glm::dot(n, b)) < cos_degrees(kSheetDegrees) &&
         std::abs(glm::dot(n, across)) < std::sin(kBetweenDegrees * std::numbers::pi / 180.0);
}

// A crease is a jump of the normal at the crease point: just off it on either side (kSide edge
// lengths toward that end) the normal must be one of the two sheets' (the same one on both
// sides when the crease runs through an end: a seam through a grid point). A normal in between
// says the sheets' planes merely happen to meet on the surface, as a scan's facets a few apart
// do where the facets between them turn only a little (bunny00 at h = 0.02). Clears `active`
// where that is so.
constexpr double kSide = 0.05;
void confirm_jumps(const TapeEvaluator& eval, const std::vector<glm::dvec3>& P, const std::vector<Edge>& edges,
                   const std::vector<glm::dvec3>& points, const std::vector<std::array<glm::dvec3, 2>>& plane_normal,
                   std::vector<std::uint8_t>& active, CreaseStats& stats) {
  std::vector<std::uint32_t> checked;
  std::vector<glm::dvec3> side;
  for (std::uint32_t e = 0; e < edges.size(); ++e) {
    if (!active[e]) continue;
    checked.push_back(e);
    const double len = glm::length(P[edges[e][1]] - P[edges[e][0]]);
    for (int s = 0; s < 2; ++s) side.push_back(points[e] + kSide * len * glm::normalize(P[edges[e][s]] - points[e]));
  }
  if (side.empty()) return;
  std::vector<double> values(side.size());
  std::vector<glm::dvec3> grads(side.size());
  eval.gradient(side, values, grads);
  for (std::size_t i = 0; i < checked.size(); ++i) {
    bool jump = true;
    for (int s = 0; s < 2; ++s) {
      const double g = glm::length(grads[2 * i + s]);
      jump = jump && g > 0 && !between_sheets(-grads[2 * i + s] / g, plane_normal[checked[i]][0], plane_normal[checked[i]][1]);
    }
    if (!jump) {
      active[checked[i]] = 0;
      ++stats.spread_edges;
    }
  }
}

}  // namespace

bool may_have_creases(const Tape& tape) {
  return std::any_of(tape.code.begin(), tape.code.end(), [](const Instruction& i) {
    switch (i.op) {
      case OpCode::Mesh:
      case OpCode::Max:
      case OpCode::Min:
      case OpCode::RUnion:
      case OpCode::RIntersection:
      case OpCode::DiffMinMax:
      case OpCode::DiffRFunction:
      case OpCode::LocalBlendMinMax:
      case OpCode::LocalBlendRFunction:
      case OpCode::Crop: return true;
      default: return false;
    }
  });
}

void mark_suspect_cells(std::span<const float> values, int cells, const FeatureOptions& options,
                        std::span<std::uint8_t> suspect) {
  const int n = cells + 1;
  auto at = [&](int i, int j, int k) { return double(values[std::size_t(i + n * (j + n * k))]); };
  auto diff = [&](int i, int j, int k, int axis) {
    int lo[3] = {i, j, k}, hi[3] = {i, j, k};
    lo[axis] = std::max(lo[axis] - 1, 0);
    hi[axis] = std::min(hi[axis] + 1, cells);
    return (at(hi[0], hi[1], hi[2]) - at(lo[0], lo[1], lo[2])) / double(hi[axis] - lo[axis]);
  };
  std::vector<glm::vec3> dir(std::size_t(n) * n * n);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const glm::dvec3 g(diff(i, j, k, 0), diff(i, j, k, 1), diff(i, j, k, 2));
        const double len = glm::length(g);
        dir[std::size_t(i + n * (j + n * k))] = len > 0 && std::isfinite(len) ? glm::vec3(g / len) : glm::vec3(0.0f);
      }
  const float cos_suspect = float(cos_degrees(options.suspect_angle_degrees));
  for (int k = 0; k < cells; ++k)
    for (int j = 0; j < cells; ++j)
      for (int i = 0; i < cells; ++i) {
        glm::vec3 d[8];
        int m = 0;
        for (int c = 0; c < 8; ++c) {
          const glm::vec3 g = dir[std::size_t((i + (c & 1)) + n * ((j + ((c >> 1) & 1)) + n * (k + ((c >> 2) & 1))))];
          if (g != glm::vec3(0.0f)) d[m++] = g;
        }
        bool spread = false;
        for (int a = 0; a < m && !spread; ++a)
          for (int b = a + 1; b < m && !spread; ++b) spread = glm::dot(d[a], d[b]) < cos_suspect;
        suspect[std::size_t(i + cells * (j + cells * k))] = spread;
      }
}

CreaseStats split_creases(TriangleMesh& mesh, std::span<const glm::vec3> normals, const TapeEvaluator& eval, double T,
                          double h, const FeatureOptions& options, std::vector<std::uint8_t>* on_crease) {
  CreaseStats stats;
  if (on_crease) on_crease->resize(mesh.positions.size(), 0);  // flags the caller set stay
  auto& P = mesh.positions;
  const float cos_sharp = float(cos_degrees(options.sharp_angle_degrees));
  auto known = [&](std::uint32_t v) { return normals[v] != glm::vec3(0.0f); };

  // 1. Edges whose end normals disagree.
  std::vector<Edge> edges;
  for (const glm::uvec3& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = t[k], b = t[(k + 1) % 3];
      if (a < b && known(a) && known(b) && glm::dot(normals[a], normals[b]) < cos_sharp) edges.push_back({a, b});
    }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  stats.candidate_edges = edges.size();
  if (edges.empty()) return stats;

  // 2. Where the crease crosses each: on the line where the tangent planes at the two ends meet.
  //    A tangent plane strays from its sheet with the square of the distance, so the estimate is
  //    refined from surface points a third of the way from it toward each end, whose tangent
  //    planes are that much closer to the crease.
  std::vector<glm::dvec3> points(edges.size());
  std::vector<std::uint8_t> plausible(edges.size(), 0);
  auto plausible_point = [&](std::size_t e, const glm::dvec3& x) {
    // Between the ends, not far off the edge: else the two planes do not describe a crease here.
    const glm::dvec3 u = P[edges[e][0]], d = P[edges[e][1]] - u;
    const double len2 = glm::dot(d, d), t = glm::dot(x - u, d) / len2;
    const glm::dvec3 off = x - (u + t * d);
    return t > 0.02 && t < 0.98 && glm::dot(off, off) <= 0.25 * len2;
  };
  // Each side's current tangent plane: first the end's own, then a probe's nearer the crease.
  std::vector<std::array<glm::dvec3, 2>> plane_point(edges.size()), plane_normal(edges.size());
  for (std::size_t e = 0; e < edges.size(); ++e) {
    for (int s = 0; s < 2; ++s) {
      plane_point[e][s] = P[edges[e][s]];
      plane_normal[e][s] = glm::dvec3(normals[edges[e][s]]);
    }
    plausible[e] = crease_point(plane_point[e][0], plane_normal[e][0], plane_point[e][1], plane_normal[e][1],
                                0.5 * (P[edges[e][0]] + P[edges[e][1]]), points[e]) &&
                   plausible_point(e, points[e]);
  }
  // A crease turns the normal at one line: the sheets' planes nearer to it still differ by as
  // much as the ends' (and by more than the sharp angle). A faceted scan whose facets each turn
  // a little does not: its probes' normals lie in between. Such an edge is no crease, whatever
  // its ends say. Only mesh leaves have such normals, piecewise constant: a field's own normals
  // turn smoothly, and a ridge tighter than the cell is split on purpose (the split halves its
  // chamfer; random trees with local blends over crops measured 20% more face error without).
  const bool faceted = std::any_of(eval.tape().code.begin(), eval.tape().code.end(),
                                   [](const Instruction& i) { return i.op == OpCode::Mesh; });
  std::vector<std::uint8_t> spread(edges.size(), 0);
  auto bend_stays_sharp = [&](std::size_t e) {
    const double c = glm::dot(plane_normal[e][0], plane_normal[e][1]);
    const double ends = std::acos(std::clamp(double(glm::dot(normals[edges[e][0]], normals[edges[e][1]])), -1.0, 1.0));
    return c < cos_sharp && c <= std::cos(kConcentrated * ends);
  };
  std::vector<glm::dvec3> probes(2 * edges.size()), grads(2 * edges.size());
  std::vector<double> values(2 * edges.size());
  for (int round = 0; round < options.refine_rounds; ++round) {
    for (std::size_t e = 0; e < edges.size(); ++e)
      for (int s = 0; s < 2; ++s) probes[2 * e + s] = points[e] + (1.0 / 3.0) * (plane_point[e][s] - points[e]);
    eval.gradient(probes, values, grads);
    for (std::size_t e = 0; e < edges.size(); ++e) {
      if (!plausible[e]) continue;
      for (int s = 0; s < 2; ++s) {
        const glm::dvec3 g = grads[2 * e + s];
        const double g2 = glm::dot(g, g);
        if (!(g2 > 0) || !std::isfinite(g2)) continue;
        const glm::dvec3 n = -g / std::sqrt(g2);
        // A probe that fell on the other sheet (the estimate was off) keeps the older plane.
        if (glm::dot(n, plane_normal[e][s]) <= glm::dot(n, plane_normal[e][1 - s])) continue;
        plane_point[e][s] = probes[2 * e + s] - ((values[2 * e + s] - T) / g2) * g;  // a Newton step onto the surface
        plane_normal[e][s] = n;
      }
      if (faceted && !bend_stays_sharp(e)) {
        plausible[e] = 0;
        spread[e] = 1;
        continue;
      }
      glm::dvec3 x;
      if (crease_point(plane_point[e][0], plane_normal[e][0], plane_point[e][1], plane_normal[e][1], points[e], x) &&
          plausible_point(e, x))
        points[e] = x;
    }
  }
  stats.spread_edges = std::size_t(std::count(spread.begin(), spread.end(), std::uint8_t(1)));
  eval.gradient(points, {values.data(), points.size()}, {grads.data(), points.size()});
  // Vertex ids while cutting: originals below n0, edge e's crease point n0 + e, triangle t's
  // corner n0 + E + t. The new ones actually used are numbered after the originals at the end.
  const std::uint32_t n0 = static_cast<std::uint32_t>(P.size()), E = static_cast<std::uint32_t>(edges.size());
  std::vector<std::uint8_t> active(edges.size(), 0);
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const double g = glm::length(grads[e]), off = g > 0 ? std::abs(values[e] - T) / g : 1e300;
    if (!plausible[e] || !(off <= options.max_error * h)) continue;
    const glm::dvec3 n = -grads[e] / g, bisector = glm::normalize(plane_normal[e][0] + plane_normal[e][1]);
    const bool mesh_edge = glm::dot(n, bisector) >= cos_degrees(kBisectorDegrees) && off <= kOnEdge * h;
    active[e] = !faceted || mesh_edge || !between_sheets(n, plane_normal[e][0], plane_normal[e][1]);
    if (!active[e]) ++stats.spread_edges;
  }
  if (faceted) confirm_jumps(eval, P, edges, points, plane_normal, active, stats);
  // An end lying on the other end's tangent plane is on the crease already (a crease through
  // grid points: marching tetrahedra put it there). The edge does not cross the crease, it ends
  // on it: no split. That end is a crease point, and its normal is one sheet's only.
  std::vector<std::uint8_t> on_line(n0, 0);
  for (std::uint32_t e = 0; e < E; ++e) {
    if (spread[e]) continue;  // the ends lie on no crease either
    const glm::dvec3 d = P[edges[e][1]] - P[edges[e][0]];
    const double len = glm::length(d);
    for (int s = 0; s < 2; ++s)
      if (std::abs(glm::dot(glm::dvec3(normals[edges[e][s]]), d)) < kOnPlane * len) {
        on_line[edges[e][1 - s]] = 1;
        active[e] = 0;
      }
  }
  // A crease point near an end of its edge moves that end onto the crease instead of cutting a
  // sliver off the edge's triangles. The edges at a moved vertex then no longer cross the crease.
  std::vector<std::uint32_t> snap_of(n0, ~0u);  // the edge whose crease point vertex v moved to
  {
    struct Snap {
      std::uint32_t v, e;
      double d;
    };
    std::vector<Snap> snaps;
    for (std::uint32_t e = 0; e < E; ++e) {
      if (!active[e]) continue;
      const double len = glm::length(P[edges[e][1]] - P[edges[e][0]]);
      for (int s = 0; s < 2; ++s)
        if (const double d = glm::length(points[e] - P[edges[e][s]]); d < options.snap * len) snaps.push_back({edges[e][s], e, d});
    }
    std::sort(snaps.begin(), snaps.end(), [](const Snap& x, const Snap& y) {
      return x.v != y.v ? x.v < y.v : x.d != y.d ? x.d < y.d : x.e < y.e;
    });
    for (std::size_t i = 0; i < snaps.size(); ++i)
      if (i == 0 || snaps[i].v != snaps[i - 1].v) snap_of[snaps[i].v] = snaps[i].e;
    for (std::uint32_t e = 0; e < E; ++e)
      if (snap_of[edges[e][0]] != ~0u || snap_of[edges[e][1]] != ~0u) active[e] = 0;
  }
  std::vector<glm::dvec3> corner_points;
  std::vector<std::uint32_t> corner_tris;  // sorted: triangle of each corner point
  auto pos = [&](std::uint32_t id) -> const glm::dvec3& {
    if (id < n0) return snap_of[id] != ~0u ? points[snap_of[id]] : P[id];
    if (id < n0 + E) return points[id - n0];
    const auto it = std::lower_bound(corner_tris.begin(), corner_tris.end(), id - n0 - E);
    return corner_points[std::size_t(it - corner_tris.begin())];
  };
  auto edge_index = [&](std::uint32_t a, std::uint32_t b) {
    const Edge key = edge_of(a, b);
    const auto it = std::lower_bound(edges.begin(), edges.end(), key);
    return it != edges.end() && *it == key ? std::uint32_t(it - edges.begin()) : ~0u;
  };
  auto split_of = [&](std::uint32_t a, std::uint32_t b) {
    const std::uint32_t e = edge_index(a, b);
    return e != ~0u && active[e] ? n0 + e : ~0u;
  };
  // Triangle t cut along its active splits (and around its corner point, if any); returns the
  // number of pieces written to `piece`, orientation kept.
  auto cut = [&](std::uint32_t t, bool with_corner, std::array<glm::uvec3, 6>& piece) {
    const glm::uvec3 tri = mesh.triangles[t];
    std::uint32_t s[3];
    int count = 0;
    for (int k = 0; k < 3; ++k) count += (s[k] = split_of(tri[k], tri[(k + 1) % 3])) != ~0u;
    if (count == 0) {
      piece[0] = tri;
      return 1;
    }
    if (count == 1) {
      int k = 0;
      while (s[k] == ~0u) ++k;
      const std::uint32_t a = tri[k], b = tri[(k + 1) % 3], c = tri[(k + 2) % 3], x = s[k];
      piece[0] = {a, x, c};
      piece[1] = {x, b, c};
      return 2;
    }
    if (count == 2) {
      // Rotate so the edges a-b and b-c are split (at x and y) and c-a is not.
      int k = 0;
      while (s[(k + 2) % 3] != ~0u) ++k;
      const std::uint32_t a = tri[k], b = tri[(k + 1) % 3], c = tri[(k + 2) % 3], x = s[k], y = s[(k + 1) % 3];
      piece[0] = {x, b, y};  // x-y runs along the crease
      // The quad a x y c: the diagonal that gives the better worse triangle.
      const double qa = std::min(triangle_quality(pos(a), pos(x), pos(y)), triangle_quality(pos(a), pos(y), pos(c)));
      const double qb = std::min(triangle_quality(pos(a), pos(x), pos(c)), triangle_quality(pos(x), pos(y), pos(c)));
      if (qa >= qb) {
        piece[1] = {a, x, y};
        piece[2] = {a, y, c};
      } else {
        piece[1] = {a, x, c};
        piece[2] = {x, y, c};
      }
      return 3;
    }
    const std::uint32_t x = s[0], y = s[1], z = s[2];
    piece[0] = {tri[0], x, z};
    piece[1] = {x, tri[1], y};
    piece[2] = {z, y, tri[2]};
    if (!with_corner) {
      piece[3] = {x, y, z};
      return 4;
    }
    const std::uint32_t p = n0 + E + t;
    piece[3] = {x, y, p};
    piece[4] = {y, z, p};
    piece[5] = {z, x, p};
    return 6;
  };
  // A cut is kept when no piece is degenerate or turned over: each piece must face the way the
  // normals at its vertices do (at a crease point, the way the two sheets' normals do together).
  // Marching tetrahedra leaves some slivers of its own, turned any way: a piece is held only to
  // the normals the triangle it comes from clearly agreed with, and a piece too small to matter
  // (two crease points almost together) only to having an area.
  const double min_area2 = 1e-10 * h * h, tiny_area2 = 0.05 * h * h;
  auto sound = [&](std::uint32_t t, const std::array<glm::uvec3, 6>& piece, int n) {
    const glm::uvec3 tri = mesh.triangles[t];
    const glm::dvec3 nt = glm::cross(P[tri[1]] - P[tri[0]], P[tri[2]] - P[tri[0]]);
    for (int i = 0; i < n; ++i) {
      const glm::dvec3 a = pos(piece[i][0]), b = pos(piece[i][1]), c = pos(piece[i][2]);
      const glm::dvec3 np = glm::cross(b - a, c - a);
      const double area2 = glm::length(np);
      if (area2 <= min_area2) return false;
      if (area2 <= tiny_area2) continue;
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t v = piece[i][k];
        glm::dvec3 nv(0.0);
        if (v < n0 && snap_of[v] != ~0u)
          nv = plane_normal[snap_of[v]][0] + plane_normal[snap_of[v]][1];
        else if (v < n0 && !on_line[v])  // a point on the crease has one sheet's normal only
          nv = glm::dvec3(normals[v]);
        else if (v >= n0 && v < n0 + E)
          nv = plane_normal[v - n0][0] + plane_normal[v - n0][1];
        if (glm::dot(np, nv) <= 0 && glm::dot(nt, nv) > 0.25 * glm::length(nt) * glm::length(nv)) return false;
      }
    }
    return true;
  };
  // The triangles a split or a move changes; an unsound one gives back the split nearest an end
  // of its edge, or else a move, until every cut is sound.
  std::vector<std::uint32_t> touched;
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    const glm::uvec3 tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k)
      if (snap_of[tri[k]] != ~0u || edge_index(tri[k], tri[(k + 1) % 3]) != ~0u) {
        touched.push_back(t);
        break;
      }
  }
  std::array<glm::uvec3, 6> piece;
  for (bool changed = true; changed;) {
    changed = false;
    for (std::uint32_t t : touched) {
      if (sound(t, piece, cut(t, false, piece))) continue;
      const glm::uvec3 tri = mesh.triangles[t];
      std::uint32_t worst = ~0u;
      double nearest = 1e300;
      for (int k = 0; k < 3; ++k)
        if (const std::uint32_t e = edge_index(tri[k], tri[(k + 1) % 3]); e != ~0u && active[e]) {
          const double d = std::min(glm::length(points[e] - P[edges[e][0]]), glm::length(points[e] - P[edges[e][1]]));
          if (d < nearest) {
            nearest = d;
            worst = e;
          }
        }
      if (worst != ~0u) {
        active[worst] = 0;
        changed = true;
        continue;
      }
      for (int k = 0; k < 3; ++k)
        if (snap_of[tri[k]] != ~0u) {
          snap_of[tri[k]] = ~0u;
          changed = true;
          break;
        }
    }
  }

  // 3. Corners: a triangle split on all three edges gets the point on its three tangent planes.
  for (std::uint32_t t : touched) {
    const glm::uvec3 tri = mesh.triangles[t];
    if (split_of(tri[0], tri[1]) == ~0u || split_of(tri[1], tri[2]) == ~0u || split_of(tri[2], tri[0]) == ~0u) continue;
    glm::dmat3 rows;  // glm is column-major: the columns are N's rows; transpose below
    glm::dvec3 rhs;
    for (int k = 0; k < 3; ++k) {
      rows[k] = glm::dvec3(normals[tri[k]]);
      rhs[k] = glm::dot(rows[k], P[tri[k]]);
    }
    const glm::dmat3 N = glm::transpose(rows);
    if (std::abs(glm::determinant(N)) < 0.05) continue;
    const glm::dvec3 x = glm::inverse(N) * rhs;
    const glm::dvec3 centre = (P[tri[0]] + P[tri[1]] + P[tri[2]]) / 3.0;
    const double size = std::max({glm::length(P[tri[1]] - P[tri[0]]), glm::length(P[tri[2]] - P[tri[1]]),
                                  glm::length(P[tri[0]] - P[tri[2]])});
    if (glm::length(x - centre) > size) continue;
    corner_tris.push_back(t);
    corner_points.push_back(x);
  }
  std::vector<std::uint8_t> corner_ok(corner_tris.size(), 0);
  if (!corner_tris.empty()) {
    std::vector<glm::dvec3> cg(corner_tris.size());
    std::vector<double> cv(corner_tris.size());
    eval.gradient(corner_points, cv, cg);
    for (std::size_t i = 0; i < corner_tris.size(); ++i) {
      const double g = glm::length(cg[i]);
      corner_ok[i] = g > 0 && std::abs(cv[i] - T) <= options.max_error * h * g &&
                     sound(corner_tris[i], piece, cut(corner_tris[i], true, piece));
    }
  }

  // 4. Cut every triangle; number the new vertices that are used after the originals.
  std::vector<glm::uvec3> out;
  out.reserve(mesh.triangles.size() + 4 * touched.size());
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto it = std::lower_bound(corner_tris.begin(), corner_tris.end(), t);
    const bool with_corner = it != corner_tris.end() && *it == t && corner_ok[std::size_t(it - corner_tris.begin())];
    const int n = cut(t, with_corner, piece);
    out.insert(out.end(), piece.begin(), piece.begin() + n);
  }
  for (std::uint32_t v = 0; v < n0; ++v)
    if (on_line[v] && on_crease) (*on_crease)[v] = 1;
  for (std::uint32_t v = 0; v < n0; ++v)
    if (snap_of[v] != ~0u) {
      P[v] = points[snap_of[v]];
      ++stats.moved_vertices;
      if (on_crease) (*on_crease)[v] = 1;
    }
  std::vector<std::uint32_t> renumber(std::size_t(E) + corner_tris.size(), ~0u);
  for (glm::uvec3& tri : out)
    for (int k = 0; k < 3; ++k) {
      if (tri[k] < n0) continue;
      std::size_t slot = tri[k] - n0;
      if (slot >= E) slot = E + std::size_t(std::lower_bound(corner_tris.begin(), corner_tris.end(), tri[k] - n0 - E) -
                                            corner_tris.begin());
      if (renumber[slot] == ~0u) {
        renumber[slot] = static_cast<std::uint32_t>(P.size());
        P.push_back(pos(tri[k]));
      }
      tri[k] = renumber[slot];
    }
  for (std::size_t i = 0; i < renumber.size(); ++i)
    if (renumber[i] != ~0u) ++(i < E ? stats.split_edges : stats.corners);
  mesh.triangles = std::move(out);
  if (on_crease) on_crease->resize(P.size(), 1);
  return stats;
}

}  // namespace ht
