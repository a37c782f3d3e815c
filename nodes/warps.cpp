// Warps. References: Barr, "Global and local deformations of solid primitives" (SIGGRAPH 1984)
// for twist, taper and bend and their inverses; Sederberg & Parry, "Free-form deformation of
// solid geometric models" (SIGGRAPH 1986).
#include "nodes/warps.hpp"

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>
#include <glm/matrix.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

namespace ht {
namespace {

glm::dvec3 apply3x4(const double* m, const glm::dvec3& p) {
  return {m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
          m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]};
}

// Local frame of a Barr warp: h along the axis, (v, w) the turning plane, all from the center.
struct Frame {
  int axis;
  glm::dvec3 center;
  int iv() const { return (axis + 1) % 3; }
  int iw() const { return (axis + 2) % 3; }
  glm::dvec3 to_local(const glm::dvec3& p) const {
    const glm::dvec3 q = p - center;
    return {q[axis], q[iv()], q[iw()]};
  }
  glm::dvec3 to_world(const glm::dvec3& l) const {
    glm::dvec3 q;
    q[axis] = l.x;
    q[iv()] = l.y;
    q[iw()] = l.z;
    return q + center;
  }
};

Frame frame_of(const double* s) { return {static_cast<int>(s[0]), {s[1], s[2], s[3]}}; }

// Turns each slice by direction * rate * h about the axis.
glm::dvec3 twist_by(const double* s, const glm::dvec3& p, double direction) {
  const Frame f = frame_of(s);
  const glm::dvec3 l = f.to_local(p);
  const double a = direction * s[4] * l.x, c = std::cos(a), sn = std::sin(a);
  return f.to_world({l.x, c * l.y - sn * l.z, sn * l.y + c * l.z});
}

double taper_scale(const double* s, double h) {
  const double h0 = s[4], h1 = s[5], s0 = s[6], s1 = s[7];
  const double t = std::clamp((h - h0) / (h1 - h0), 0.0, 1.0);
  return s0 + (s1 - s0) * t;
}

// sin(theta)/theta and (1 - cos(theta))/theta, stable near 0 so that rate -> 0 is the identity.
double sinc(double t) { return std::abs(t) < 1e-4 ? 1.0 - t * t / 6.0 : std::sin(t) / t; }
double cosc(double t) { return std::abs(t) < 1e-4 ? t / 2.0 - t * t * t / 24.0 : (1.0 - std::cos(t)) / t; }

// The n + 1 Bernstein polynomials of degree n at t, into b[0..n]: powers by products (std::pow
// for each of them cost as much as the rest of the deformation).
void bernstein_basis(int n, double t, double* b) {
  double up = 1.0;  // t^i
  for (int i = 0; i <= n; ++i) b[i] = up, up *= t;
  double down = 1.0, binom = 1.0;  // (1 - t)^(n - i), C(n, i)
  for (int i = n; i >= 0; --i) {
    b[i] *= down;
    down *= 1.0 - t;
  }
  for (int i = 0; i <= n; ++i) {
    b[i] *= binom;
    binom = binom * (n - i) / (i + 1);
  }
}

// The frame only permutes and translates coordinates, so boxes map to boxes.
Aabb local_box(const Frame& f, const Aabb& box) {
  Aabb out;
  out.grow(f.to_local(box.lo));
  out.grow(f.to_local(box.hi));
  return out;
}
Aabb world_box(const Frame& f, const Aabb& local) {
  Aabb out;
  out.grow(f.to_world(local.lo));
  out.grow(f.to_world(local.hi));
  return out;
}

}  // namespace

void bend_forward(double h0, double h1, double k, double& u, double& v) {
  const double hc = std::clamp(u, h0, h1);
  const double theta = k * hc;
  const double c = std::cos(theta), s = std::sin(theta);
  // The bent part follows the circle of radius 1/k about (0, 1/k); beyond the range, the
  // continuation is the rigid motion of the range's end.
  const double du = u - hc;
  const double nu = hc * sinc(theta) + c * du - s * v;
  const double nv = hc * cosc(theta) + s * du + c * v;
  u = nu;
  v = nv;
}

void bend_inverse(double h0, double h1, double k, double& u, double& v) {
  // The angle of the point about the centre of curvature gives the slice it came from.
  double hc = std::clamp(u, h0, h1);
  if (k != 0.0) hc = std::clamp(std::atan2(k * u, 1.0 - k * v) / k, h0, h1);
  const double theta = k * hc;
  const double c = std::cos(theta), s = std::sin(theta);
  const double du = u - hc * sinc(theta), dv = v - hc * cosc(theta);
  u = hc + c * du + s * dv;
  v = -s * du + c * dv;
}

