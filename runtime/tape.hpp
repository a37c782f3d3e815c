// The tape: a HybridTree node compiled into a flat list of instructions over numbered
// registers, evaluated in float over structure-of-arrays blocks of points.
//
//   Graph --compile(node, region?)--> Tape --TapeEvaluator--> values / gradients
//
// One register file: a register is a row of one float per lane. A field value takes one row; a
// frame of coordinates takes three consecutive rows (x, y, z) and is named by its first. Rows 0-2
// are the query points; a warp writes a new frame for its subtree, so coordinates are registers
// too and the hot loop never walks the tree.
// Each instruction is a tight loop over the lanes of a block (the compiler vectorizes the float
// loops; the evaluator is built for AVX-512, AVX2 and baseline x86-64 and picks at run time).
//
// Compilation is a post-order walk with register reuse: a value's register is freed when its
// consumer is emitted, so the registers in use grow with the tree's depth, not its size, and a
// block's working set stays in L1. The `auto` Boolean rule is resolved here, per path.
//
// With a region (an axis-aligned box), compilation specializes: interval analysis over the box
// removes every node whose field is 0 there, every blend term that is 0 there and every
// min/max branch decided there, so the tape is shorter and gives the same values inside the
// box. This is the paper's bounding-box hierarchy (section 4), made data-oriented.
#pragma once

#include "runtime/aabb.hpp"
#include "runtime/graph.hpp"

#include <bit>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace ht {

// X(opcode, what it computes)
#define HT_TAPE_OPS(X)                                                   \
  X(Point, "s[out] = g(distance to a point, in frame a)")                \
  X(Segment, "s[out] = g(distance to a segment)")                       \
  X(Circle, "s[out] = g(distance to a circle)")                         \
  X(Disc, "s[out] = g(distance to a disc)")                             \
  X(Triangle, "s[out] = g(distance to a triangle)")                     \
  X(Curve, "s[out] = g(distance to a polyline)")                        \
  X(Box, "s[out] = g(distance to a solid box)")                         \
  X(Cylinder, "s[out] = g(distance to a solid capped cylinder)")        \
  X(ConeSphere, "s[out] = g(distance to the hull of two spheres)")      \
  X(Mesh, "s[out] = pseudo-distance field of mesh k (Embree)")         \
  X(Zero, "s[out] = 0")                                                 \
  X(Constant, "s[out] = constant k (a node constant over the region)")  \
  X(Add, "s[out] = s[a] + s[b]")                                        \
  X(Max, "s[out] = max(s[a], s[b])")                                    \
  X(Min, "s[out] = min(s[a], s[b])")                                    \
  X(RUnion, "s[out] = R-function union of s[a], s[b]")                  \
  X(RIntersection, "s[out] = R-function intersection of s[a], s[b]")    \
  X(DiffMinMax, "s[out] = max(0, min(s[a], 2T - s[b]))")                \
  X(DiffRFunction, "s[out] = max(0, R-intersection(s[a], 2T - s[b]))")  \
  X(LocalBlendMinMax, "s[out] = w(s[a]+s[b]) + (1-w) max(s[a],s[b])")   \
  X(LocalBlendRFunction, "s[out] = w(s[a]+s[b]) + (1-w) R-union")       \
  X(Crop, "s[out] = max(0, min(s[b], h(frame a)))")                     \
  X(Affine, "frame out = inverse affine map of frame a")                \
  X(Twist, "frame out = inverse twist of frame a")                      \
  X(Taper, "frame out = inverse taper of frame a")                      \
  X(Bend, "frame out = inverse bend of frame a")                      \
  X(Skip, "no lane of frame a in box k: s[out] = 0, jump past the range")

enum class OpCode : std::uint8_t {
#define HT_X(name, doc) name,
  HT_TAPE_OPS(HT_X)
#undef HT_X
};

const char* op_name(OpCode op);

/// One instruction: 8 bytes, operands as the opcode says (registers are rows of the one file):
///   primitives, Mesh      s[out] from frame a and the constants at k()
///   warps                 frame out from frame a and the constants at k()
///   Crop                  s[out] cropped in place, frame a, constants at k()
///   Constant              s[out] = immediate()
///   Zero                  s[out] = 0
///   Add ... DiffRFunction s[out] = s[a] op s[b]
///   LocalBlend*           s[out] blended in place with s[a] by the weight s[b]
///   Skip                  guards the range of instructions after it, which computes s[out]
///                         from frame a and is exactly 0 outside a box: when no lane of the
///                         block lies in the box, s[out] = 0 and the range is jumped over.
///                         Constants at k(): the box lo(3), hi(3), the range's length.
/// k() is a 24-bit index into the constant pool, kept in `b` and `hi`; a Constant's value is a
/// float immediate in `a` and `b`.
struct Instruction {
  OpCode op = OpCode::Zero;
  std::uint8_t hi = 0;  ///< bits 16-23 of k()
  std::uint16_t out = 0, a = 0, b = 0;

