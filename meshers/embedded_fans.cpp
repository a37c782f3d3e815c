#include "meshers/embedded_fans.hpp"

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>

namespace ht {
namespace {

using glm::dvec2;
using glm::dvec3;

// A triangle counts as turning counter-clockwise in projection when its turn exceeds this times
// the product of its projected sides: far above the rounding of the projection (header).
constexpr double kMargin = 1e-8;
// Fans with more triangles are not certified (their pairs are tested).
constexpr std::size_t kMaxValence = 64;

struct Corner {
  std::uint32_t a, b;  // the link edge a -> b of the triangle (v, a, b), in the mesh's order
};

double cross2(const dvec2& a, const dvec2& b) { return a.x * b.y - a.y * b.x; }

// The fan's certificate (header): its link one closed cycle, every projected turn
// counter-clockwise by the margin, winding once around the vertex. `fan` is reordered along the
// cycle.
bool certify(const TriangleMesh& mesh, std::uint32_t v, Corner* fan, std::size_t k) {
  if (k > kMaxValence) return false;  // the walk below is quadratic in the valence
  // Walk the link: the triangle after (a, b) is the one starting at b; a link vertex that starts
  // two triangles (a pinch), an open end or a second cycle fails.
  for (std::size_t i = 0; i + 1 < k; ++i) {
    std::size_t next = k;
    for (std::size_t j = i + 1; j < k; ++j)
      if (fan[j].a == fan[i].b) {
        if (next != k) return false;
        next = j;
      }
    if (next == k) return false;
    std::swap(fan[i + 1], fan[next]);
  }
  if (fan[k - 1].b != fan[0].a) return false;
  const dvec3 pv = mesh.positions[v];
  dvec3 n(0.0);
  for (std::size_t i = 0; i < k; ++i) n += glm::cross(mesh.positions[fan[i].a] - pv, mesh.positions[fan[i].b] - pv);
  const double len = glm::length(n);
  if (!(len > 0)) return false;
  n /= len;
  // Any two directions across n: P need only be linear (header).
  const dvec3 helper = std::abs(n.x) < 0.6 ? dvec3(1, 0, 0) : dvec3(0, 1, 0);
  const dvec3 e1 = glm::normalize(glm::cross(n, helper)), e2 = glm::cross(n, e1);
  // Each link vertex projected once, so both triangles on it read the same corner.
  // The rounding of a projected corner grows with the corner's distance in space, not with its
  // projection (the dot products cancel when the corner lies almost along n): the margin is
  // taken against the sides in space, |d|, which bound the projections' errors.
  struct Projected {
    dvec2 at;
    double reach;  // |d|
  };
  auto project = [&](std::uint32_t w) {
    const dvec3 d = mesh.positions[w] - pv;
    return Projected{dvec2(glm::dot(e1, d), glm::dot(e2, d)), glm::length(d)};
  };
  int winding = 0;
  Projected A = project(fan[0].a);
  const Projected first = A;
  for (std::size_t i = 0; i < k; ++i) {
    const Projected B = i + 1 < k ? project(fan[i].b) : first;
    if (!(cross2(A.at, B.at) > kMargin * A.reach * B.reach)) return false;
    // A turn of less than a half-turn from below the +x ray to on or above it crosses that ray.
    if (A.at.y < 0 && B.at.y >= 0) ++winding;
    A = B;
  }
  return winding == 1;
}

}  // namespace

std::vector<std::uint8_t> embedded_fans(const TriangleMesh& mesh) {
  const std::size_t nv = mesh.positions.size();
  std::vector<std::uint8_t> ok(nv, 0);
  // Each vertex's triangles by a counting sort: start[v] .. start[v + 1] in `corner`.
  std::vector<std::uint32_t> start(nv + 1, 0);
  for (const glm::uvec3& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) ++start[t[k] + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<Corner> corner(start.back());
  {
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (const glm::uvec3& t : mesh.triangles)
      for (int k = 0; k < 3; ++k) corner[fill[t[k]]++] = {t[(k + 1) % 3], t[(k + 2) % 3]};
  }
  tbb::parallel_for(std::size_t(0), nv, [&](std::size_t v) {
    if (start[v] != start[v + 1]) ok[v] = certify(mesh, std::uint32_t(v), corner.data() + start[v], start[v + 1] - start[v]);
  });
  return ok;
}

}  // namespace ht