bool affine_from_matrix(const double* m, double* out) {
  glm::dmat3 a(1.0);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) a[c][r] = m[4 * r + c];  // glm is column-major
  // Invertible in doubles: a finite, nonzero determinant, a finite inverse, and a condition
  // number (in the largest-entry norm) under 1e12. |det| against the largest entry cubed, the
  // rule before, called diag(1e4, 1e-4, 1) singular: its determinant is 1, its condition 1e8.
  const double det = glm::determinant(a);
  if (!std::isfinite(det) || det == 0.0) return false;
  const glm::dmat3 inv = glm::inverse(a);
  double big = 0.0, big_inverse = 0.0;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) {
      if (!std::isfinite(inv[c][r])) return false;
      big = std::max(big, std::abs(a[c][r]));
      big_inverse = std::max(big_inverse, std::abs(inv[c][r]));
    }
  if (!(big * big_inverse < kMaxAffineCondition)) return false;
  const glm::dvec3 t(m[3], m[7], m[11]);
  const glm::dvec3 it = -(inv * t);
  std::copy(m, m + 12, out);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out[12 + 4 * r + c] = inv[c][r];
    out[12 + 4 * r + 3] = it[r];
  }
  return true;
}

glm::dvec3 warp_forward(NodeKind kind, const double* s, const glm::dvec3& p) {
  switch (kind) {
    case NodeKind::Affine: return apply3x4(s, p);
    case NodeKind::Twist: return twist_by(s, p, 1.0);
    case NodeKind::Taper: {
      const Frame f = frame_of(s);
      glm::dvec3 l = f.to_local(p);
      const double k = taper_scale(s, l.x);
      return f.to_world({l.x, k * l.y, k * l.z});
    }
    case NodeKind::Bend: {
      const Frame f = frame_of(s);
      glm::dvec3 l = f.to_local(p);
      bend_forward(s[4], s[5], s[6], l.x, l.y);
      return f.to_world(l);
    }
    case NodeKind::Ffd: {
      const glm::dvec3 lo(s[0], s[1], s[2]), hi(s[3], s[4], s[5]);
      if (!Aabb{lo, hi}.contains(p)) return p;
      const int dims[3] = {static_cast<int>(s[6]), static_cast<int>(s[7]), static_cast<int>(s[8])};
      const glm::dvec3 t = (p - lo) / (hi - lo);
      const double* pts = s + kFfdHeader;
      double bx[kFfdMaxDim + 1], by[kFfdMaxDim + 1], bz[kFfdMaxDim + 1];
      bernstein_basis(dims[0], t.x, bx);
      bernstein_basis(dims[1], t.y, by);
      bernstein_basis(dims[2], t.z, bz);
      glm::dvec3 out(0.0);
      for (int k = 0; k <= dims[2]; ++k) {
        const double bk = bz[k];
        for (int j = 0; j <= dims[1]; ++j) {
          const double bj = bk * by[j];
          for (int i = 0; i <= dims[0]; ++i) {
            const double w = bj * bx[i];
            const int idx = 3 * (i + (dims[0] + 1) * (j + (dims[1] + 1) * k));
            out += w * glm::dvec3(pts[idx], pts[idx + 1], pts[idx + 2]);
          }
        }
      }
      return out;
    }
    default: return p;
  }
}

glm::dvec3 warp_inverse(NodeKind kind, const double* s, const glm::dvec3& p) {
  switch (kind) {
    case NodeKind::Affine: return apply3x4(s + 12, p);
    case NodeKind::Twist: return twist_by(s, p, -1.0);  // twisting keeps h: turn back by rate*h
    case NodeKind::Taper: {
      const Frame f = frame_of(s);
      glm::dvec3 l = f.to_local(p);
      const double k = taper_scale(s, l.x);
      return f.to_world({l.x, l.y / k, l.z / k});
    }
    case NodeKind::Bend: {
      const Frame f = frame_of(s);
      glm::dvec3 l = f.to_local(p);
      bend_inverse(s[4], s[5], s[6], l.x, l.y);
      return f.to_world(l);
    }
    default: return p;
  }
}

