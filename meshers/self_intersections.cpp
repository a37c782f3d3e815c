#include "meshers/self_intersections.hpp"

#include "meshers/box_pairs.hpp"
#include "meshers/embedded_fans.hpp"

#include <embree3/rtcore.h>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>

namespace ht {
namespace {

using glm::dvec3;

// ---- Exact arithmetic ------------------------------------------------------------------------
// An expansion is a sum of doubles, nonoverlapping and sorted by increasing magnitude, that
// holds a value exactly; its sign is the sign of its largest component. Round-to-nearest double
// arithmetic (SSE2) is assumed, as everywhere on x86-64 and AArch64.

/// s + e == a + b exactly, s the rounded sum (the branch-free two-sum).
inline void two_sum(double a, double b, double& s, double& e) {
  s = a + b;
  const double bv = s - a, av = s - bv;
  e = (a - av) + (b - bv);
}

/// d = a - b; true when that difference is exact and, unless zero, not so small (below 1e-80)
/// that a product of three such could underflow.
inline bool exact_diff(double a, double b, double& d) {
  double e;
  two_sum(a, -b, d, e);
  return e == 0 && (d == 0 || std::abs(d) > 1e-80);
}

class Expansion {
 public:
  /// Adds b exactly: two-sums from the smallest component up keep the invariant; zero
  /// components are dropped.
  void add(double b) {
    int m = 0;
    for (int i = 0; i < n_; ++i) {
      double s, e;
      two_sum(b, c_[i], s, e);
      b = s;
      if (e != 0) c_[m++] = e;
    }
    if (b != 0) c_[m++] = b;
    n_ = m;
  }
  /// Adds x*y*z (negated when asked) exactly: x*y = p + e with a fused multiply-add for the
  /// rounding error, then p*z and e*z the same way; four doubles in all.
  void add_product(double x, double y, double z, bool negate) {
    const double p = x * y, e = std::fma(x, y, -p);
    const double p1 = p * z, e1 = std::fma(p, z, -p1);
    const double p2 = e * z, e2 = std::fma(e, z, -p2);
    const double s = negate ? -1.0 : 1.0;
    for (const double part : {e2, p2, e1, p1}) add(s * part);
  }
  int sign() const { return n_ == 0 ? 0 : (c_[n_ - 1] > 0 ? 1 : -1); }

