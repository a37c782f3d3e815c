// The tape compiler: a post-order walk that emits one instruction per surviving node, frees each
// value's register when its consumer is emitted, and (with a region) drops what interval analysis
// proves irrelevant inside the region. See runtime/tape.hpp.
#include "nodes/mesh_leaf.hpp"
#include "nodes/operators.hpp"
#include "nodes/primitives.hpp"
#include "nodes/warps.hpp"
#include "runtime/interval.hpp"
#include "runtime/node_params.hpp"
#include "runtime/tape.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace ht {

namespace {

constexpr int kNoValue = -1;  // the node is 0 everywhere that matters: no code, no register
constexpr int kMaxDepth = kMaxTreeDepth;

class Compiler {
 public:
  Compiler(const Graph& g, double T, Tape& tape, bool guards) : g_(g), T_(T), tape_(tape), guards_(guards) {
    for (auto& v : zero_known_) v.assign(guards ? g.size() : 0, -1);
  }

  // Emits code for node n reading frame `frame`; returns its scalar register or kNoValue.
  // `region` is the box of interest in this frame's coordinates, or null for everywhere.
  int node(NodeId n, int frame, bool under_blend, const Aabb* region, int depth) {
    if (depth > kMaxDepth) throw CompileError("the tree is deeper than " + std::to_string(kMaxDepth) + " nodes");
    const Aabb& box = g_.support(n, under_blend);
    const double size = volume(box), parent = parent_volume_;
    if (!guards_ || !guard_worthy(n, under_blend, box, size, region)) {
      parent_volume_ = std::isfinite(size) ? size : parent;
      const int r = unguarded(n, frame, under_blend, region, depth);
      parent_volume_ = parent;
      return r;
    }
    // A placeholder Skip, patched once the subtree's code is known, or taken out again when
    // that code is too short to pay for the box test.
    const std::size_t mark = tape_.code.size();
    const Aabb padded = box.expanded(kGuardPad * (1.0 + std::max(glm::length(box.lo), glm::length(box.hi))));
    const std::uint32_t k = constants({padded.lo.x, padded.lo.y, padded.lo.z, padded.hi.x, padded.hi.y, padded.hi.z, 0.0});
    emit_k(OpCode::Skip, n, 0, frame, k);
    parent_volume_ = size;
    const int r = unguarded(n, frame, under_blend, region, depth);
    parent_volume_ = parent;
    const std::size_t length = tape_.code.size() - mark - 1;
    if (r == kNoValue || length < kGuardMinLength || tape_.code.back().out != r) {
      tape_.code.erase(tape_.code.begin() + std::ptrdiff_t(mark));
      tape_.source.erase(tape_.source.begin() + std::ptrdiff_t(mark));
      return r;
    }
    tape_.code[mark].out = static_cast<std::uint16_t>(r);
    tape_.constants[k + 6] = static_cast<float>(length);
    ++tape_.skips;
    return r;
  }

  // Is a guard worth trying around n? Operators and warps only (a leaf costs what the test
  // does), with a bounded support well inside the parent's, and not where the region of
  // interest lies inside the support anyway (the guard would never skip there).
  bool guard_worthy(NodeId n, bool under_blend, const Aabb& box, double size, const Aabb* region) const {
    const Family f = kind_family(g_.kind[n]);
    if (f != Family::Operator && f != Family::Warp) return false;
    // Not the root (no parent volume): the points asked of a tree are mostly near it.
    if (g_.kind[n] == NodeKind::Ffd || !box.finite() || !std::isfinite(parent_volume_) ||
        !(size < kGuardFraction * parent_volume_))
      return false;
    if (region && region->finite() && box.contains(region->lo) && box.contains(region->hi)) return false;
    return zero_in_float(n, under_blend);
  }

