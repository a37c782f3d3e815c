// Narrowing: a tape specialized to a box, made from a tape valid over a larger one. The pass
// bounds every register over the box by interval arithmetic (runtime/interval.hpp, the rules
// the compiler prunes with), replaces the leaves it finds 0 or constant there, drops the
// operations it finds decided there, then removes what no longer reaches the result.
#include "runtime/interval.hpp"
#include "runtime/tape.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <vector>

namespace ht {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

bool is_leaf(OpCode op) { return op <= OpCode::Mesh; }
bool is_warp(OpCode op) { return op >= OpCode::Affine && op <= OpCode::Bend; }
bool uses_constants(OpCode op) { return is_leaf(op) || is_warp(op) || op == OpCode::Crop || op == OpCode::Skip; }

// Phase 1: bound each register over the box and decide each instruction: kept as it is,
// replaced (a leaf by Zero or Constant, a local blend by its union or sum) or dropped (an
// operation whose result is its first operand, which already holds it).
void bound_and_decide(const Tape& parent, const Aabb& region, std::vector<Instruction>& code,
                      std::vector<NodeId>& source) {
  const Graph& g = *parent.graph;
  const double T = parent.threshold;
  std::vector<Interval> iv(parent.registers, Interval{-kInf, kInf});
  std::vector<Aabb> box(parent.registers, Aabb::everything());
  box[0] = region;
  auto keep = [&](const Instruction& ins, NodeId n) {
    code.push_back(ins);
    source.push_back(n);
  };
  for (std::size_t i = 0; i < parent.code.size(); ++i) {
    const Instruction& ins = parent.code[i];
    const NodeId n = parent.source[i];
    // Register operands only where the opcode has them: elsewhere a and b hold k or an immediate.
    const bool registers = ins.op >= OpCode::Add && ins.op <= OpCode::LocalBlendRFunction;
    const Interval a = registers ? iv[ins.a] : Interval{}, b = registers ? iv[ins.b] : Interval{};
    Interval& out = iv[ins.out];
    const bool in_place = ins.out == ins.a;
    switch (ins.op) {
      case OpCode::Skip: break;  // dropped: its range runs, and gives the same values
      case OpCode::Zero: out = {}; keep(ins, n); break;
      case OpCode::Constant: out = {ins.immediate(), ins.immediate()}; keep(ins, n); break;
      case OpCode::Add:
        out = interval::add(a, b);
        if (!(in_place && b.zero())) keep(ins, n);
        break;
      case OpCode::Max:
      case OpCode::Min: {
        const bool first_wins = ins.op == OpCode::Max ? a.lo >= b.hi : a.hi <= b.lo;
        out = ins.op == OpCode::Max ? interval::unite(a, b, T, false) : interval::intersect(a, b, T, false);
        if (!(in_place && first_wins)) keep(ins, n);
        break;
      }
      case OpCode::RUnion: out = interval::unite(a, b, T, true); keep(ins, n); break;
      case OpCode::RIntersection: out = interval::intersect(a, b, T, true); keep(ins, n); break;
      case OpCode::DiffMinMax: {
        // max(0, min(A, 2T - B)) is A where 0 <= A <= 2T - B.
        const bool first_wins = a.lo >= 0.0 && a.hi <= 2.0 * T - b.hi;
        out = interval::subtract(a, b, T, false);
        if (!(in_place && first_wins)) keep(ins, n);
        break;
      }
      case OpCode::DiffRFunction: out = interval::subtract(a, b, T, true); keep(ins, n); break;
      case OpCode::LocalBlendMinMax:
      case OpCode::LocalBlendRFunction: {  // in place: out (A) blended with a (B), weight b
        const bool rf = ins.op == OpCode::LocalBlendRFunction;
        const Interval w = b, first = out;
        out = interval::local_blend(first, a, w, T, rf);
        if (w.hi <= 0.0)  // no blending here: the union alone
          keep(Instruction::make(rf ? OpCode::RUnion : OpCode::Max, ins.out, ins.out, ins.a), n);
        else if (w.lo >= 1.0)  // full blending here: the sum alone
          keep(Instruction::make(OpCode::Add, ins.out, ins.out, ins.a), n);
        else
          keep(ins, n);
        break;
      }
      case OpCode::Crop: out = interval::crop(g, n, T, box[ins.a], out); keep(ins, n); break;
      default:
        if (is_warp(ins.op)) {
          Aabb local;
          box[ins.out] = interval::warp_child_region(g, n, box[ins.a], local) ? local : Aabb::everything();
          keep(ins, n);
          break;
        }
        out = interval::leaf(g, n, T, box[ins.a]);  // a primitive or a mesh
        if (out.zero()) {
          keep(Instruction::make(OpCode::Zero, ins.out), n);
        } else if (out.lo == out.hi) {
          Instruction c = Instruction::make(OpCode::Constant, ins.out);
          c.set_immediate(static_cast<float>(out.lo));
          keep(c, n);
        } else {
          keep(ins, n);
        }
    }
  }
}

// Phase 2: which instructions reach the result, walking back with the rows still to be read.
std::vector<std::uint8_t> reaching(const std::vector<Instruction>& code, std::size_t registers, int result) {
  std::vector<std::uint8_t> live(registers, 0), needed(code.size(), 0);
  live[std::size_t(result)] = 1;
  auto read_frame = [&](int f) { live[std::size_t(f)] = live[std::size_t(f) + 1] = live[std::size_t(f) + 2] = 1; };
  for (std::size_t i = code.size(); i-- > 0;) {
    const Instruction& ins = code[i];
    const std::size_t o = ins.out;
    if (is_warp(ins.op)) {
      if (!(live[o] | live[o + 1] | live[o + 2])) continue;
      live[o] = live[o + 1] = live[o + 2] = 0;
      needed[i] = 1;
      read_frame(ins.a);
      continue;
    }
    if (!live[o]) continue;
    needed[i] = 1;
    const bool in_place = ins.op == OpCode::Crop || ins.op == OpCode::LocalBlendMinMax || ins.op == OpCode::LocalBlendRFunction;
    live[o] = in_place ? 1 : 0;
    if (is_leaf(ins.op) || ins.op == OpCode::Crop) read_frame(ins.a);
    else if (ins.op != OpCode::Zero && ins.op != OpCode::Constant) live[ins.a] = live[ins.b] = 1;
  }
  return needed;
}

}  // namespace

