#include "runtime/tape_eval.hpp"

#include "nodes/mesh_leaf.hpp"
#include "runtime/morton.hpp"
#include "runtime/tape_curve.hpp"
#include "runtime/tape_ops.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <cmath>
#include <limits>
#include <type_traits>
#include <vector>

namespace ht {

using tape_ops::Dual;
using tape_ops::V3;

namespace {

// One workspace per thread, shared by every evaluator: a block's evaluation runs start to end
// on its thread without yielding to another task (no instruction spawns work or evaluates
// another tape), so nothing else touches the thread's workspace meanwhile, and making an
// evaluator allocates nothing.
struct Workspace {
  std::vector<float> rows;  // the register file: [register][lane]
  std::vector<Dual> dual_rows;
  std::vector<float> mesh_distance = std::vector<float>(kBlock);
  std::vector<std::uint8_t> mesh_inside = std::vector<std::uint8_t>(kBlock);
};

Workspace& thread_workspace() {
  thread_local Workspace ws;
  return ws;
}

#define HT_LANE [[gnu::always_inline]] inline

template <class T>
struct Block {
  T* rows;                      // register r: rows + r * kBlock; frame f, axis j: register f + j
  float* mesh_distance;         // scratch for the mesh instruction
  std::uint8_t* mesh_inside;
  int count;                    // the lanes that hold query points; loops run whole chunks past them
  T* reg(int r) const { return rows + static_cast<std::ptrdiff_t>(r) * kBlock; }
  T* axis(int frame, int j) const { return reg(frame + j); }
};

using namespace tape_ops;
using tape_curve::in_box;
using tape_curve::kChunk;

// One primitive instruction over the block: distance squared, then the falloff.
template <class T, class Dist>
HT_LANE void primitive_loop(const Block<T>& b, const Instruction& ins, const float* k, int n, Dist dist) {
  const T* x = b.axis(ins.a, 0);
  const T* y = b.axis(ins.a, 1);
  const T* z = b.axis(ins.a, 2);
  T* out = b.reg(ins.out);
  for (int i = 0; i < n; ++i) out[i] = falloff2(dist(V3<T>{x[i], y[i], z[i]}), k);  // vectorized in every build
}

// The mesh leaf's pseudo-distance field from dM and the inside flag (SCENE_FORMAT.md).
HT_LANE float pseudo_distance(float dm, bool inside, float r0) {
  if (std::isinf(dm)) return inside ? 0.0f : std::numeric_limits<float>::infinity();
  return inside ? std::max(r0 - dm, 0.0f) : dm + r0;
}
HT_LANE float mesh_value(float d, float F, float kernel) {
  if (!(d < kernel)) return 0.0f;
  const float u = 1.0f - (d * d) / (kernel * kernel);
  return F * u * u * u;
}

void mesh_loop(const Tape& tape, const Block<float>& b, const Instruction& ins, const float* k, int n) {
  const MeshLeaf& leaf = *tape.meshes[static_cast<std::size_t>(k[4])];
  const float F = k[0], kernel = k[1], r0 = k[2], radius = k[3];
  // Only the lanes with query points: a mesh query is too dear for padding.
  const int m = std::min(n, b.count);
  leaf.query_batch(b.axis(ins.a, 0), b.axis(ins.a, 1), b.axis(ins.a, 2), static_cast<std::size_t>(m), radius,
                   b.mesh_distance, b.mesh_inside);
  float* out = b.reg(ins.out);
  for (int i = 0; i < m; ++i)
    out[i] = mesh_value(pseudo_distance(b.mesh_distance[i], b.mesh_inside[i] != 0, r0), F, kernel);
  for (int i = m; i < n; ++i) out[i] = 0.0f;
}

// With gradients: the pseudo-distance's gradient from pseudo_distance_gradient() (the unit
// vector from the nearest point, or on the mesh the outward pseudo-normal: the one-sided limit
// from outside), in double as the reference evaluator computes it, then the falloff's slope.
void mesh_loop(const Tape& tape, const Block<Dual>& b, const Instruction& ins, const float* k, int n) {
  const MeshLeaf& leaf = *tape.meshes[static_cast<std::size_t>(k[4])];
  const float F = k[0], kernel = k[1], r0 = k[2], radius = k[3];
  const Dual* x = b.axis(ins.a, 0);
  const Dual* y = b.axis(ins.a, 1);
  const Dual* z = b.axis(ins.a, 2);
  Dual* out = b.reg(ins.out);
  MeshLeaf::Neighbours run(leaf, static_cast<double>(radius));  // a block's points are neighbours
  for (int i = 0; i < n; ++i) {
    const glm::dvec3 p(x[i].v, y[i].v, z[i].v);
    const MeshLeaf::Closest c = run.next(p);
    const float dm = std::isfinite(c.distance) ? static_cast<float>(c.distance) : std::numeric_limits<float>::infinity();
    const float d = pseudo_distance(dm, c.inside, r0);
    if (!(d < kernel) || d == 0.0f || !std::isfinite(dm)) {
      out[i] = Dual(mesh_value(d, F, kernel));
      continue;
    }
    const glm::dvec3 g = pseudo_distance_gradient(c, p, leaf.surface_band());
    const Dual dd = x[i] * static_cast<float>(g.x) + y[i] * static_cast<float>(g.y) + z[i] * static_cast<float>(g.z);
    const float u = 1.0f - (d * d) / (kernel * kernel);
    const float slope = -6.0f * F * d / (kernel * kernel) * u * u;
    out[i] = chain(dd, F * u * u * u, slope);
  }
}

// Frames: the inverse warps. Coordinates of the turning plane are picked per instruction.
template <class T>
HT_LANE T sinc_(const T& t) {
  return std::abs(val(t)) < 1e-3f ? T(1.0f) - t * t * (1.0f / 6.0f) : sin_(t) / t;
}
template <class T>
HT_LANE T cosc_(const T& t) {
  return std::abs(val(t)) < 1e-3f ? t * 0.5f - t * t * t * (1.0f / 24.0f) : (T(1.0f) - cos_(t)) / t;
}

template <class T>
HT_LANE void warp_loop(const Block<T>& b, const Instruction& ins, const float* k, int n) {
  if (ins.op == OpCode::Affine) {
    const T* x = b.axis(ins.a, 0);
    const T* y = b.axis(ins.a, 1);
    const T* z = b.axis(ins.a, 2);
    T* ox = b.axis(ins.out, 0);
    T* oy = b.axis(ins.out, 1);
    T* oz = b.axis(ins.out, 2);
    for (int i = 0; i < n; ++i) {
      const T px = x[i], py = y[i], pz = z[i];
      ox[i] = px * k[0] + py * k[1] + pz * k[2] + k[3];
      oy[i] = px * k[4] + py * k[5] + pz * k[6] + k[7];
      oz[i] = px * k[8] + py * k[9] + pz * k[10] + k[11];
    }
    return;
  }
  const int axis = static_cast<int>(k[0]), iv = (axis + 1) % 3, iw = (axis + 2) % 3;
  const float ch = k[1 + axis], cv = k[1 + iv], cw = k[1 + iw];
  const T* h = b.axis(ins.a, axis);
  const T* v = b.axis(ins.a, iv);
  const T* w = b.axis(ins.a, iw);
  T* oh = b.axis(ins.out, axis);
  T* ov = b.axis(ins.out, iv);
  T* ow = b.axis(ins.out, iw);
  if (ins.op == OpCode::Twist) {
    const float rate = k[4];
    for (int i = 0; i < n; ++i) {
      const T a = (h[i] - ch) * (-rate);
      const T c = cos_(a), s = sin_(a);
      const T pv = v[i] - cv, pw = w[i] - cw;
      oh[i] = h[i];
      ov[i] = c * pv - s * pw + cv;
      ow[i] = s * pv + c * pw + cw;
    }
  } else if (ins.op == OpCode::Taper) {
    const float h0 = k[4], h1 = k[5], s0 = k[6], s1 = k[7], inv_range = 1.0f / (h1 - h0);
    for (int i = 0; i < n; ++i) {
      const T t = clamp_((h[i] - ch - h0) * inv_range, 0.0f, 1.0f);
      const T inv = T(1.0f) / (t * (s1 - s0) + s0);
      oh[i] = h[i];
      ov[i] = (v[i] - cv) * inv + cv;
      ow[i] = (w[i] - cw) * inv + cw;
    }
  } else {  // Bend: the slice comes from the point's angle about the centre of curvature
    const float h0 = k[4], h1 = k[5], rate = k[6];
    for (int i = 0; i < n; ++i) {
      const T u = h[i] - ch, vv = v[i] - cv;
      const T hc = rate != 0.0f ? clamp_(atan2_(u * rate, T(1.0f) - vv * rate) * (1.0f / rate), h0, h1)
                                : clamp_(u, h0, h1);
      const T theta = hc * rate;
      const T c = cos_(theta), s = sin_(theta);
      const T du = u - hc * sinc_(theta), dv = vv - hc * cosc_(theta);
      oh[i] = hc + c * du + s * dv + ch;
      ov[i] = c * dv - s * du + cv;
      ow[i] = w[i];
    }
  }
}

HT_LANE float lane_value(float x) { return x; }
HT_LANE float lane_value(const Dual& x) { return x.v; }

// Whether any query point of the block (not the padding lanes) lies in the box lo(3) hi(3).
template <class T>
HT_LANE bool any_in_box(const Block<T>& b, int frame, const float* box) {
  const T* x = b.axis(frame, 0);
  const T* y = b.axis(frame, 1);
  const T* z = b.axis(frame, 2);
  int hit = 0;
  for (int i = 0; i < b.count; ++i) hit |= in_box(lane_value(x[i]), lane_value(y[i]), lane_value(z[i]), box) ? 1 : 0;
  return hit != 0;
}

template <class T>
HT_LANE void run(const Tape& tape, const Block<T>& b, int n) {
  const float t = tape.threshold;
  const float* pool = tape.constants.data();
  const std::size_t size = tape.code.size();
  for (std::size_t pc = 0; pc < size; ++pc) {
    const Instruction& ins = tape.code[pc];
    const float* k = pool + ins.k();
    T* out = b.reg(ins.out);
    const T* ra = b.reg(ins.a);
    const T* rb = b.reg(ins.b);
    switch (ins.op) {
      case OpCode::Point: primitive_loop(b, ins, k, n, [&](const V3<T>& q) { return point2(q, k + 4); }); break;
      case OpCode::Segment: primitive_loop(b, ins, k, n, [&](const V3<T>& q) { return segment2(q, k + 4); }); break;
      case OpCode::Circle: primitive_loop(b, ins, k, n, [&](const V3<T>& q) { return circle2(q, k + 4, false); }); break;
      case OpCode::Disc: primitive_loop(b, ins, k, n, [&](const V3<T>& q) { return circle2(q, k + 4, true); }); break;
      case OpCode::Triangle: primitive_loop(b, ins, k, n, [&](const V3<T>& q) { return triangle2(q, k + 4); }); break;
      case OpCode::Curve:
        tape_curve::curve_loop(b.axis(ins.a, 0), b.axis(ins.a, 1), b.axis(ins.a, 2), b.reg(ins.out), n, b.count, k);
        break;
      case OpCode::Box: primitive_loop(b, ins, k, n, [&](const V3<T>& q) { return box2(q, k + 4); }); break;
      case OpCode::Cylinder: primitive_loop(b, ins, k, n, [&](const V3<T>& q) { return cylinder2(q, k + 4); }); break;
      case OpCode::ConeSphere: primitive_loop(b, ins, k, n, [&](const V3<T>& q) { return cone_sphere2(q, k + 4); }); break;
      case OpCode::Mesh: mesh_loop(tape, b, ins, k, n); break;
      case OpCode::Zero:
        for (int i = 0; i < n; ++i) out[i] = T(0.0f);
        break;
      case OpCode::Constant: {
        const float v = ins.immediate();
        for (int i = 0; i < n; ++i) out[i] = T(v);
        break;
      }
      case OpCode::Add:
        for (int i = 0; i < n; ++i) out[i] = ra[i] + rb[i];
        break;
      case OpCode::Max:
        for (int i = 0; i < n; ++i) out[i] = max_(ra[i], rb[i]);
        break;
      case OpCode::Min:
        for (int i = 0; i < n; ++i) out[i] = min_(ra[i], rb[i]);
        break;
      case OpCode::RUnion:
        for (int i = 0; i < n; ++i) out[i] = r_union(ra[i], rb[i], t);
        break;
      case OpCode::RIntersection:
        for (int i = 0; i < n; ++i) out[i] = r_intersection(ra[i], rb[i], t);
        break;
      case OpCode::DiffMinMax:
        for (int i = 0; i < n; ++i) out[i] = max_(T(0.0f), min_(ra[i], T(2.0f * t) - rb[i]));
        break;
      case OpCode::DiffRFunction:
        for (int i = 0; i < n; ++i) out[i] = max_(T(0.0f), r_intersection(ra[i], T(2.0f * t) - rb[i], t));
        break;
      case OpCode::LocalBlendMinMax:
      case OpCode::LocalBlendRFunction: {  // in place: out blended with a, weight b
        const bool rf = ins.op == OpCode::LocalBlendRFunction;
        for (int i = 0; i < n; ++i) out[i] = local_blend(out[i], ra[i], rb[i], t, rf);
        break;
      }
      case OpCode::Crop: {  // in place
        const T* x = b.axis(ins.a, 0);
        const T* y = b.axis(ins.a, 1);
        const T* z = b.axis(ins.a, 2);
        for (int i = 0; i < n; ++i) out[i] = crop(out[i], V3<T>{x[i], y[i], z[i]}, k);
        break;
      }
      case OpCode::Affine:
      case OpCode::Twist:
      case OpCode::Taper:
      case OpCode::Bend: warp_loop(b, ins, k, n); break;
      case OpCode::Skip:
        if (!any_in_box(b, ins.a, k)) {
          for (int i = 0; i < n; ++i) out[i] = T(0.0f);
          pc += static_cast<std::size_t>(k[6]);
        }
        break;
    }
  }
}

// The float path is built once per instruction set and picked at run time. The lane code is
// written so that GCC vectorizes it on each (select, not branch, in runtime/tape_ops.hpp, and
// -fno-trapping-math so that both arms may be computed); tests/test_vectorization.cpp checks
// that the loops so marked are vectorized by each build.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define HT_X86_BUILDS 1
[[gnu::target("avx512f,avx512vl,avx512dq,avx512bw,avx2,fma,bmi2")]]
void run_values_avx512(const Tape& tape, const Block<float>& b, int n) { run(tape, b, n); }
[[gnu::target("avx2,fma,bmi2")]] void run_values_avx2(const Tape& tape, const Block<float>& b, int n) { run(tape, b, n); }
[[gnu::target("sse4.2,popcnt")]] void run_values_sse4(const Tape& tape, const Block<float>& b, int n) { run(tape, b, n); }
#endif
void run_values_baseline(const Tape& tape, const Block<float>& b, int n) { run(tape, b, n); }

// Gradients the same way: the dual numbers' four lanes are one vector each.
#ifdef HT_X86_BUILDS
[[gnu::target("avx512f,avx512vl,avx512dq,avx512bw,avx2,fma,bmi2")]]
void run_gradients_avx512(const Tape& tape, const Block<Dual>& b, int n) { run(tape, b, n); }
[[gnu::target("avx2,fma,bmi2")]] void run_gradients_avx2(const Tape& tape, const Block<Dual>& b, int n) { run(tape, b, n); }
[[gnu::target("sse4.2,popcnt")]] void run_gradients_sse4(const Tape& tape, const Block<Dual>& b, int n) { run(tape, b, n); }
#endif
void run_gradients_baseline(const Tape& tape, const Block<Dual>& b, int n) { run(tape, b, n); }

template <class T>
using Run = void (*)(const Tape&, const Block<T>&, int);

template <class T>
Run<T> builds(TapeIsa isa) {
  constexpr bool values = std::is_same_v<T, float>;
#ifdef HT_X86_BUILDS
  switch (isa) {
    case TapeIsa::Avx512: if constexpr (values) return run_values_avx512; else return run_gradients_avx512;
    case TapeIsa::Avx2: if constexpr (values) return run_values_avx2; else return run_gradients_avx2;
    case TapeIsa::Sse4: if constexpr (values) return run_values_sse4; else return run_gradients_sse4;
    case TapeIsa::Baseline: break;
  }
#else
  (void)isa;
#endif
  if constexpr (values) return run_values_baseline; else return run_gradients_baseline;
}

template <class T>
void run_build(const Tape& tape, const Block<T>& b, int n) {
  builds<T>(tape_isa())(tape, b, n);
}
void run_values(const Tape& tape, const Block<float>& b, int n) { run_build(tape, b, n); }
void run_gradients(const Tape& tape, const Block<Dual>& b, int n) { run_build(tape, b, n); }

#undef HT_LANE

// Parallel over blocks above a small size; below it, on the calling thread (TBB's overhead
// would dominate).
template <class Body>
void for_blocks(std::size_t n, Body&& body) {
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  if (blocks <= 2) {
    for (std::size_t i = 0; i < blocks; ++i) body(i);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks, 1), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) body(i);
  });
}