  // Whether the tape computes exactly 0 for n outside its support, so that a skipped guard gives
  // the same bits as the code it skips. R-functions do not: their shifted formulas leave float
  // residues of about 1e-13 where the exact field is 0.
  bool zero_in_float(NodeId n, bool under_blend) const {
    std::int8_t& known = zero_known_[under_blend ? 1 : 0][n];
    if (known >= 0) return known != 0;
    const NodeKind k = g_.kind[n];
    const auto c = g_.children_of(n);
    const bool below = under_blend || k == NodeKind::Blend || k == NodeKind::LocalBlend;
    bool zero = true;
    switch (kind_family(k)) {
      case Family::Primitive:
      case Family::Mesh: break;
      case Family::Warp: zero = k != NodeKind::Ffd && zero_in_float(c[0], below); break;
      case Family::Operator:
        if (k != NodeKind::Blend && k != NodeKind::Crop && use_rfunction(g_.boolean[n], under_blend)) {
          zero = false;
        } else if (k == NodeKind::Difference) {
          zero = zero_in_float(c[0], below);  // max(0, min(0, x)) = 0 whatever B is
        } else {
          for (NodeId child : c) zero = zero && zero_in_float(child, below);
        }
        break;
    }
    known = zero ? 1 : 0;
    return zero;
  }

  int unguarded(NodeId n, int frame, bool under_blend, const Aabb* region, int depth) {
    if (region) {
      const Interval iv = field_interval(g_, n, T_, *region, under_blend);
      if (iv.zero()) return kNoValue;
      if (iv.lo == iv.hi) {  // constant over the region (deep inside a mesh, say): no subtree
        const int out = alloc_scalar();
        Instruction ins;
        ins.op = OpCode::Constant;
        ins.out = static_cast<std::uint16_t>(out);
        ins.set_immediate(static_cast<float>(iv.lo));
        push(ins, kNone);
        return out;
      }
    }
    const NodeKind k = g_.kind[n];
    switch (kind_family(k)) {
      case Family::Primitive: return primitive(n, frame);
      case Family::Mesh: return mesh(n, frame);
      case Family::Warp:
        if (k == NodeKind::Ffd && g_.mesh[n] != kNone) return mesh(n, frame);  // its deformed mesh
        if (params::ffd_empty(g_, n)) return kNoValue;                          // 0 everywhere
        return warp(n, frame, under_blend, region, depth);
      case Family::Operator: break;
    }
    switch (k) {
      case NodeKind::Blend: return blend(n, frame, region, depth);
      case NodeKind::Union:
      case NodeKind::Intersection: return min_max(n, frame, under_blend, region, depth);
      case NodeKind::Difference: return difference(n, frame, under_blend, region, depth);
      case NodeKind::LocalBlend: return local_blend(n, frame, under_blend, region, depth);
      default: return crop(n, frame, under_blend, region, depth);
    }
  }

  std::uint16_t register_count() const { return high_; }

  int materialize(int reg) {
    if (reg != kNoValue) return reg;
    const int out = alloc_scalar();
    emit(OpCode::Zero, out);
    return out;
  }

 private:
  // -- registers --------------------------------------------------------------------------
  // One file: values take a row, frames three consecutive rows; each kind reuses its own freed
  // slots, and both grow the same file.
  int grow(int rows) {
    if (high_ + rows > std::numeric_limits<std::uint16_t>::max()) throw CompileError("too many registers");
    const int r = high_;
    high_ = static_cast<std::uint16_t>(high_ + rows);
    return r;
  }
  int alloc_scalar() {
    if (free_scalars_.empty()) return grow(1);
    const int r = free_scalars_.back();
    free_scalars_.pop_back();
    return r;
  }
  void release_scalar(int r) {
    if (r != kNoValue) free_scalars_.push_back(r);
  }
  int alloc_frame() {
    if (free_frames_.empty()) return grow(3);
    const int f = free_frames_.back();
    free_frames_.pop_back();
    return f;
  }
  void release_frame(int f) { free_frames_.push_back(f); }