Tape narrow_tape(const Tape& parent, const Aabb& region) {
  if (parent.source.size() != parent.code.size())
    throw std::invalid_argument("narrow_tape: the tape has no source nodes (made by compile_tape?)");
  std::vector<Instruction> code;
  std::vector<NodeId> source;
  bound_and_decide(parent, region, code, source);
  const std::vector<std::uint8_t> needed = reaching(code, parent.registers, parent.result);
  // Each instruction's constants run from its k to the next one's: the compiler appends them in
  // the order it emits.
  std::vector<std::uint32_t> starts;
  for (const Instruction& ins : parent.code)
    if (uses_constants(ins.op)) starts.push_back(ins.k());
  std::sort(starts.begin(), starts.end());
  Tape out;
  out.graph = parent.graph;
  out.meshes = parent.meshes;
  out.registers = parent.registers;
  out.result = parent.result;
  out.threshold = parent.threshold;
  for (std::size_t i = 0; i < code.size(); ++i) {
    if (!needed[i]) continue;
    Instruction ins = code[i];
    if (uses_constants(ins.op)) {
      const std::uint32_t k = ins.k();
      const auto next = std::upper_bound(starts.begin(), starts.end(), k);
      const std::size_t end = next == starts.end() ? parent.constants.size() : *next;
      ins.set_k(static_cast<std::uint32_t>(out.constants.size()));
      out.constants.insert(out.constants.end(), parent.constants.begin() + k, parent.constants.begin() + std::ptrdiff_t(end));
    }
    out.code.push_back(ins);
    out.source.push_back(source[i]);
  }
  if (out.code.empty()) {  // the result row is written by nothing: 0 everywhere in the box
    out.code.push_back(Instruction::make(OpCode::Zero, out.result));
    out.source.push_back(kNone);
  }
  return out;
}

}  // namespace ht
