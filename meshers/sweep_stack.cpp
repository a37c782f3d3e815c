// The building blocks of the sweep meshes; see meshers/sweep_stack.hpp.
#include "meshers/sweep_stack.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace ht::sweep {

// ---------------------------------------------------------------------------------------------
// Loop stacks

Frame frame_around(const dvec3& origin, const dvec3& axis) {
  // The coordinate axis least aligned with `axis` gives a well-conditioned perpendicular.
  const dvec3 a = glm::abs(axis);
  const dvec3 pick = a.x <= a.y && a.x <= a.z ? dvec3(1, 0, 0) : a.y <= a.z ? dvec3(0, 1, 0) : dvec3(0, 0, 1);
  const dvec3 u = glm::normalize(glm::cross(axis, pick));
  return {origin, axis, u, glm::cross(axis, u)};
}

// A ring of radius rho at height z on the frame's axis: a pole when rho is 0, else
// max(3, round(2 pi rho / h)) vertices, turned by half a step when `stagger` so that equal
// neighbouring rings zip into equilateral-like triangles.
Loop add_ring(TriangleMesh& m, const Frame& f, double rho, double z, double h, bool stagger) {
  const Loop loop{vertex_count(m), rho == 0.0 ? 1u : static_cast<std::uint32_t>(cells_for(2.0 * kPi * rho, h, 3))};
  const dvec3 c = f.origin + z * f.axis;
  if (loop.count == 1) {
    m.positions.push_back(c);
    return loop;
  }
  const double step = 2.0 * kPi / loop.count, phase = stagger ? 0.5 * step : 0.0;
  for (std::uint32_t j = 0; j < loop.count; ++j) {
    const double t = phase + j * step;
    m.positions.push_back(c + rho * (std::cos(t) * f.u + std::sin(t) * f.v));
  }
  return loop;
}

// Zips loop a (nearer the top) to loop b with a band of a.count + b.count triangles (a pole
// contributes none of its own): walking both loops once, each step advances the loop whose next
// vertex gives the shorter diagonal. b's walk starts at its vertex nearest a's first. Every step
// advances one loop, so the band is an annulus (or a fan); the one way it could still use an
// edge twice is by sweeping a whole loop around a single vertex of the other (the diagonal it
// starts from would come back), so the last step of each loop must come after the other loop
// has moved on since that loop's first step.
void zip(TriangleMesh& m, Loop a, Loop b) {
  const auto& P = m.positions;
  std::uint32_t offset = 0;
  if (b.count > 1) {
    double best = std::numeric_limits<double>::infinity();
    for (std::uint32_t j = 0; j < b.count; ++j) {
      const dvec3 d = P[b.first + j] - P[a.first];
      if (glm::dot(d, d) < best) best = glm::dot(d, d), offset = j;
    }
  }
  auto A = [&](std::uint32_t i) { return a.first + i % a.count; };
  auto B = [&](std::uint32_t j) { return b.first + (j + offset) % b.count; };
  auto dist2 = [&](std::uint32_t x, std::uint32_t y) {
    const dvec3 d = P[x] - P[y];
    return glm::dot(d, d);
  };
  const std::uint32_t na = a.count == 1 ? 0 : a.count, nb = b.count == 1 ? 0 : b.count;
  const bool guard = na > 0 && nb > 0;
  std::uint32_t a_started = ~0u, b_started = ~0u;  // j at a's first step, i at b's first step
  for (std::uint32_t i = 0, j = 0; i < na || j < nb;) {
    bool advance_a = j == nb || (i < na && dist2(A(i + 1), B(j)) < dist2(A(i), B(j + 1)));
    if (guard && advance_a && i + 1 == na && j == a_started && j < nb) advance_a = false;
    if (guard && !advance_a && j + 1 == nb && i == b_started && i < na) advance_a = true;
    if (advance_a) {
      if (i == 0) a_started = j;
      m.triangles.push_back({A(i), B(j), A(i + 1)});
      ++i;
    } else {
      if (j == 0) b_started = i;
      m.triangles.push_back({A(i), B(j), B(j + 1)});
      ++j;
    }
  }
}

void zip_stack(TriangleMesh& m, std::span<const Loop> loops, bool closed) {
  for (std::size_t k = 0; k + 1 < loops.size(); ++k) zip(m, loops[k], loops[k + 1]);
  if (closed) zip(m, loops.back(), loops.front());
}