  std::uint32_t constants(std::initializer_list<double> values) {
    const auto at = static_cast<std::uint32_t>(tape_.constants.size());
    if (at + values.size() > Instruction::kMaxConstant)
      throw CompileError("the tape's constants exceed " + std::to_string(Instruction::kMaxConstant) + " floats");
    for (double v : values) tape_.constants.push_back(static_cast<float>(v));
    return at;
  }
  // 1/x for a squared length x, or 0 when x is 0 or negligible against `scale2` (a square of the
  // same kind: floats cannot tell it from 0 there): the evaluators read 0 as a degenerate segment
  // or edge (its first point) or triangle (its edges). Measured against the node's own scale, not
  // the float range, so that a triangle 1e-10 wide is no set of edges (a review found the tape
  // then disagreeing with the tree); past the float range on its own it is refused (check_float).
  static double float_inverse(double x, double scale2) {
    return x > 0 && x > 1e-14 * scale2 ? 1.0 / x : 0.0;
  }
  // The constants of node n's field: each must hold as a float, the tape's arithmetic (a twist
  // rate of 4e38 became infinite there, and the tape said 0 where the tree said 1).
  std::uint32_t constants(NodeId n, std::initializer_list<double> values) {
    for (double v : values) check_float(n, v);
    return constants(values);
  }
  // An affine map's inverse (row-major 3x4) whose linear part underflows as floats: a scale of
  // 1e150 made every entry 0 in the tape, so the whole space mapped onto one point of the child.
  void check_inverse_scale(NodeId n, std::span<const double> inverse) const {
    double big = 0.0;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) big = std::max(big, std::abs(inverse[std::size_t(4 * r + c)]));
    if (big >= static_cast<double>(std::numeric_limits<float>::min())) return;
    char buf[96];
    std::snprintf(buf, sizeof buf, "%.3g", big);
    throw FloatRangeError("node " + g_.label(n) + ": its inverse map's largest entry, " + buf +
                          ", is below the float range (1.2e-38) the field tape evaluates in (a scale of extreme size?)");
  }
  void check_float(NodeId n, double v) const {
    if (!std::isfinite(v) || std::isfinite(static_cast<float>(v))) return;
    char buf[96];
    std::snprintf(buf, sizeof buf, "%.3g", v);
    throw FloatRangeError("node " + g_.label(n) + ": its field needs the number " + buf +
                       ", beyond the float range (3.4e38) the field tape evaluates in (a parameter of extreme size?)");
  }
  // An instruction with register operands.
  void emit(OpCode op, int out, int a = 0, int b = 0) { push(Instruction::make(op, out, a, b), kNone); }
  void push(const Instruction& ins, NodeId from) {
    tape_.code.push_back(ins);
    tape_.source.push_back(from);
  }
  // An instruction of node `from` reading frame `frame` and the constants at k.
  void emit_k(OpCode op, NodeId from, int out, int frame, std::uint32_t k) {
    Instruction ins = Instruction::make(op, out, frame);
    ins.set_k(k);
    push(ins, from);
  }