// A batch in no order puts points from everywhere into every block, and a Skip skips only
// when a whole block misses its box. Tapes with Skips therefore run big batches in Morton
// order; each point's value does not depend on the block it lands in, so the results are the
// same either way. Empty: the batch runs in its own order.
constexpr std::size_t kOrderMinPoints = 8 * kBlock;

template <class Coord>
std::vector<std::uint32_t> batch_order(const Tape& tape, std::size_t n, Coord coord) {
  if (tape.skips == 0 || n < kOrderMinPoints || n > std::numeric_limits<std::uint32_t>::max()) return {};
  return morton::order(n, coord);
}

}  // namespace

TapeEvaluator::TapeEvaluator(std::shared_ptr<const Tape> tape) : tape_(std::move(tape)) {}
TapeEvaluator::~TapeEvaluator() = default;

void TapeEvaluator::field_block(const float* x, const float* y, const float* z, int n, float* values) const {
  Workspace& ws = thread_workspace();
  const std::size_t rows = std::size_t(tape_->registers) * kBlock;
  if (ws.rows.size() < rows) ws.rows.resize(rows);
  const Block<float> b{ws.rows.data(), ws.mesh_distance.data(), ws.mesh_inside.data(), n};
  std::copy(x, x + n, b.axis(0, 0));
  std::copy(y, y + n, b.axis(0, 1));
  std::copy(z, z + n, b.axis(0, 2));
  // Every instruction runs whole chunks (no scalar remainder on any build): the lanes past n
  // hold a harmless point, and their values are never read.
  const int padded = std::min(kBlock, (n + kChunk - 1) / kChunk * kChunk);
  for (int j = 0; j < 3; ++j) std::fill(b.axis(0, j) + n, b.axis(0, j) + padded, 0.0f);
  run_values(*tape_, b, padded);
  const float* r = b.reg(tape_->result);
  std::copy(r, r + n, values);
}

