// The lane math of every tape instruction, written once as templates over the lane type: float
// for values (the loops vectorize) and Dual for values with their gradient (forward-mode
// differentiation, so gradients are exact to float rounding, not finite differences).
// Constant layouts match runtime/tape_compiler.cpp.
#pragma once

#include <algorithm>
#include <cmath>

namespace ht::tape_ops {

#define HT_LANE [[gnu::always_inline]] inline

/// A value and its gradient with respect to the query point.
struct Dual {
  float v = 0, dx = 0, dy = 0, dz = 0;
  Dual() = default;
  constexpr Dual(float value) : v(value) {}  // NOLINT: constants promote implicitly
  constexpr Dual(float value, float gx, float gy, float gz) : v(value), dx(gx), dy(gy), dz(gz) {}
};
HT_LANE Dual operator+(Dual a, Dual b) { return {a.v + b.v, a.dx + b.dx, a.dy + b.dy, a.dz + b.dz}; }
HT_LANE Dual operator-(Dual a, Dual b) { return {a.v - b.v, a.dx - b.dx, a.dy - b.dy, a.dz - b.dz}; }
HT_LANE Dual operator-(Dual a) { return {-a.v, -a.dx, -a.dy, -a.dz}; }
HT_LANE Dual operator*(Dual a, Dual b) {
  return {a.v * b.v, a.dx * b.v + a.v * b.dx, a.dy * b.v + a.v * b.dy, a.dz * b.v + a.v * b.dz};
}
HT_LANE Dual operator/(Dual a, Dual b) {
  const float inv = 1.0f / b.v;
  const float q = a.v * inv;
  return {q, (a.dx - q * b.dx) * inv, (a.dy - q * b.dy) * inv, (a.dz - q * b.dz) * inv};
}
HT_LANE Dual scale(Dual a, float k) { return {a.v * k, a.dx * k, a.dy * k, a.dz * k}; }
HT_LANE Dual chain(Dual a, float value, float slope) { return {value, a.dx * slope, a.dy * slope, a.dz * slope}; }

HT_LANE float val(float x) { return x; }
HT_LANE float val(const Dual& x) { return x.v; }

HT_LANE float sqrt_(float x) { return std::sqrt(x); }
HT_LANE Dual sqrt_(Dual x) {
  const float r = std::sqrt(x.v);
  return chain(x, r, r > 0 ? 0.5f / r : 0.0f);  // the cusp at 0: a zero gradient, by convention
}
HT_LANE float sin_(float x) { return std::sin(x); }
HT_LANE Dual sin_(Dual x) { return chain(x, std::sin(x.v), std::cos(x.v)); }
HT_LANE float cos_(float x) { return std::cos(x); }
HT_LANE Dual cos_(Dual x) { return chain(x, std::cos(x.v), -std::sin(x.v)); }
HT_LANE float atan2_(float y, float x) { return std::atan2(y, x); }
HT_LANE Dual atan2_(Dual y, Dual x) {
  const float r2 = x.v * x.v + y.v * y.v;
  const float k = r2 > 0 ? 1.0f / r2 : 0.0f;
  return {std::atan2(y.v, x.v), (x.v * y.dx - y.v * x.dx) * k, (x.v * y.dy - y.v * x.dy) * k,
          (x.v * y.dz - y.v * x.dz) * k};
}
// std::max and std::min: on a tie or a NaN in b, a. Written with the other operand first, the
// float forms are exactly x86's maxps and minps, so they compile to one instruction, not a
// compare and a blend.
template <class T>
HT_LANE T max_(const T& a, const T& b) {
  return val(a) < val(b) ? b : a;
}
template <class T>
HT_LANE T min_(const T& a, const T& b) {
  return val(b) < val(a) ? b : a;
}
template <class T>
HT_LANE T clamp_(const T& x, float lo, float hi) {
  return val(x) < lo ? T(lo) : val(x) > hi ? T(hi) : x;
}
template <class T>
HT_LANE T abs_(const T& x) {
  return val(x) < 0 ? T(0.0f) - x : x;
}

// The float lanes select instead of branching: every arm is computed and a select (a blend on
// x86) keeps one, so GCC vectorizes the loops on every target, AVX2 and SSE included, whose
// lack of masked arithmetic made it keep a computing arm behind a branch. NaN keeps the
// templates' choice (a comparison with NaN is false).
HT_LANE float max_(float a, float b) { return a < b ? b : a; }
HT_LANE float min_(float a, float b) { return b < a ? b : a; }
HT_LANE float clamp_(float x, float lo, float hi) {
  const float above = x < lo ? lo : x;
  return above > hi ? hi : above;
}
HT_LANE float abs_(float x) { return std::fabs(x); }
HT_LANE float select_(bool c, float a, float b) { return c ? a : b; }

template <class T>
struct V3 {
  T x, y, z;
};
template <class T>
HT_LANE V3<T> sub(const V3<T>& a, const float* c) {
  return {a.x - c[0], a.y - c[1], a.z - c[2]};
}
template <class T>
HT_LANE T dot(const V3<T>& a, const float* c) {
  return a.x * c[0] + a.y * c[1] + a.z * c[2];
}
template <class T>
HT_LANE T norm2(const V3<T>& a) {
  return a.x * a.x + a.y * a.y + a.z * a.z;
}

/// g from a squared distance: F (1 - d^2/R^2)^3 inside the support, 0 outside. Header k:
/// [R^2, 1/R^2, F, R].
template <class T>
HT_LANE T falloff2(const T& d2, const float* k) {
  const T u = T(1.0f) - d2 * k[1];
  return val(u) > 0 ? u * u * u * k[2] : T(0.0f);
}
HT_LANE float falloff2(float d2, const float* k) {
  const float u = 1.0f - d2 * k[1], m = u > 0.0f ? u : 0.0f;
  return m * m * m * k[2];
}

// Squared distances to the skeletons; s points past the 4-float header.
template <class T>
HT_LANE T point2(const V3<T>& q, const float* s) {
  return norm2(sub(q, s));
}

template <class T>
HT_LANE T segment2(const V3<T>& q, const float* s) {  // a(3) ab(3) 1/|ab|^2
  const V3<T> pa = sub(q, s);
  const T t = clamp_(dot(pa, s + 3) * s[6], 0.0f, 1.0f);
  const V3<T> d{pa.x - t * s[3], pa.y - t * s[4], pa.z - t * s[5]};
  return norm2(d);
}

template <class T>
HT_LANE T circle2(const V3<T>& q, const float* s, bool filled) {  // c(3) n(3) rho
  const V3<T> pc = sub(q, s);
  const T h = dot(pc, s + 3);
  const T r = sqrt_(max_(norm2(pc) - h * h, T(0.0f)));
  T radial = r - s[6];
  if (filled) radial = max_(radial, T(0.0f));
  return h * h + radial * radial;
}

template <class T>
HT_LANE T triangle2(const V3<T>& q, const float* s) {
  // a b c, ba cb ac, ba x n, cb x n, ac x n, n, 1/|ba|^2 1/|cb|^2 1/|ac|^2 1/|n|^2.
  const V3<T> pa = sub(q, s), pb = sub(q, s + 3), pc = sub(q, s + 6);
  auto side = [](const T& x) { return val(x) > 0 ? 1 : val(x) < 0 ? -1 : 0; };
  const int inside_prism = side(dot(pa, s + 18)) + side(dot(pb, s + 21)) + side(dot(pc, s + 24));
  if (inside_prism < 2) {
    auto edge = [&](const V3<T>& p, const float* e, float inv) {
      const T t = clamp_(dot(p, e) * inv, 0.0f, 1.0f);
      const V3<T> d{t * e[0] - p.x, t * e[1] - p.y, t * e[2] - p.z};
      return norm2(d);
    };
    return min_(min_(edge(pa, s + 9, s[30]), edge(pb, s + 12, s[31])), edge(pc, s + 15, s[32]));
  }
  const T h = dot(pa, s + 27);
  return h * h * s[33];
}

HT_LANE float triangle2(const V3<float>& q, const float* s) {
  const V3<float> pa = sub(q, s), pb = sub(q, s + 3), pc = sub(q, s + 6);
  auto side = [](float x) { return select_(x > 0, 1.0f, select_(x < 0, -1.0f, 0.0f)); };
  const float inside_prism = side(dot(pa, s + 18)) + side(dot(pb, s + 21)) + side(dot(pc, s + 24));
  auto edge = [&](const V3<float>& p, const float* e, float inv) {
    const float t = clamp_(dot(p, e) * inv, 0.0f, 1.0f);
    const V3<float> d{t * e[0] - p.x, t * e[1] - p.y, t * e[2] - p.z};
    return norm2(d);
  };
  const float to_edges = min_(min_(edge(pa, s + 9, s[30]), edge(pb, s + 12, s[31])), edge(pc, s + 15, s[32]));
  const float h = dot(pa, s + 27);
  return select_(inside_prism < 2.0f, to_edges, h * h * s[33]);
}

template <class T>
HT_LANE T box2(const V3<T>& q, const float* s) {  // centre(3) half(3)
  const T ox = max_(abs_(q.x - s[0]) - s[3], T(0.0f));
  const T oy = max_(abs_(q.y - s[1]) - s[4], T(0.0f));
  const T oz = max_(abs_(q.z - s[2]) - s[5], T(0.0f));
  return ox * ox + oy * oy + oz * oz;
}

template <class T>
HT_LANE T cylinder2(const V3<T>& q, const float* s) {  // a(3) u(3) len rho
  const V3<T> pa = sub(q, s);
  const T t = dot(pa, s + 3);
  const T r = sqrt_(max_(norm2(pa) - t * t, T(0.0f)));
  const T radial = max_(r - s[7], T(0.0f));
  const T along = max_(max_(T(0.0f) - t, t - s[6]), T(0.0f));
  return radial * radial + along * along;
}

template <class T>
HT_LANE T cone_sphere2(const V3<T>& q, const float* s) {
  // a(3) u(3) len ra rb sin cos flag; flag 1: one sphere holds the other, centre a, radius s[7].
  const V3<T> pa = sub(q, s);
  if (s[11] != 0.0f) {
    const T d = max_(sqrt_(norm2(pa)) - s[7], T(0.0f));
    return d * d;
  }
  const T x = dot(pa, s + 3);
  const T y = sqrt_(max_(norm2(pa) - x * x, T(0.0f)));
  const float len = s[6], ra = s[7], rb = s[8], sn = s[9], cs = s[10];
  const T along = x * cs - y * sn;
  T sd;
  if (val(along) < 0)
    sd = sqrt_(x * x + y * y) - ra;
  else if (val(along) > len * cs)
    sd = sqrt_((x - len) * (x - len) + y * y) - rb;
  else
    sd = y * cs + x * sn - ra;
  const T d = max_(sd, T(0.0f));
  return d * d;
}

HT_LANE float cone_sphere2(const V3<float>& q, const float* s) {
  const V3<float> pa = sub(q, s);
  const float x = dot(pa, s + 3);
  const float y = sqrt_(max_(norm2(pa) - x * x, 0.0f));
  const float len = s[6], ra = s[7], rb = s[8], sn = s[9], cs = s[10];
  const float along = x * cs - y * sn;
  const float to_a = sqrt_(x * x + y * y) - ra, to_b = sqrt_((x - len) * (x - len) + y * y) - rb;
  float sd = select_(along < 0, to_a, select_(along > len * cs, to_b, y * cs + x * sn - ra));
  if (s[11] != 0.0f) sd = to_a;  // one sphere holds the other: centre a, radius s[7] (loop-invariant)
  const float d = max_(sd, 0.0f);
  return d * d;
}

// Operators.
inline constexpr float kRUnionWeight = 1.0f / (2.0f - 1.41421356f);
inline constexpr float kRIntersectionWeight = 1.0f / (2.0f + 1.41421356f);

template <class T>
HT_LANE T r_union(const T& fa, const T& fb, float t) {
  const T a = fa - t, b = fb - t;
  return T(t) + (a + b + sqrt_(a * a + b * b)) * kRUnionWeight;
}
template <class T>
HT_LANE T r_intersection(const T& fa, const T& fb, float t) {
  const T a = fa - t, b = fb - t;
  return T(t) + (a + b - sqrt_(a * a + b * b)) * kRIntersectionWeight;
}
template <class T>
HT_LANE T local_blend(const T& fa, const T& fb, const T& fr, float t, bool rf) {
  const T w = clamp_(fr, 0.0f, 1.0f);
  const T u = rf ? r_union(fa, fb, t) : max_(fa, fb);
  return w * (fa + fb) + (T(1.0f) - w) * u;
}
template <class T>
HT_LANE T crop(const T& f, const V3<T>& q, const float* k) {  // centre(3) half(3) T/L T
  const T qx = abs_(q.x - k[0]) - k[3], qy = abs_(q.y - k[1]) - k[4], qz = abs_(q.z - k[2]) - k[5];
  const T ox = max_(qx, T(0.0f)), oy = max_(qy, T(0.0f)), oz = max_(qz, T(0.0f));
  const T outside = sqrt_(ox * ox + oy * oy + oz * oz);
  const T inside = min_(max_(qx, max_(qy, qz)), T(0.0f));
  const T h = T(k[7]) - (outside + inside) * k[6];
  return max_(T(0.0f), min_(f, h));
}

#undef HT_LANE

}  // namespace ht::tape_ops