  // -- leaves -----------------------------------------------------------------------------
  int primitive(NodeId n, int frame) {
    const params::Primitive prim = params::primitive(g_, n);
    const double R = prim.R, F = prim.F;
    const double* s = g_.skeleton_of(n);
    // Common header: R^2, 1/R^2, F, R; the skeleton follows (layouts in runtime/tape_ops.hpp).
    const std::uint32_t k = constants(n, {R * R, 1.0 / (R * R), F, R});
    auto v = [&](int i) { return glm::dvec3(s[i], s[i + 1], s[i + 2]); };
    auto push3 = [&](const glm::dvec3& q) { constants(n, {q.x, q.y, q.z}); };
    OpCode op = OpCode::Point;
    switch (g_.kind[n]) {
      case NodeKind::Point: push3(v(0)); op = OpCode::Point; break;
      case NodeKind::Segment: {
        const glm::dvec3 a = v(0), ab = v(3) - v(0);
        push3(a);
        push3(ab);
        constants(n, {float_inverse(glm::dot(ab, ab), R * R)});
        op = OpCode::Segment;
        break;
      }
      case NodeKind::Circle:
      case NodeKind::Disc:
        push3(v(0));
        push3(v(3));
        constants(n, {s[6]});
        op = g_.kind[n] == NodeKind::Circle ? OpCode::Circle : OpCode::Disc;
        break;
      case NodeKind::Triangle: {
        const glm::dvec3 a = v(0), b = v(3), c = v(6);
        const glm::dvec3 ba = b - a, cb = c - b, ac = a - c;
        // A normal negligible against its edges (the rounding residue of a collinear triangle's
        // cross product: 1/|n|^2 was 1.8e47 and refused) is the degenerate triangle's: its edges.
        glm::dvec3 nor = glm::cross(ba, ac);
        if (float_inverse(glm::dot(nor, nor), glm::dot(ba, ba) * glm::dot(ac, ac)) == 0.0) nor = glm::dvec3(0.0);
        const auto inv = [&](double x) { return float_inverse(x, R * R); };
        push3(a);
        push3(b);
        push3(c);
        push3(ba);
        push3(cb);
        push3(ac);
        push3(glm::cross(ba, nor));
        push3(glm::cross(cb, nor));
        push3(glm::cross(ac, nor));
        push3(nor);
        const double n2 = glm::dot(nor, nor);
        constants(n, {inv(glm::dot(ba, ba)), inv(glm::dot(cb, cb)), inv(glm::dot(ac, ac)), n2 > 0 ? 1.0 / n2 : 0.0});
        op = OpCode::Triangle;
        break;
      }
      case NodeKind::Curve: {
        const auto count = static_cast<std::size_t>(s[0]);
        const std::size_t segments = count > 1 ? count - 1 : 1;
        auto end = [&](std::size_t i) { return count > 1 ? v(1 + 3 * static_cast<int>(i + 1)) : v(1); };
        // The support box first: lanes outside it skip the segments (runtime/tape_eval.cpp).
        const Aabb support = skeleton_bounds(NodeKind::Curve, s).expanded(R);
        push3(support.lo);
        push3(support.hi);
        constants(n, {static_cast<double>(segments)});
        // The box of each group of kCurveGroup segments: a chunk of points skips the groups
        // that lie farther than what it has already found.
        std::vector<Aabb> boxes;
        for (std::size_t g0 = 0; g0 < segments; g0 += kCurveGroup) {
          Aabb box;
          for (std::size_t i = g0; i < std::min(segments, g0 + kCurveGroup); ++i) {
            box.grow(v(1 + 3 * static_cast<int>(i)));
            box.grow(end(i));
          }
          push3(box.lo);
          push3(box.hi);
          boxes.push_back(box);
        }
        // Each group's ball: its box's centre, and the squared distance beyond which a point is
        // farther than R from every segment of the group. The slack (relative, and absolute for
        // coordinates far from the origin) keeps out only points whose float distance gives a
        // field of exactly 0: the lanes outside every ball are 0 without a segment's distance.
        for (std::size_t g = 0; g < boxes.size(); ++g) {
          const glm::dvec3 c = boxes[g].center();
          const double reach = (R + 0.5 * glm::length(boxes[g].size())) * (1.0 + 1e-4) +
                               1e-5 * (1.0 + std::max({std::abs(c.x), std::abs(c.y), std::abs(c.z)}));
          push3(c);
          constants(n, {reach * reach});
        }
        for (std::size_t i = 0; i < segments; ++i) {
          const glm::dvec3 a = v(1 + 3 * static_cast<int>(i)), ab = end(i) - a;
          push3(a);
          push3(ab);
          constants(n, {float_inverse(glm::dot(ab, ab), R * R)});
        }
        op = OpCode::Curve;
        break;
      }
      case NodeKind::Box:
        push3(0.5 * (v(0) + v(3)));
        push3(0.5 * (v(3) - v(0)));
        op = OpCode::Box;
        break;
      case NodeKind::Cylinder: {
        const glm::dvec3 a = v(0), axis = v(3) - v(0);
        const double len = glm::length(axis);
        push3(a);
        push3(axis / len);
        constants(n, {len, s[6]});
        op = OpCode::Cylinder;
        break;
      }
      default: {  // cone_sphere
        const glm::dvec3 a = v(0), b = v(3);
        const double ra = s[6], rb = s[7], len = glm::length(b - a);
        if (len <= std::abs(ra - rb)) {  // one sphere holds the other: flag 1, the big sphere
          const bool a_big = ra >= rb;
          push3(a_big ? a : b);
          constants(n, {0, 0, 0, 0, a_big ? ra : rb, 0, 0, 0, 1});
        } else {
          const double sn = (ra - rb) / len;
          push3(a);
          push3((b - a) / len);
          constants(n, {len, ra, rb, sn, std::sqrt(1 - sn * sn), 0});
        }
        op = OpCode::ConeSphere;
        break;
      }
    }
    const int out = alloc_scalar();
    emit_k(op, n, out, frame, k);
    return out;
  }