void TapeEvaluator::field(const float* x, const float* y, const float* z, std::size_t n, float* values) const {
  const auto order = batch_order(*tape_, n, [&](std::size_t i) { return glm::vec3(x[i], y[i], z[i]); });
  if (order.empty()) {
    for_blocks(n, [&](std::size_t block) {
      const std::size_t at = block * kBlock;
      const int count = static_cast<int>(std::min<std::size_t>(kBlock, n - at));
      field_block(x + at, y + at, z + at, count, values + at);
    });
    return;
  }
  for_blocks(n, [&](std::size_t block) {
    const std::size_t at = block * kBlock;
    const int count = static_cast<int>(std::min<std::size_t>(kBlock, n - at));
    float bx[kBlock] = {}, by[kBlock] = {}, bz[kBlock] = {}, v[kBlock];
    for (int i = 0; i < count; ++i) {
      const std::uint32_t j = order[at + std::size_t(i)];
      bx[i] = x[j];
      by[i] = y[j];
      bz[i] = z[j];
    }
    field_block(bx, by, bz, count, v);
    for (int i = 0; i < count; ++i) values[order[at + std::size_t(i)]] = v[i];
  });
}

void TapeEvaluator::field(std::span<const glm::dvec3> points, std::span<double> values) const {
  if (values.size() != points.size()) throw std::invalid_argument("TapeEvaluator::field: values.size() != points.size()");
  const auto order = batch_order(*tape_, points.size(), [&](std::size_t i) { return glm::vec3(points[i]); });
  auto index = [&](std::size_t i) { return order.empty() ? i : std::size_t(order[i]); };
  for_blocks(points.size(), [&](std::size_t block) {
    const std::size_t at = block * kBlock;
    const int count = static_cast<int>(std::min<std::size_t>(kBlock, points.size() - at));
    float x[kBlock] = {}, y[kBlock] = {}, z[kBlock] = {}, v[kBlock];
    for (int i = 0; i < count; ++i) {
      const glm::dvec3& p = points[index(at + std::size_t(i))];
      x[i] = static_cast<float>(p.x);
      y[i] = static_cast<float>(p.y);
      z[i] = static_cast<float>(p.z);
    }
    field_block(x, y, z, count, v);
    for (int i = 0; i < count; ++i) values[index(at + std::size_t(i))] = v[i];
  });
}