 private:
  std::array<double, 100> c_;  // orient3d needs at most 24 products * 4 components; uninitialized
  int n_ = 0;
};

/// Adds (negated when asked) det[p; q; r] = p . (q x r): six products of three coordinates.
void add_det3(Expansion& e, const dvec3& p, const dvec3& q, const dvec3& r, bool negate) {
  e.add_product(p.x, q.y, r.z, negate);
  e.add_product(p.x, q.z, r.y, !negate);
  e.add_product(p.y, q.z, r.x, negate);
  e.add_product(p.y, q.x, r.z, !negate);
  e.add_product(p.z, q.x, r.y, negate);
  e.add_product(p.z, q.y, r.x, !negate);
}

/// Sign of det[b-a; c-a; d-a], exactly: det[u; v; w] of the differences when all nine are exact
/// (typical of nearby vertices), six products; else, by multilinearity, determinants of the
/// inputs themselves: det(bcd) - det(acd) + det(abd) - det(abc), 24 products.
int orient3d_exact(const dvec3& a, const dvec3& b, const dvec3& c, const dvec3& d) {
  Expansion e;
  dvec3 u, v, w;
  bool exact = true;
  for (int k = 0; k < 3; ++k)
    exact = exact_diff(b[k], a[k], u[k]) && exact_diff(c[k], a[k], v[k]) && exact_diff(d[k], a[k], w[k]) && exact;
  if (exact) {
    add_det3(e, u, v, w, false);
    return e.sign();
  }
  add_det3(e, b, c, d, false);
  add_det3(e, a, c, d, true);
  add_det3(e, a, b, d, false);
  add_det3(e, a, b, c, true);
  return e.sign();
}

/// Sign of the 2D determinant of (b-a, c-a) in coordinates (i, j), exactly: the two products of
/// the differences when those are exact, else the six cross terms of the inputs.
int orient2d_exact(const dvec3& a, const dvec3& b, const dvec3& c, int i, int j) {
  Expansion e;
  double bi, bj, ci, cj;
  if (exact_diff(b[i], a[i], bi) && exact_diff(b[j], a[j], bj) && exact_diff(c[i], a[i], ci) &&
      exact_diff(c[j], a[j], cj)) {
    e.add_product(bi, cj, 1.0, false);
    e.add_product(bj, ci, 1.0, true);
    return e.sign();
  }
  const dvec3* pts[3][2] = {{&b, &c}, {&c, &a}, {&a, &b}};  // the cyclic cross terms
  for (const auto& pq : pts) {
    e.add_product((*pq[0])[i], (*pq[1])[j], 1.0, false);
    e.add_product((*pq[0])[j], (*pq[1])[i], 1.0, true);
  }
  return e.sign();
}

constexpr double kUnitRoundoff = std::numeric_limits<double>::epsilon() / 2;

/// Whether every product of det[u; v; w] = w . (u x v) has a factor that is zero: then it is
/// exactly zero, as a rounded difference is zero exactly when the exact one is.
bool zero_terms(const dvec3& u, const dvec3& v, const dvec3& w) {
  const auto z = [](double x, double y) { return x == 0 || y == 0; };
  return (w.x == 0 || (z(u.y, v.z) && z(u.z, v.y))) && (w.y == 0 || (z(u.z, v.x) && z(u.x, v.z))) &&
         (w.z == 0 || (z(u.x, v.y) && z(u.y, v.x)));
}

/// Sign of det[b-a; c-a; d-a]: positive when d lies on the side of plane abc that the normal
/// (b-a) x (c-a) points to. The double evaluation errs by at most about 7u times the permanent
/// (u the unit roundoff); below 16u times it the sign is recomputed exactly. A permanent of zero
/// is decided on the spot when every term has a zero factor (say, four points in a coordinate
/// plane), which the error bound alone cannot tell from a tiny nonzero value.
int orient3d(const dvec3& a, const dvec3& b, const dvec3& c, const dvec3& d) {
  const dvec3 u = b - a, v = c - a, w = d - a;
  const double x1 = u.y * v.z, x2 = u.z * v.y, y1 = u.z * v.x, y2 = u.x * v.z;
  const double z1 = u.x * v.y, z2 = u.y * v.x;
  const double det = w.x * (x1 - x2) + w.y * (y1 - y2) + w.z * (z1 - z2);
  const double perm = std::abs(w.x) * (std::abs(x1) + std::abs(x2)) +
                      std::abs(w.y) * (std::abs(y1) + std::abs(y2)) + std::abs(w.z) * (std::abs(z1) + std::abs(z2));
  const double bound = 16 * kUnitRoundoff * perm;
  if (det > bound) return 1;
  if (det < -bound) return -1;
  return perm == 0 && zero_terms(u, v, w) ? 0 : orient3d_exact(a, b, c, d);
}

/// The coordinates a plane is projected onto: dropping `axis` (the other two, in cyclic order).
struct Proj { int i, j; };
Proj projection(int axis) { return {(axis + 1) % 3, (axis + 2) % 3}; }

/// Sign of the 2D determinant of (b-a, c-a) in projection p; error bound about 3u, filter 8u.
int orient2d(const dvec3& a, const dvec3& b, const dvec3& c, Proj p) {
  const double l = (b[p.i] - a[p.i]) * (c[p.j] - a[p.j]), r = (b[p.j] - a[p.j]) * (c[p.i] - a[p.i]);
  const double det = l - r, bound = 8 * kUnitRoundoff * (std::abs(l) + std::abs(r));
  if (det > bound) return 1;
  if (det < -bound) return -1;
  return orient2d_exact(a, b, c, p.i, p.j);
}

// ---- Triangles -------------------------------------------------------------------------------

struct Tri {
  dvec3 v[3];
  int axis = -1;  ///< a coordinate whose dropping keeps the triangle non-degenerate; -1: degenerate
  int sign = 0;   ///< the sign of its orientation in that projection
  int flat = -1;  ///< a coordinate all three corners share (the plane is x[flat] = const), or -1
};

/// Side of point q against t's plane: orient3d(t.v[0], t.v[1], t.v[2], q). In a coordinate
/// plane x[k] = c the determinant is (q[k] - c) times the normal's k component: one comparison.
int side(const Tri& t, const dvec3& q) {
  if (t.flat < 0) return orient3d(t.v[0], t.v[1], t.v[2], q);
  const double d = q[t.flat], c = t.v[0][t.flat];
  return d > c ? t.sign : d < c ? -t.sign : 0;  // exact: comparisons
}

/// What a search keeps of each triangle between its tests (3 bytes, where a Tri copies its
/// corners: 88): the Tri's axis, sign and flat coordinate, computed once.
struct Shape {
  std::int8_t axis = -1, sign = 0, flat = -1;
};

/// Triangle t with the shape computed before: its corners read from the mesh.
Tri tri_of(const TriangleMesh& mesh, std::uint32_t t, const Shape& shape) {
  Tri r;
  for (int k = 0; k < 3; ++k) r.v[k] = mesh.positions[mesh.triangles[t][k]];
  r.axis = shape.axis, r.sign = shape.sign, r.flat = shape.flat;
  return r;
}

/// The triangle, with the axis to drop for 2D tests: the largest normal component first, and
/// the first one whose projection is exactly non-degenerate.
Tri make_tri(const TriangleMesh& mesh, std::uint32_t t) {
  Tri r;
  for (int k = 0; k < 3; ++k) r.v[k] = mesh.positions[mesh.triangles[t][k]];
  const dvec3 n = glm::abs(glm::cross(r.v[1] - r.v[0], r.v[2] - r.v[0]));
  int order[3] = {0, 1, 2};
  std::sort(order, order + 3, [&](int x, int y) { return n[x] > n[y]; });
  for (int k : order)
    if ((r.sign = orient2d(r.v[0], r.v[1], r.v[2], projection(k))) != 0) {
      r.axis = k;
      break;
    }
  // Corners level in x[k]: the normal u x v has only a k component, and dropping k is then the
  // one projection that keeps the triangle non-degenerate, so r.sign is that component's sign.
  for (int k = 0; k < 3 && r.axis >= 0; ++k)
    if (r.v[0][k] == r.v[1][k] && r.v[1][k] == r.v[2][k]) r.flat = k;
  return r;
}

/// Three orientations not mixing strict signs, zeros allowed: inside a closed region.
bool agree(int s0, int s1, int s2) { return (s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0); }
/// All three strictly on one side.
bool one_side(const int s[3]) { return (s[0] > 0 && s[1] > 0 && s[2] > 0) || (s[0] < 0 && s[1] < 0 && s[2] < 0); }

// 2D tests on points of one plane, in a projection that keeps the plane's triangles
// non-degenerate. Closed sets throughout. Disjoint convex polygons (segments included) are always
// strictly separated by the line of an edge of one of them: their closest features are a vertex
// and an edge, two parallel edges or two vertices, and in each case an edge there has such a line.

/// True when all n points q lie strictly on side s of the line e0 e1.
bool all_on_side(const dvec3& e0, const dvec3& e1, int s, const dvec3* q, int n, Proj p) {
  for (int k = 0; k < n; ++k)
    if (orient2d(e0, e1, q[k], p) != s) return false;
  return true;
}

/// The sign of t's orientation in projection p: the side of each directed edge its corners lie on.
int orientation_2d(const Tri& t, Proj p) {
  return p.i == projection(t.axis).i ? t.sign : orient2d(t.v[0], t.v[1], t.v[2], p);
}

/// Whether the line of an edge of t strictly separates the n points q from t.
bool edge_separates(const Tri& t, const dvec3* q, int n, Proj p) {
  const int s = orientation_2d(t, p);
  for (int k = 0; k < 3; ++k)
    if (all_on_side(t.v[k], t.v[(k + 1) % 3], -s, q, n, p)) return true;
  return false;
}

/// Closed segment pq (not a point) and closed triangle t.
bool seg_tri_2d(const dvec3& p, const dvec3& q, const Tri& t, Proj pr) {
  const dvec3 pq[2] = {p, q};
  if (edge_separates(t, pq, 2, pr)) return false;
  const int s = orient2d(p, q, t.v[0], pr);
  return s == 0 || !all_on_side(p, q, s, t.v + 1, 2, pr);
}

bool tri_tri_2d(const Tri& a, const Tri& b, Proj p) {
  return !edge_separates(a, b.v, 3, p) && !edge_separates(b, a.v, 3, p);
}

/// Coplanar triangles sharing corner a.v[k] == b.v[l] meet beyond it exactly when their wedges
/// there share a direction (their intersection is convex and holds the corner). Wedges narrower
/// than a half-turn do exactly when a side ray of one lies in the other: with both wedges
/// counter-clockwise, four orientations about the corner.
bool wedges_overlap(const Tri& a, int k, const Tri& b, int l, Proj p) {
  const int ka = orientation_2d(a, p) > 0 ? 1 : 2, kb = orientation_2d(b, p) > 0 ? 1 : 2;
  const dvec3 &v = a.v[k], &a1 = a.v[(k + ka) % 3], &a2 = a.v[(k + 3 - ka) % 3];
  const dvec3 &b1 = b.v[(l + kb) % 3], &b2 = b.v[(l + 3 - kb) % 3];
  const int s1 = orient2d(v, a1, b1, p), s2 = orient2d(v, b1, a2, p);
  if (s1 >= 0 && s2 >= 0) return true;  // ray b1 in wedge a
  const int s3 = orient2d(v, a1, b2, p), s4 = orient2d(v, b2, a2, p);
  return (s3 >= 0 && s4 >= 0) || (s1 <= 0 && s3 >= 0) || (s2 >= 0 && s4 <= 0);  // b2 in a, a1 in b, a2 in b
}

// 3D tests.

/// Closed segment pq against closed triangle t, given the sides sp, sq of p and q against t's
/// plane. A segment crossing or touching the plane meets the triangle when the line pq passes
/// on no strictly different sides of t's three directed edges.
bool seg_tri_3d(const dvec3& p, const dvec3& q, int sp, int sq, const Tri& t) {
  if (sp != 0 && sp == sq) return false;
  if (sp == 0 && sq == 0) return seg_tri_2d(p, q, t, projection(t.axis));
  return agree(orient3d(p, q, t.v[0], t.v[1]), orient3d(p, q, t.v[1], t.v[2]), orient3d(p, q, t.v[2], t.v[0]));
}

/// Closed triangles. Coplanar ones are compared in 2D; otherwise they meet on the line of their
/// planes, where each cuts a segment whose ends lie on its edges: they meet exactly when an edge
/// of one meets the other.
bool tri_tri(const Tri& a, const Tri& b) {
  int sb[3], sa[3];
  for (int k = 0; k < 3; ++k) sb[k] = side(a, b.v[k]);
  if (one_side(sb)) return false;
  if (sb[0] == 0 && sb[1] == 0 && sb[2] == 0) return tri_tri_2d(a, b, projection(a.axis));
  for (int k = 0; k < 3; ++k) sa[k] = side(b, a.v[k]);
  if (one_side(sa)) return false;
  for (int k = 0; k < 3; ++k) {
    const int l = (k + 1) % 3;
    if (seg_tri_3d(a.v[k], a.v[l], sa[k], sa[l], b) || seg_tri_3d(b.v[k], b.v[l], sb[k], sb[l], a)) return true;
  }
  return false;
}

/// Triangles sharing only corner a.v[k] == b.v[l]. Their intersection is convex and holds that
/// corner; if it holds more it reaches the opposite edge of one of them. The other corners of
/// one strictly on one side of the other's plane settle it first (the common case); both on it:
/// coplanar, a wedge test.
bool share_corner(const Tri& a, int k, const Tri& b, int l) {
  const dvec3 &a1 = a.v[(k + 1) % 3], &a2 = a.v[(k + 2) % 3], &b1 = b.v[(l + 1) % 3], &b2 = b.v[(l + 2) % 3];
  const int s1 = side(a, b1), s2 = side(a, b2);
  if (s1 * s2 > 0) return false;
  if (s1 == 0 && s2 == 0) return wedges_overlap(a, k, b, l, projection(a.axis));
  const int t1 = side(b, a1), t2 = side(b, a2);
  if (t1 * t2 > 0) return false;
  return seg_tri_3d(a1, a2, t1, t2, b) || seg_tri_3d(b1, b2, s1, s2, a);
}

/// Triangles on a common edge v0 v1 with opposite corners a.v[ka] and bo overlap beyond the edge
/// only when coplanar with both opposite corners on the same side of the edge: a fold.
bool folded(const Tri& a, int ka, const dvec3& bo, const dvec3& v0, const dvec3& v1) {
  if (side(a, bo) != 0) return false;
  const Proj p = projection(a.axis);
  return orient2d(v0, v1, a.v[ka], p) == orient2d(v0, v1, bo, p);
}

/// The pair rule (see the header), on triangles with their mesh indices.
bool pair_intersects(const Tri& a, const glm::uvec3& ia, const Tri& b, const glm::uvec3& ib) {
  if (a.axis < 0 || b.axis < 0) return false;
  // Corners of a non-degenerate triangle are distinct points, so each matches at most one.
  int ma[3], mb[3], m = 0;
  for (int k = 0; k < 3; ++k)
    for (int l = 0; l < 3 && m < 3; ++l)
      if (ia[k] == ib[l] || a.v[k] == b.v[l]) {
        ma[m] = k;
        mb[m++] = l;
      }
  if (m == 0) return tri_tri(a, b);
  if (m == 1) return share_corner(a, ma[0], b, mb[0]);
  if (m == 2) return folded(a, 3 - ma[0] - ma[1], b.v[3 - mb[0] - mb[1]], a.v[ma[0]], a.v[ma[1]]);
  return true;  // the same three points: a duplicate face
}

// ---- Candidates from Embree ------------------------------------------------------------------

/// The nearest float to x on the side of `dir` (+1: not below x, -1: not above).
float float_toward(double x, float dir) {
  const float f = static_cast<float>(x);
  return (static_cast<double>(f) - x) * dir < 0 ? std::nextafter(f, dir * std::numeric_limits<float>::infinity()) : f;
}

/// The triangle's box in float, rounded outward and grown by a millionth of its largest side.
/// Rounding is monotone, so even nearest rounding keeps touching boxes overlapping; the outward
/// rounding and the pad are margin, for the cost of a few more candidates.
RTCBounds float_box(const Tri& t) {
  const dvec3 lo = glm::min(t.v[0], glm::min(t.v[1], t.v[2])), hi = glm::max(t.v[0], glm::max(t.v[1], t.v[2]));
  const dvec3 d = hi - lo;
  const float pad = static_cast<float>(1e-6 * std::max(d.x, std::max(d.y, d.z)));
  RTCBounds b{};
  b.lower_x = float_toward(lo.x, -1) - pad, b.upper_x = float_toward(hi.x, 1) + pad;
  b.lower_y = float_toward(lo.y, -1) - pad, b.upper_y = float_toward(hi.y, 1) + pad;
  b.lower_z = float_toward(lo.z, -1) - pad, b.upper_z = float_toward(hi.z, 1) + pad;
  return b;
}

bool boxes_overlap(const Tri& a, const Tri& b) {
  for (int c = 0; c < 3; ++c) {
    const double alo = std::min(a.v[0][c], std::min(a.v[1][c], a.v[2][c]));
    const double ahi = std::max(a.v[0][c], std::max(a.v[1][c], a.v[2][c]));
    const double blo = std::min(b.v[0][c], std::min(b.v[1][c], b.v[2][c]));
    const double bhi = std::max(b.v[0][c], std::max(b.v[1][c], b.v[2][c]));
    if (ahi < blo || bhi < alo) return false;
  }
  return true;
}

/// Whether triangles a and b share a vertex whose fan is certified embedded: then they meet only
/// where the fan's connectivity says (meshers/embedded_fans.hpp), and no exact test is needed.
bool share_embedded_fan(const glm::uvec3& a, const glm::uvec3& b, const std::vector<std::uint8_t>& fans) {
  for (int k = 0; k < 3; ++k)
    if (fans[a[k]] && (a[k] == b[0] || a[k] == b[1] || a[k] == b[2])) return true;
  return false;
}

using PairLists = tbb::enumerable_thread_specific<std::vector<std::uint64_t>>;  // (i << 32) | j, i < j

struct Collector {
  const TriangleMesh* mesh;
  const std::vector<Shape>* shapes;
  PairLists found;
};

void bounds_of(const RTCBoundsFunctionArguments* args) {
  const auto* boxes = static_cast<const RTCBounds*>(args->geometryUserPtr);
  *args->bounds_o = boxes[args->primID];
}

/// Embree calls this from its worker threads with all pairs of primitives of two leaves whose
/// node boxes overlap: not filtered by the primitives' own boxes, without (i, i), and (in 3.13,
/// scene against itself) each pair in both orders. Either order is kept, normalized, so nothing
/// depends on that symmetry.
void on_collide(void* user, RTCCollision* hits, unsigned int n) {
  auto& c = *static_cast<Collector*>(user);
  auto& out = c.found.local();
  const auto& S = *c.shapes;
  for (unsigned int k = 0; k < n; ++k) {
    std::uint32_t i = hits[k].primID0, j = hits[k].primID1;
    if (i == j) continue;
    if (i > j) std::swap(i, j);
    if (S[i].axis < 0 || S[j].axis < 0 || !boxes_overlap(tri_of(*c.mesh, i, S[i]), tri_of(*c.mesh, j, S[j]))) continue;
    out.push_back(std::uint64_t(i) << 32 | j);
  }
}

/// Candidate pairs (i, j), i < j, bucketed by i: the j of bucket i are second[start[i] ..
/// start[i + 1]), in no order and possibly repeated. A counting sort of the per-thread lists.
struct Buckets {
  std::vector<std::size_t> start;
  std::vector<std::uint32_t> second;
};

template <class Lists>
Buckets bucket_pairs(const Lists& found, std::size_t n) {
  Buckets b{std::vector<std::size_t>(n + 1, 0), {}};
  for (const auto& v : found)
    for (const std::uint64_t p : v) ++b.start[(p >> 32) + 1];
  std::partial_sum(b.start.begin(), b.start.end(), b.start.begin());
  b.second.resize(b.start.back());
  std::vector<std::size_t> fill(b.start.begin(), b.start.end() - 1);
  for (const auto& v : found)
    for (const std::uint64_t p : v) b.second[fill[p >> 32]++] = static_cast<std::uint32_t>(p);
  return b;
}

void check_embree(RTCDevice device, const char* what) {
  if (rtcGetDeviceError(device) != RTC_ERROR_NONE)
    throw std::runtime_error(std::string("find_self_intersections: Embree could not ") + what);
}

/// The pairs i < j of non-degenerate triangles whose boxes overlap, bucketed by i, from Embree's
/// self-collision of a box hierarchy.
Buckets hierarchy_pairs(const TriangleMesh& mesh, const std::vector<Shape>& shapes) {
  std::unique_ptr<RTCDeviceTy, decltype(&rtcReleaseDevice)> device(rtcNewDevice(nullptr), rtcReleaseDevice);
  if (!device) throw std::runtime_error("find_self_intersections: cannot create an Embree device");
  std::vector<RTCBounds> boxes(shapes.size());
  // A degenerate triangle intersects nothing here (on_collide skips it): an empty box (lower
  // above upper), which Embree leaves out. Given the point boxes of a mesh collapsed to one
  // point, its builder asserted (a zero-size scene) and aborted the process.
  tbb::parallel_for(std::size_t(0), shapes.size(), [&](std::size_t t) {
    if (shapes[t].axis < 0) boxes[t] = RTCBounds{1.0f, 1.0f, 1.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    else boxes[t] = float_box(tri_of(mesh, static_cast<std::uint32_t>(t), shapes[t]));
  });
  std::unique_ptr<RTCSceneTy, decltype(&rtcReleaseScene)> scene(rtcNewScene(device.get()), rtcReleaseScene);
  RTCGeometry geom = scene ? rtcNewGeometry(device.get(), RTC_GEOMETRY_TYPE_USER) : nullptr;
  if (!geom) throw std::runtime_error("find_self_intersections: Embree could not create its scene");
  rtcSetGeometryUserPrimitiveCount(geom, static_cast<unsigned int>(shapes.size()));
  rtcSetGeometryUserData(geom, boxes.data());
  rtcSetGeometryBoundsFunction(geom, bounds_of, nullptr);
  rtcCommitGeometry(geom);
  rtcAttachGeometry(scene.get(), geom);
  rtcReleaseGeometry(geom);  // the scene holds it now
  rtcSetSceneBuildQuality(scene.get(), RTC_BUILD_QUALITY_LOW);  // a Morton build: quick, good enough here
  rtcCommitScene(scene.get());
  check_embree(device.get(), "build its box hierarchy");
  Collector c{&mesh, &shapes, {}};
  rtcCollide(scene.get(), scene.get(), on_collide, &c);
  check_embree(device.get(), "collide the boxes");
  return bucket_pairs(c.found, shapes.size());
}

/// The intersecting pairs (i << 32 | j, i < j) in increasing order, from a uniform grid's
/// candidate pairs tested as they are found, when the triangles are of a size, as a mesh's are
/// (meshers/box_pairs.hpp: no hierarchy to build, no candidate stored: on the quality pass's
/// 81k-triangle snake the grid took 29 ms against the hierarchy's 72); nullopt when the grid
/// declines.
std::optional<std::vector<std::uint64_t>> grid_hits(const TriangleMesh& mesh, const std::vector<Shape>& shapes,
                                                    const std::vector<std::uint8_t>& fans) {
  const auto& P = mesh.positions;
  const auto& T = mesh.triangles;
  std::vector<dvec3> lo(T.size()), hi(T.size());
  std::vector<std::uint8_t> skip(T.size());
  tbb::parallel_for(std::size_t(0), T.size(), [&](std::size_t t) {
    const dvec3 a = P[T[t][0]], b = P[T[t][1]], c = P[T[t][2]];
    lo[t] = glm::min(a, glm::min(b, c)), hi[t] = glm::max(a, glm::max(b, c));
    skip[t] = shapes[t].axis < 0;
  });
  tbb::enumerable_thread_specific<std::vector<std::uint64_t>> found;
  const bool gridded = grid_box_pairs(lo, hi, skip, [&](std::span<const std::uint64_t> batch) {
    auto& out = found.local();
    for (const std::uint64_t p : batch) {
      const auto i = static_cast<std::uint32_t>(p >> 32), j = static_cast<std::uint32_t>(p);
      if (share_embedded_fan(T[i], T[j], fans)) continue;
      if (pair_intersects(tri_of(mesh, i, shapes[i]), T[i], tri_of(mesh, j, shapes[j]), T[j])) out.push_back(p);
    }
  });
  if (!gridded) return std::nullopt;
  std::vector<std::uint64_t> hits;
  for (const auto& v : found) hits.insert(hits.end(), v.begin(), v.end());
  std::sort(hits.begin(), hits.end());  // each pair once (the grid reports it from one cell)
  return hits;
}

/// Each bucket i sorted and deduplicated, then the j that intersect i moved to its front, in
/// order; returns how many there are per bucket.
std::vector<std::uint32_t> test_buckets(const TriangleMesh& mesh, const std::vector<Shape>& shapes,
                                        const std::vector<std::uint8_t>& fans, Buckets& cand) {
  const auto& T = mesh.triangles;
  std::vector<std::uint32_t> hits(T.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, T.size()), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const auto b = cand.second.begin() + std::ptrdiff_t(cand.start[i]);
      const auto e = cand.second.begin() + std::ptrdiff_t(cand.start[i + 1]);
      std::sort(b, e);
      auto out = b;
      const Tri ti = tri_of(mesh, static_cast<std::uint32_t>(i), shapes[i]);
      for (auto it = b, last = std::unique(b, e); it != last; ++it)
        if (!share_embedded_fan(T[i], T[*it], fans) && pair_intersects(ti, T[i], tri_of(mesh, *it, shapes[*it]), T[*it])) *out++ = *it;
      hits[i] = static_cast<std::uint32_t>(out - b);
    }
  });
  return hits;
}

}  // namespace