  int mesh(NodeId n, int frame) {
    const MeshFieldParams mp = params::mesh_field(g_, n, T_);
    const MeshLeaf* leaf = g_.meshes[g_.mesh[n]].get();
    auto it = std::find(tape_.meshes.begin(), tape_.meshes.end(), leaf);
    const auto index = static_cast<int>(it - tape_.meshes.begin());
    if (it == tape_.meshes.end()) tape_.meshes.push_back(leaf);
    // F, kernel radius R', r0, query radius, the mesh's index in the tape's table.
    const std::uint32_t k = constants(n, {mp.F, mp.kernel_radius, mp.r0, mp.query_radius, static_cast<double>(index)});
    const int out = alloc_scalar();
    emit_k(OpCode::Mesh, n, out, frame, k);
    return out;
  }

  // -- warps ------------------------------------------------------------------------------
  int warp(NodeId n, int frame, bool under_blend, const Aabb* region, int depth) {
    const NodeKind k = g_.kind[n];
    if (k == NodeKind::Ffd)
      throw CompileError("ffd node " + g_.label(n) +
                         ": its field is the distance to its deformed mesh, which needs meshing first (meshers/ffd.hpp)");
    const auto p = g_.params_of(n);
    std::uint32_t at = 0;
    OpCode op = OpCode::Affine;
    switch (k) {
      case NodeKind::Affine:
        at = static_cast<std::uint32_t>(tape_.constants.size());
        for (int i = 12; i < 24; ++i) check_float(n, p[i]);
        check_inverse_scale(n, p.subspan(12, 12));
        for (int i = 12; i < 24; ++i) tape_.constants.push_back(static_cast<float>(p[i]));
        op = OpCode::Affine;
        break;
      case NodeKind::Twist: at = constants(n, {p[0], p[1], p[2], p[3], p[4]}); op = OpCode::Twist; break;
      case NodeKind::Taper: at = constants(n, {p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]}); op = OpCode::Taper; break;
      default: at = constants(n, {p[0], p[1], p[2], p[3], p[4], p[5], p[6]}); op = OpCode::Bend; break;
    }
    const int inner = alloc_frame();
    const std::size_t mark = tape_.code.size();
    emit_k(op, n, inner, frame, at);
    Aabb local;
    const bool known = region && interval::warp_child_region(g_, n, *region, local);
    const int r = node(g_.children_of(n)[0], inner, under_blend, known ? &local : nullptr, depth + 1);
    release_frame(inner);
    if (r == kNoValue) {  // the child vanished: so does the warp
      tape_.code.resize(mark);
      tape_.source.resize(mark);
    }
    return r;
  }

  // -- operators --------------------------------------------------------------------------
  // A blend is a sum, and a blend's blend children are terms of the same sum: they are summed
  // in place (depth first, in order), so a chain of binary blends however deep holds two
  // registers, not one per level.
  int blend(NodeId n, int frame, const Aabb* region, int depth) {
    int acc = kNoValue;
    std::vector<std::pair<NodeId, int>> todo;  // (blend, next child) of the blends being summed
    todo.push_back({n, 0});
    while (!todo.empty()) {
      auto& [b, next] = todo.back();
      const auto children = g_.children_of(b);
      if (next == static_cast<int>(children.size())) {
        todo.pop_back();
        continue;
      }
      const NodeId c = children[static_cast<std::size_t>(next++)];
      const int level = depth + static_cast<int>(todo.size());
      if (level > kMaxDepth) throw CompileError("the tree is deeper than " + std::to_string(kMaxDepth) + " nodes");
      const auto flat = [&] {  // not where the region makes the child 0 or a constant: node() says so
        if (!region) return true;
        const Interval iv = field_interval(g_, c, T_, *region, true);
        return !iv.zero() && iv.lo != iv.hi;
      };
      const bool guarded = guards_ && guard_worthy(c, true, g_.support(c, true), volume(g_.support(c, true)), region);
      if (g_.kind[c] == NodeKind::Blend && !guarded && flat()) {
        todo.push_back({c, 0});
        continue;
      }
      const int r = node(c, frame, true, region, level);
      if (r == kNoValue) continue;  // a blend term that is 0 here
      if (acc == kNoValue) {
        acc = r;
        continue;
      }
      emit(OpCode::Add, acc, acc, r);
      release_scalar(r);
    }
    return acc;
  }

  // Union and intersection. With min/max and a region, children whose interval lies entirely
  // below (union) or above (intersection) another surviving child's cannot win anywhere in the
  // region: they are dropped. R-functions keep every child (zero ones become Zero).
  int min_max(NodeId n, int frame, bool under_blend, const Aabb* region, int depth) {
    const bool rf = use_rfunction(g_.boolean[n], under_blend);
    const bool is_union = g_.kind[n] == NodeKind::Union;
    const auto c = g_.children_of(n);
    std::vector<std::uint8_t> keep(c.size(), 1);
    if (region && !rf) {
      std::vector<Interval> iv(c.size());
      for (std::size_t i = 0; i < c.size(); ++i) iv[i] = field_interval(g_, c[i], T_, *region, under_blend);
      for (std::size_t i = 0; i < c.size(); ++i)
        for (std::size_t j = 0; j < c.size(); ++j) {
          if (i == j || !keep[j]) continue;
          const bool dominated = is_union ? iv[j].lo >= iv[i].hi : iv[j].hi <= iv[i].lo;
          if (dominated) {
            keep[i] = 0;
            break;
          }
        }
    }
    int acc = kNoValue;
    bool first = true;
    const OpCode op = rf ? (is_union ? OpCode::RUnion : OpCode::RIntersection) : (is_union ? OpCode::Max : OpCode::Min);
    for (std::size_t i = 0; i < c.size(); ++i) {
      if (!keep[i]) continue;
      int r = node(c[i], frame, under_blend, region, depth + 1);
      if (first) {
        acc = r;
        first = false;
        continue;
      }
      if (!rf && r == kNoValue && acc == kNoValue) continue;
      acc = materialize(acc);
      r = materialize(r);
      emit(op, acc, acc, r);
      release_scalar(r);
    }
    return acc;
  }

  int difference(NodeId n, int frame, bool under_blend, const Aabb* region, int depth) {
    const bool rf = use_rfunction(g_.boolean[n], under_blend);
    const auto c = g_.children_of(n);
    int acc = node(c[0], frame, under_blend, region, depth + 1);
    if (c.size() == 1) return acc;
    Interval acc_iv = region ? field_interval(g_, c[0], T_, *region, under_blend) : Interval{-1e300, 1e300};
    for (std::size_t i = 1; i < c.size(); ++i) {
      const Interval b_iv = region ? field_interval(g_, c[i], T_, *region, under_blend) : Interval{-1e300, 1e300};
      // With min/max, max(0, min(A, 2T - B)) is A itself where 0 <= A <= 2T - B.
      if (!rf && region && acc_iv.lo >= 0.0 && acc_iv.hi <= 2.0 * T_ - b_iv.hi) continue;
      if (!rf && acc == kNoValue) continue;  // max(0, min(0, x)) = 0
      int r = node(c[i], frame, under_blend, region, depth + 1);
      acc = materialize(acc);
      r = materialize(r);
      emit(rf ? OpCode::DiffRFunction : OpCode::DiffMinMax, acc, acc, r);
      release_scalar(r);
      acc_iv = {difference_field(acc_iv.lo, b_iv.hi, T_, rf), difference_field(acc_iv.hi, b_iv.lo, T_, rf)};
    }
    return acc;
  }

  int local_blend(NodeId n, int frame, bool under_blend, const Aabb* region, int depth) {
    const bool rf = use_rfunction(g_.boolean[n], under_blend);
    const auto c = g_.children_of(n);
    if (region) {
      const Interval w = field_interval(g_, c[2], T_, *region, true);
      if (w.hi <= 0.0) {  // no blending here: the union alone
        const int a = materialize(node(c[0], frame, true, region, depth + 1));
        const int b = materialize(node(c[1], frame, true, region, depth + 1));
        emit(rf ? OpCode::RUnion : OpCode::Max, a, a, b);
        release_scalar(b);
        return a;
      }
      if (w.lo >= 1.0) {  // full blending here: the sum alone
        const int a = node(c[0], frame, true, region, depth + 1);
        const int b = node(c[1], frame, true, region, depth + 1);
        if (a == kNoValue) return b;
        if (b == kNoValue) return a;
        emit(OpCode::Add, a, a, b);
        release_scalar(b);
        return a;
      }
    }
    const int a = materialize(node(c[0], frame, true, region, depth + 1));
    const int b = materialize(node(c[1], frame, true, region, depth + 1));
    const int r = materialize(node(c[2], frame, true, region, depth + 1));
    emit(rf ? OpCode::LocalBlendRFunction : OpCode::LocalBlendMinMax, a, b, r);  // in place in a
    release_scalar(b);
    release_scalar(r);
    return a;
  }

  int crop(NodeId n, int frame, bool under_blend, const Aabb* region, int depth) {
    const params::Crop c = params::crop(g_, n);
    const int child = node(g_.children_of(n)[0], frame, under_blend, region, depth + 1);
    if (child == kNoValue) return kNoValue;
    const glm::dvec3 centre = c.box.center(), half = 0.5 * c.box.size();
    const std::uint32_t k =
        constants(n, {centre.x, centre.y, centre.z, half.x, half.y, half.z, T_ / crop_reach(c.box6), T_});
    emit_k(OpCode::Crop, n, child, frame, k);  // in place
    return child;
  }

  // A guard around fewer instructions than this costs more than it saves.
  static constexpr std::size_t kGuardMinLength = 4;
  // Guard a subtree whose box has under this fraction of its parent's volume.
  static constexpr double kGuardFraction = 0.5;
  // Relative padding of a guard's box: floats just outside the support box may round inside it.
  static constexpr double kGuardPad = 1e-5;

  const Graph& g_;
  double T_;
  Tape& tape_;
  bool guards_ = true;
  double parent_volume_ = std::numeric_limits<double>::infinity();
  mutable std::vector<std::int8_t> zero_known_[2];  // zero_in_float per context: -1 unknown, 0, 1
  std::vector<int> free_scalars_, free_frames_;
  std::uint16_t high_ = 3;  // rows 0-2: the input frame
};

}  // namespace