namespace {

// sin of a triangle's smallest angle (at most 60 degrees): twice its area over the product of
// its two longest edges. 0 for a degenerate triangle.
double shape_quality(const dvec3& p, const dvec3& q, const dvec3& r) {
  const double a = glm::length(q - p), b = glm::length(r - q), c = glm::length(p - r);
  const double two_longest = a * b * c / std::min({a, b, c});
  return two_longest > 0.0 ? glm::length(glm::cross(q - p, r - p)) / two_longest : 0.0;
}

}  // namespace

// A flat face zipped from loops whose corners sit far apart (the triangle's, at its acute
// corners) keeps thin triangles there; flipping the diagonal of every coplanar convex quad whose
// smallest angle that raises (Lawson's flips) turns them into the Delaunay triangulation of the
// same vertices. Works on triangles [first, last) of m, whose vertices form one index range;
// edges on the range's border are kept, and so are curved quads: on a convex surface the other
// diagonal would dent it. Each flip raises the sorted angle list, so the loop ends.
void flip_flat_quads(TriangleMesh& m, std::size_t first, std::size_t last) {
  constexpr std::uint32_t kBorder = ~0u;
  const auto& P = m.positions;
  const std::span<glm::uvec3> T(m.triangles.data() + first, last - first);
  std::uint32_t v0 = ~0u, v1 = 0;
  for (const auto& t : T)
    for (int k = 0; k < 3; ++k) v0 = std::min(v0, t[k]), v1 = std::max(v1, t[k]);
  if (T.empty()) return;
  const std::size_t vertices = v1 - v0 + 1, half_edges = 3 * T.size();
  auto from = [&](std::uint32_t e) { return T[e / 3][e % 3]; };
  auto next = [](std::uint32_t e) { return e - e % 3 + (e + 1) % 3; };
  auto prev = [](std::uint32_t e) { return e - e % 3 + (e + 2) % 3; };

  // Twins: half-edges bucketed by their lower vertex (count, prefix sum, fill), then matched
  // within each small bucket by their upper vertex.
  std::vector<std::uint32_t> start(vertices + 1, 0), bucket(half_edges), twin(half_edges, kBorder), out(vertices);
  auto lower = [&](std::uint32_t e) { return std::min(from(e), from(next(e))) - v0; };
  auto upper = [&](std::uint32_t e) { return std::max(from(e), from(next(e))); };
  for (std::uint32_t e = 0; e < half_edges; ++e) ++start[lower(e) + 1];
  for (std::size_t v = 0; v < vertices; ++v) start[v + 1] += start[v];
  {
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::uint32_t e = 0; e < half_edges; ++e) bucket[fill[lower(e)]++] = e;
  }
  for (std::size_t v = 0; v < vertices; ++v)
    for (std::uint32_t i = start[v]; i < start[v + 1]; ++i)
      for (std::uint32_t j = i + 1; j < start[v + 1]; ++j)
        if (upper(bucket[i]) == upper(bucket[j])) {
          twin[bucket[i]] = bucket[j];
          twin[bucket[j]] = bucket[i];
        }
  for (std::uint32_t e = 0; e < half_edges; ++e) out[from(e) - v0] = e;

  // Whether c and d share a triangle: c's fan, walked one way and, if it meets the border, the
  // other way too.
  auto share_triangle = [&](std::uint32_t c, std::uint32_t d) {
    auto holds = [&](std::uint32_t e) {
      const auto& t = T[e / 3];
      return t[0] == d || t[1] == d || t[2] == d;
    };
    const std::uint32_t start_edge = out[c - v0];
    std::uint32_t e = start_edge;
    do {
      if (holds(e)) return true;
      e = twin[prev(e)];
    } while (e != kBorder && e != start_edge);
    if (e == start_edge) return false;
    for (e = start_edge; twin[e] != kBorder;) {
      e = next(twin[e]);  // c -> y, its twin y -> c, then c -> the vertex before y
      if (holds(e)) return true;
    }
    return false;
  };

  // Only thin triangles are worth a look: those whose smallest angle is below 30 degrees.
  constexpr double kGood = 0.5;
  std::vector<double> quality(T.size());
  std::vector<std::uint32_t> stack;
  for (std::uint32_t t = 0; t < T.size(); ++t) {
    quality[t] = shape_quality(P[T[t][0]], P[T[t][1]], P[T[t][2]]);
    if (quality[t] < kGood)
      for (std::uint32_t k = 0; k < 3; ++k) stack.push_back(3 * t + k);
  }
  std::size_t budget = 20 * half_edges;
  while (!stack.empty() && budget-- > 0) {
    const std::uint32_t e1 = stack.back(), e2 = twin[e1];
    stack.pop_back();
    if (e2 == kBorder || std::min(quality[e1 / 3], quality[e2 / 3]) >= kGood) continue;
    const std::uint32_t t1 = e1 / 3, t2 = e2 / 3;
    const std::uint32_t a = from(e1), b = from(next(e1)), c = from(prev(e1)), d = from(prev(e2));
    const dvec3 n = glm::cross(P[b] - P[a], P[c] - P[a]);
    const double scale = glm::dot(P[b] - P[a], P[b] - P[a]);
    if (!(std::abs(glm::dot(P[d] - P[a], n)) <= 1e-9 * scale * std::sqrt(scale))) continue;  // not flat
    const double before = std::min(quality[t1], quality[t2]);
    const double q1 = shape_quality(P[a], P[d], P[c]), q2 = shape_quality(P[d], P[b], P[c]);
    if (!(std::min(q1, q2) > before + 1e-12)) continue;
    // Convex quad: the new triangles face the old way.
    if (glm::dot(glm::cross(P[d] - P[a], P[c] - P[a]), n) <= 0.0 || glm::dot(glm::cross(P[b] - P[d], P[c] - P[d]), n) <= 0.0)
      continue;
    if (share_triangle(c, d)) continue;
    // (a, b, c) + (b, a, d) -> (a, d, c) + (d, b, c), half-edge k of each starting at vertex k.
    const std::uint32_t bc = twin[next(e1)], ca = twin[prev(e1)], ad = twin[next(e2)], db = twin[prev(e2)];
    T[t1] = glm::uvec3(a, d, c);
    T[t2] = glm::uvec3(d, b, c);
    quality[t1] = q1;
    quality[t2] = q2;
    const std::uint32_t f1 = 3 * t1, f2 = 3 * t2;
    auto link = [&](std::uint32_t x, std::uint32_t y) {
      twin[x] = y;
      if (y != kBorder) twin[y] = x;
    };
    link(f1 + 0, ad);
    link(f1 + 1, f2 + 2);
    link(f1 + 2, ca);
    link(f2 + 0, db);
    link(f2 + 1, bc);
    out[a - v0] = f1 + 0;
    out[d - v0] = f2 + 0;
    out[b - v0] = f2 + 1;
    out[c - v0] = f1 + 2;
    for (std::uint32_t e : {f1 + 0, f1 + 2, f2 + 0, f2 + 1}) stack.push_back(e);
  }
}