bool triangles_intersect(const TriangleMesh& mesh, std::uint32_t a, std::uint32_t b) {
  if (a == b) return false;
  return pair_intersects(make_tri(mesh, a), mesh.triangles[a], make_tri(mesh, b), mesh.triangles[b]);
}

SelfIntersections find_self_intersections(const TriangleMesh& mesh, std::size_t max_examples) {
  SelfIntersections r;
  const auto& T = mesh.triangles;
  if (T.size() < 2) return r;
  std::vector<Shape> shapes(T.size());
  tbb::parallel_for(std::size_t(0), T.size(), [&](std::size_t t) {
    const Tri tri = make_tri(mesh, static_cast<std::uint32_t>(t));
    shapes[t] = {static_cast<std::int8_t>(tri.axis), static_cast<std::int8_t>(tri.sign), static_cast<std::int8_t>(tri.flat)};
  });
  // Pairs around a certified fan need no test: 99% of a well-shaped closed mesh's candidates.
  const std::vector<std::uint8_t> fans = embedded_fans(mesh);
  if (const auto found = grid_hits(mesh, shapes, fans)) {
    r.pairs = found->size();
    for (std::size_t k = 0; k < found->size() && k < max_examples; ++k)
      r.examples.push_back({static_cast<std::uint32_t>((*found)[k] >> 32), static_cast<std::uint32_t>((*found)[k])});
    return r;
  }
  Buckets cand = hierarchy_pairs(mesh, shapes);
  const std::vector<std::uint32_t> hits = test_buckets(mesh, shapes, fans, cand);
  for (std::size_t i = 0; i < T.size(); ++i) {
    r.pairs += hits[i];
    for (std::uint32_t k = 0; k < hits[i] && r.examples.size() < max_examples; ++k)
      r.examples.push_back({static_cast<std::uint32_t>(i), cand.second[cand.start[i] + k]});
  }
  return r;
}

}  // namespace ht