float TapeEvaluator::field(const glm::dvec3& p) const {
  const float x = static_cast<float>(p.x), y = static_cast<float>(p.y), z = static_cast<float>(p.z);
  float v;
  field_block(&x, &y, &z, 1, &v);
  return v;
}

void TapeEvaluator::gradient(std::span<const glm::dvec3> points, std::span<double> values,
                             std::span<glm::dvec3> gradients) const {
  if (gradients.size() != points.size() || (!values.empty() && values.size() != points.size()))
    throw std::invalid_argument("TapeEvaluator::gradient: output sizes differ from points.size()");
  const auto order = batch_order(*tape_, points.size(), [&](std::size_t i) { return glm::vec3(points[i]); });
  auto index = [&](std::size_t i) { return order.empty() ? i : std::size_t(order[i]); };
  for_blocks(points.size(), [&](std::size_t block) {
    Workspace& ws = thread_workspace();
    const std::size_t rows = std::size_t(tape_->registers) * kBlock;
    if (ws.dual_rows.size() < rows) ws.dual_rows.resize(rows);
    const std::size_t at = block * kBlock;
    const int count = static_cast<int>(std::min<std::size_t>(kBlock, points.size() - at));
    const Block<Dual> b{ws.dual_rows.data(), ws.mesh_distance.data(), ws.mesh_inside.data(), count};
    const int padded = std::min(kBlock, (count + kChunk - 1) / kChunk * kChunk);
    for (int j = 0; j < 3; ++j) std::fill(b.axis(0, j) + count, b.axis(0, j) + padded, Dual(0.0f));
    for (int i = 0; i < count; ++i) {
      const glm::dvec3& p = points[index(at + std::size_t(i))];
      b.axis(0, 0)[i] = Dual(static_cast<float>(p.x), 1, 0, 0);
      b.axis(0, 1)[i] = Dual(static_cast<float>(p.y), 0, 1, 0);
      b.axis(0, 2)[i] = Dual(static_cast<float>(p.z), 0, 0, 1);
    }
    run_gradients(*tape_, b, count);
    const Dual* r = b.reg(tape_->result);
    for (int i = 0; i < count; ++i) {
      const std::size_t j = index(at + std::size_t(i));
      if (!values.empty()) values[j] = r[i].v;
      gradients[j] = glm::dvec3(r[i].dx, r[i].dy, r[i].dz);
    }
  });
}

}  // namespace ht