  static constexpr std::uint32_t kMaxConstant = (1u << 24) - 1;
  /// An instruction with register operands.
  static Instruction make(OpCode op, int out, int a = 0, int b = 0) {
    Instruction i;
    i.op = op;
    i.out = static_cast<std::uint16_t>(out);
    i.a = static_cast<std::uint16_t>(a);
    i.b = static_cast<std::uint16_t>(b);
    return i;
  }
  std::uint32_t k() const { return std::uint32_t(b) | std::uint32_t(hi) << 16; }
  void set_k(std::uint32_t at) {
    b = static_cast<std::uint16_t>(at & 0xffffu);
    hi = static_cast<std::uint8_t>(at >> 16);
  }
  float immediate() const { return std::bit_cast<float>(std::uint32_t(a) | std::uint32_t(b) << 16); }
  void set_immediate(float v) {
    const auto bits = std::bit_cast<std::uint32_t>(v);
    a = static_cast<std::uint16_t>(bits & 0xffffu);
    b = static_cast<std::uint16_t>(bits >> 16);
  }
};
static_assert(sizeof(Instruction) == 8, "instructions stay 8 bytes: a tape streams through L1 once per block");

/// A Curve instruction's constants: the primitive header (4), its support box lo, hi (6), the
/// segment count S, then a box lo, hi (6) for each of the G groups of kCurveGroup consecutive
/// segments, then each group's ball (centre and the square of its reach: R plus the group's
/// radius, 4), then per segment a, b - a, 1/|b - a|^2 (7).
inline constexpr int kCurveGroup = 8;

/// Thrown when a node cannot be compiled (an ffd before meshing exists, a tree too deep).
struct CompileError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
/// Thrown when a node's field needs a number past the float range the tape computes in (a twist
/// rate of 4e38): the tape would say otherwise than the tree.
struct FloatRangeError : CompileError {
  using CompileError::CompileError;
};

struct Tape {
  std::vector<Instruction> code;
  /// Per instruction, the node a leaf, warp or crop instruction came from (kNone for the
  /// others): what narrow_tape() reads to bound it over a smaller box.
  std::vector<NodeId> source;
  std::vector<float> constants;
  std::vector<const MeshLeaf*> meshes;  ///< kept alive by `graph`
  std::shared_ptr<const Graph> graph;   ///< the graph the tape came from
  std::uint16_t registers = 3;          ///< rows of the register file used (rows 0-2: the input frame)
  std::uint16_t result = 0;             ///< the register holding the root's value
  float threshold = 0.5f;
  std::uint32_t skips = 0;              ///< Skip instructions (batches are sorted in space for them)

  std::size_t size() const { return code.size(); }
  std::size_t bytes() const {
    return code.size() * sizeof(Instruction) + constants.size() * sizeof(float) + meshes.size() * sizeof(void*);
  }
  /// Number of instructions of each primitive or mesh kind (for statistics and tests).
  std::size_t leaf_count() const;
  /// One line per instruction, for debugging and `hybridtree info --tape`.
  std::string listing() const;
};

/// Compiles `root` (a root on its own: `auto` picks min/max there, unless `under_blend` says that
/// something above blends it, as when a mesher needs a child's field in its parent's context).
/// With `region`, the tape is specialized to that box: shorter, and equal to the full tape inside it.
/// With `guards`, a subtree whose support box is small against its parent's (under half its
/// volume) and whose code is long enough to pay for a box test is guarded by a Skip: blocks of
/// points that all miss the box jump over it. Values are the same with or without guards (the
/// subtree is exactly 0 outside its box, which the guard pads against float rounding).
Tape compile_tape(std::shared_ptr<const Graph> graph, NodeId root, double threshold, const Aabb* region = nullptr,
                  bool under_blend = false, bool guards = true);

/// The tape specialized to `region`, made from `parent`, a tape valid over a box that holds
/// region (or everywhere): leaves that are 0 or constant over the region are replaced, decided
/// operations dropped, and what no longer reaches the result removed. Its values inside the
/// region equal the parent's (to float rounding where constants replace leaves); it costs one
/// interval pass over the parent's instructions, however big the tree behind them. The
/// polygonizer narrows each brick's tape from a tape of a block of bricks this way. Skips are
/// dropped (their ranges then always run): a narrowed box is small.
Tape narrow_tape(const Tape& parent, const Aabb& region);

/// A conservative range of a node's field over a box (interval analysis; the compiler's pruning
/// rules rest on it). `under_blend` as in reference_field.
struct Interval {
  double lo = 0.0, hi = 0.0;
  bool zero() const { return lo == 0.0 && hi == 0.0; }
};
Interval field_interval(const Graph& graph, NodeId node, double threshold, const Aabb& box, bool under_blend);

/// A box holding the node's solid {f >= T} (conservative; infinite when it cannot be bounded).
Aabb solid_bounds(const Graph& graph, NodeId node, double threshold, bool under_blend = false);
/// True when {f >= threshold} of the node (as a tree of its own) is surely empty: its bounds are
/// empty, or it is a leaf whose strength is below the threshold (its field is at most its
/// strength), or a Boolean, crop or warp of such (a min/max union of empty operands, an
/// intersection with one, a difference or crop of one). A blend is never called empty here beyond its bounds:
/// weak operands may sum past the threshold. Conservative: false says nothing.
bool solid_empty(const Graph& graph, NodeId node, double threshold);

}  // namespace ht