Aabb warp_bounds(NodeKind kind, const double* s, const Aabb& box) {
  if (box.empty()) return box;
  if (!box.finite()) return Aabb::everything();
  switch (kind) {
    case NodeKind::Affine: {
      Aabb out;
      for (int c = 0; c < 8; ++c)
        out.grow(apply3x4(s, {(c & 1) ? box.hi.x : box.lo.x, (c & 2) ? box.hi.y : box.lo.y,
                              (c & 4) ? box.hi.z : box.lo.z}));
      return out;
    }
    case NodeKind::Twist: {
      // The slices of the box turn by angles in [a0, a1]. A linear function of the rectangle is
      // largest at a corner, and a corner's coordinate along a direction is largest either at an
      // end of the angle range or where the corner turns onto that direction.
      const Frame f = frame_of(s);
      const Aabb local = local_box(f, box);
      const double a0 = std::min(s[4] * local.lo.x, s[4] * local.hi.x);
      const double a1 = std::max(s[4] * local.lo.x, s[4] * local.hi.x);
      constexpr double kTurn = 2.0 * std::numbers::pi;
      Aabb out{{local.lo.x, 0.0, 0.0}, {local.hi.x, 0.0, 0.0}};
      out.lo.y = out.lo.z = std::numeric_limits<double>::infinity();
      out.hi.y = out.hi.z = -std::numeric_limits<double>::infinity();
      auto add = [&](double v, double w) {
        out.lo.y = std::min(out.lo.y, v);
        out.hi.y = std::max(out.hi.y, v);
        out.lo.z = std::min(out.lo.z, w);
        out.hi.z = std::max(out.hi.z, w);
      };
      for (double v : {local.lo.y, local.hi.y})
        for (double w : {local.lo.z, local.hi.z}) {
          const double r = std::hypot(v, w), phi = std::atan2(w, v);
          for (double a : {a0, a1}) add(r * std::cos(phi + a), r * std::sin(phi + a));
          for (int k = 0; k < 4; ++k) {  // directions +v, +w, -v, -w
            const double psi = k * kTurn / 4;
            // The turn that brings the corner onto psi, moved to the first one at or after a0.
            const double turn = a0 + std::fmod(std::fmod(psi - phi - a0, kTurn) + kTurn, kTurn);
            if (turn <= a1 || a1 - a0 >= kTurn) add(r * std::cos(psi), r * std::sin(psi));
          }
        }
      return world_box(f, out);
    }
    case NodeKind::Taper: {
      // Each slice scales about the axis by a factor between the two end scales.
      const Frame f = frame_of(s);
      const Aabb local = local_box(f, box);
      const double smin = std::min(s[6], s[7]), smax = std::max(s[6], s[7]);
      const double inf = std::numeric_limits<double>::infinity();
      Aabb out{{local.lo.x, inf, inf}, {local.hi.x, -inf, -inf}};
      for (int axis = 1; axis < 3; ++axis)
        for (double k : {smin, smax})
          for (double c : {local.lo[axis], local.hi[axis]}) {
            out.lo[axis] = std::min(out.lo[axis], k * c);
            out.hi[axis] = std::max(out.hi[axis], k * c);
          }
      return world_box(f, out);
    }
    case NodeKind::Bend: {
      const Frame f = frame_of(s);
      const double h0 = s[4], h1 = s[5], k = s[6];
      const Aabb local = local_box(f, box);
      Aabb out;
      auto add = [&](double u, double v, double w) {
        bend_forward(h0, h1, k, u, v);
        out.grow(f.to_world({u, v, w}));
      };
      // Every slice moves rigidly in the (u, v) plane, and within the range the image of the
      // box is an annular sector about the centre of curvature: its corners and the points
      // where the sector crosses a quarter turn bound it.
      std::vector<double> us = {local.lo.x, local.hi.x};
      for (double h : {h0, h1})
        if (h > local.lo.x && h < local.hi.x) us.push_back(h);
      if (k != 0.0) {
        constexpr double kQuarter = std::numbers::pi / 2;
        const double a0 = k * std::clamp(local.lo.x, h0, h1), a1 = k * std::clamp(local.hi.x, h0, h1);
        const double amin = std::min(a0, a1), amax = std::max(a0, a1);
        // A whole turn or more, or angles so large that doubles no longer step finely along
        // them: the bent part lies in the annulus about the centre of curvature (0, 1/k), whose
        // box is that of the disc of its outer radius. Listing the quarter turns instead took
        // memory in proportion to the rate (1e9: 2 GB, then bad_alloc).
        if (!(amax - amin < 2 * std::numbers::pi && std::abs(amin) < 1e6 && std::abs(amax) < 1e6)) {
          const double c = 1.0 / k;
          const double r = std::max(std::abs(c - local.lo.y), std::abs(c - local.hi.y));
          for (double u : {-r, r})
            for (double v : {c - r, c + r})
              for (double w : {local.lo.z, local.hi.z}) out.grow(f.to_world({u, v, w}));
        } else {
          for (double q = std::ceil(amin / kQuarter) * kQuarter; q <= amax; q += kQuarter) us.push_back(q / k);
        }
      }
      for (double u : us)
        for (double v : {local.lo.y, local.hi.y})
          for (double w : {local.lo.z, local.hi.z}) add(u, v, w);
      return out;
    }
    default: return Aabb::everything();  // ffd: its field lives on its deformed mesh
  }
}

}  // namespace ht