const char* op_name(OpCode op) {
  switch (op) {
#define HT_X(name, doc) \
  case OpCode::name:    \
    return #name;
    HT_TAPE_OPS(HT_X)
#undef HT_X
  }
  return "?";
}

std::size_t Tape::leaf_count() const {
  std::size_t n = 0;
  for (const Instruction& i : code) n += i.op <= OpCode::Mesh ? 1 : 0;
  return n;
}

std::string Tape::listing() const {
  std::string out;
  char line[160];
  for (std::size_t i = 0; i < code.size(); ++i) {
    const Instruction& c = code[i];
    if (c.op == OpCode::Constant)
      std::snprintf(line, sizeof line, "%5zu  %-20s out=%u value=%g\n", i, op_name(c.op), c.out, double(c.immediate()));
    else if (c.op == OpCode::Skip)
      std::snprintf(line, sizeof line, "%5zu  %-20s out=%u frame=%u k=%u length=%g\n", i, op_name(c.op), c.out, c.a, c.k(),
                    double(constants[c.k() + 6]));
    else if (c.op <= OpCode::Mesh || c.op == OpCode::Crop || c.op >= OpCode::Affine)
      std::snprintf(line, sizeof line, "%5zu  %-20s out=%u frame=%u k=%u\n", i, op_name(c.op), c.out, c.a, c.k());
    else
      std::snprintf(line, sizeof line, "%5zu  %-20s out=%u a=%u b=%u\n", i, op_name(c.op), c.out, c.a, c.b);
    out += line;
  }
  return out;
}

Tape compile_tape(std::shared_ptr<const Graph> graph, NodeId root, double threshold, const Aabb* region,
                  bool under_blend, bool guards) {
  Tape tape;
  tape.graph = graph;
  tape.threshold = static_cast<float>(threshold);
  Compiler compiler(*graph, threshold, tape, guards);
  const int r = compiler.materialize(compiler.node(root, 0, under_blend, region, 0));
  tape.result = static_cast<std::uint16_t>(r);
  tape.registers = compiler.register_count();
  return tape;
}

}  // namespace ht
