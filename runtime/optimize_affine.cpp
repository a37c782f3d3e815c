#include "runtime/optimize_affine.hpp"

#include "nodes/primitives.hpp"
#include "nodes/warps.hpp"

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <cmath>

namespace ht::optimize_detail {
namespace {

// Forward map rows (3x4, row-major) as a linear part and a translation.
struct Map {
  glm::dmat3 linear;  // column-major: linear[c][r]
  glm::dvec3 shift;
  glm::dvec3 operator()(const glm::dvec3& p) const { return linear * p + shift; }
};

Map forward(std::span<const double> p) {
  Map m;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m.linear[c][r] = p[std::size_t(4 * r + c)];
    m.shift[r] = p[std::size_t(4 * r + 3)];
  }
  return m;
}

// The scale s when the linear part is s times an orthogonal matrix, else 0.
double similarity_scale(const glm::dmat3& l) {
  const glm::dmat3 g = glm::transpose(l) * l;
  const double s2 = (g[0][0] + g[1][1] + g[2][2]) / 3.0;
  if (!(s2 > 0.0)) return 0.0;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (std::abs(g[i][j] - (i == j ? s2 : 0.0)) > 1e-12 * s2) return 0.0;
  return std::sqrt(s2);
}

}  // namespace

bool compose_affine(std::span<const double> outer24, std::span<const double> inner24, std::vector<double>& out24) {
  const Map a = forward(outer24), b = forward(inner24);
  const glm::dmat3 l = a.linear * b.linear;
  const glm::dvec3 t = a.linear * b.shift + a.shift;
  double rows[12];
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) rows[4 * r + c] = l[c][r];
    rows[4 * r + 3] = t[r];
  }
  out24.assign(kAffineParams, 0.0);
  return affine_from_matrix(rows, out24.data());
}

bool affine_is_identity(std::span<const double> p) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c)
      if (std::abs(p[std::size_t(4 * r + c)] - (r == c ? 1.0 : 0.0)) > 1e-15) return false;
  return true;
}

bool fold_affine(NodeKind kind, std::span<const double> affine24, std::span<const double> primitive,
                 std::vector<double>& out) {
  const Map m = forward(affine24);
  const double s = similarity_scale(m.linear);
  if (s == 0.0) return false;
  out.assign(primitive.begin(), primitive.end());
  out[kPrimR] *= s;
  double* k = out.data() + kPrimSkeleton;
  auto move = [&](int at) {
    const glm::dvec3 q = m({k[at], k[at + 1], k[at + 2]});
    k[at] = q.x, k[at + 1] = q.y, k[at + 2] = q.z;
  };
  auto turn = [&](int at) {  // a unit normal
    const glm::dvec3 q = glm::normalize(m.linear * glm::dvec3(k[at], k[at + 1], k[at + 2]));
    k[at] = q.x, k[at + 1] = q.y, k[at + 2] = q.z;
  };
  switch (kind) {
    case NodeKind::Point: move(0); return true;
    case NodeKind::Segment: move(0), move(3); return true;
    case NodeKind::Circle:
    case NodeKind::Disc: move(0), turn(3), k[6] *= s; return true;
    case NodeKind::Triangle: move(0), move(3), move(6); return true;
    case NodeKind::Curve:  // a Catmull-Rom spline of moved points is the moved spline
      for (int i = 0; i < static_cast<int>(k[0]); ++i) move(1 + 3 * i);
      return true;
    case NodeKind::Box: {  // axis-aligned: only x -> s x + t with s > 0 keeps it one
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
          if (std::abs(m.linear[c][r] - (r == c ? s : 0.0)) > 1e-12 * s) return false;
      move(0), move(3);
      return true;
    }
    case NodeKind::Cylinder: move(0), move(3), k[6] *= s; return true;
    case NodeKind::ConeSphere: move(0), move(3), k[6] *= s, k[7] *= s; return true;
    default: return false;
  }
}

}  // namespace ht::optimize_detail