void revolve(TriangleMesh& m, const Frame& f, const Profile& p, double h, bool closed) {
  std::vector<Loop> loops(p.rho.size());
  for (std::size_t k = 0; k < loops.size(); ++k) loops[k] = add_ring(m, f, p.rho[k], p.z[k], h, k % 2 == 1);
  zip_stack(m, loops, closed);
}

// ---------------------------------------------------------------------------------------------
// The lattice: rounded boxes

// Per axis, the lattice index i maps to a box coordinate and a cube-sphere direction component:
// k cells over the first 45-degree arc (box coordinate -half, direction tan(angle)), `flat`
// cells across the box (direction 0), k cells over the last arc. A surface lattice point maps to
// center + box coordinates + r * normalize(directions): the direction lies in the normal cone of
// that box point, so the vertex is exactly at distance r from the box.
void rounded_box(TriangleMesh& m, const dvec3& center, const dvec3& half, double r, double h) {
  const int k = cells_for(0.25 * kPi * r, h, 1);
  std::array<int, 3> cells{};
  std::array<std::vector<double>, 3> coord, dir;
  for (int a = 0; a < 3; ++a) {
    const int flat = half[a] > 0.0 ? cells_for(2.0 * half[a], h, 1) : 0;
    cells[a] = 2 * k + flat;
    coord[a].resize(cells[a] + 1);
    dir[a].resize(cells[a] + 1);
    for (int i = 0; i <= cells[a]; ++i) {
      if (i < k) {
        coord[a][i] = -half[a];
        dir[a][i] = i == 0 ? -1.0 : std::tan(0.25 * kPi * (double(i) / k - 1.0));
      } else if (i <= k + flat) {
        coord[a][i] = flat == 0 ? 0.0 : -half[a] + 2.0 * half[a] * (double(i - k) / flat);  // 0: a sphere
        dir[a][i] = 0.0;
      } else {
        coord[a][i] = half[a];
        dir[a][i] = i == cells[a] ? 1.0 : std::tan(0.25 * kPi * (double(i - k - flat) / k));
      }
    }
  }

  // Vertex numbering, shared by the faces without any lookup: the 8 corners, then the interior
  // points of the 12 edges (axis-major), then the interior points of the 6 faces.
  constexpr int kOther[3][2] = {{1, 2}, {0, 2}, {0, 1}};
  std::array<std::uint32_t, 12> edge_base{};
  std::array<std::uint32_t, 6> face_base{};
  std::uint32_t total = 8;
  for (int a = 0; a < 3; ++a)
    for (int e = 0; e < 4; ++e) {
      edge_base[4 * a + e] = total;
      total += static_cast<std::uint32_t>(cells[a] - 1);
    }
  for (int a = 0; a < 3; ++a)
    for (int e = 0; e < 2; ++e) {
      face_base[2 * a + e] = total;
      total += static_cast<std::uint32_t>((cells[kOther[a][0]] - 1) * (cells[kOther[a][1]] - 1));
    }
  auto id = [&](const std::array<int, 3>& p) -> std::uint32_t {
    std::array<int, 3> ext{};  // 0 at the low end, 1 at the high end, -1 inside
    int free_axis = -1, fixed_axis = -1, extremes = 0;
    for (int a = 0; a < 3; ++a) {
      ext[a] = p[a] == 0 ? 0 : p[a] == cells[a] ? 1 : -1;
      if (ext[a] < 0) {
        free_axis = a;
      } else {
        fixed_axis = a;
        ++extremes;
      }
    }
    if (extremes == 3) return static_cast<std::uint32_t>(ext[0] + 2 * ext[1] + 4 * ext[2]);
    if (extremes == 2) {
      const int b = kOther[free_axis][0], c = kOther[free_axis][1];
      return edge_base[4 * free_axis + ext[b] + 2 * ext[c]] + static_cast<std::uint32_t>(p[free_axis] - 1);
    }
    const int b = kOther[fixed_axis][0], c = kOther[fixed_axis][1];
    return face_base[2 * fixed_axis + ext[fixed_axis]] +
           static_cast<std::uint32_t>((p[b] - 1) + (cells[b] - 1) * (p[c] - 1));
  };

  const std::uint32_t base = vertex_count(m);
  m.positions.resize(base + std::size_t(total));
  std::vector<std::uint32_t> grid;
  for (int a = 0; a < 3; ++a)
    for (int e = 0; e < 2; ++e) {
      const int b = kOther[a][0], c = kOther[a][1];
      const int nb = cells[b] + 1, nc = cells[c] + 1;
      grid.resize(std::size_t(nb) * std::size_t(nc));
      std::array<int, 3> p{};
      p[a] = e == 0 ? 0 : cells[a];
      for (int l = 0; l < nc; ++l)
        for (int j = 0; j < nb; ++j) {
          p[b] = j;
          p[c] = l;
          const std::uint32_t v = base + id(p);
          const dvec3 d(dir[0][p[0]], dir[1][p[1]], dir[2][p[2]]);
          // Points on an edge or corner are written by each of their faces, identically.
          m.positions[v] = center + dvec3(coord[0][p[0]], coord[1][p[1]], coord[2][p[2]]) + r * glm::normalize(d);
          grid[std::size_t(j) + std::size_t(nb) * std::size_t(l)] = v;
        }
      // Walking b then c turns around +a for a = x, z and around -a for a = y (y = z x x).
      const bool flip = (a != 1) != (e == 1);
      for (int l = 0; l + 1 < nc; ++l)
        for (int j = 0; j + 1 < nb; ++j) {
          const std::uint32_t q00 = grid[std::size_t(j) + std::size_t(nb) * std::size_t(l)];
          const std::uint32_t q10 = grid[std::size_t(j + 1) + std::size_t(nb) * std::size_t(l)];
          const std::uint32_t q11 = grid[std::size_t(j + 1) + std::size_t(nb) * std::size_t(l + 1)];
          const std::uint32_t q01 = grid[std::size_t(j) + std::size_t(nb) * std::size_t(l + 1)];
          const dvec3 d0 = m.positions[q11] - m.positions[q00], d1 = m.positions[q01] - m.positions[q10];
          // The shorter diagonal: the cube-sphere's rhombi near its corners become two
          // near-equilateral triangles instead of two flat ones.
          std::array<glm::uvec3, 2> t;
          if (glm::dot(d0, d0) <= glm::dot(d1, d1))
            t = {glm::uvec3(q00, q10, q11), glm::uvec3(q00, q11, q01)};
          else
            t = {glm::uvec3(q00, q10, q01), glm::uvec3(q10, q11, q01)};
          for (auto& tri : t) m.triangles.push_back(flip ? glm::uvec3(tri.x, tri.z, tri.y) : tri);
        }
    }
}


}  // namespace ht::sweep
