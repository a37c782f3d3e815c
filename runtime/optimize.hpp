// The tree-rewriting optimizer (the paper, section 4): users build trees in the order they
// think; the optimizer rewrites them into the order that evaluates and meshes fast, with the
// same field. Rules, each optional:
//   flatten   nested blends, and nested min/max unions and intersections, become n-ary nodes
//             (an R-function Boolean only through its first operand: R-functions do not
//             associate); a difference whose first operand is a difference takes its operands
//   regroup   the operands of n-ary blends and min/max unions (and the subtrahends of a min/max
//             difference, as a union) are regrouped into a spatial hierarchy of small groups
//             whose support boxes overlap little (runtime/optimize_regroup.hpp): the tape then
//             guards each group with a box test (runtime/tape.hpp Skip), region specialization
//             stops at groups that miss the region, and per-node meshing gets small jobs
//   warps     affine maps compose, fold into primitives where they are similarities, and are
//             pushed down through blends, Booleans and local blends to the leaves; twist, taper
//             and bend are pushed down over subtrees of at most 4 leaves (each copy costs a
//             frame per leaf); identity warps go
//   merge     identical subtrees become one node
//   prune     subtrees that are 0 everywhere (a min/max intersection of disjoint non-negative
//             operands, a crop whose box misses its child) leave the blends and unions holding them
//   fold      one-operand blends, unions and intersections become their operand
// Where a node moves under or out of a blend, its Booleans keep their meaning: the `auto` rule
// is resolved where the node was, and written back as `auto` only where it means the same in
// every place the node ends up.
//
// Thread-safe: optimize() reads the tree and writes a new graph. Operands of an n-ary node whose
// subtrees are big (256 nodes or more) are rewritten as TBB tasks, each into a graph of its
// own joined in operand order; regrouping large operand sets splits them as TBB tasks; the
// before/after measurements run side by side. The result is the same at any thread count, and
// the same graph as with `parallel` off.
#pragma once

#include "runtime/tree.hpp"

#include <cstddef>

namespace ht {

struct OptimizeOptions {
  bool flatten = true, regroup = true, warps = true, merge = true, prune = true, fold = true;
  int group_size = 4;  ///< operands (or groups) per group when regrouping, >= 2
  bool parallel = true;  ///< big independent operands rewritten as TBB tasks (same result either way)
};

/// What a run did: sizes before and after, and what each rule did.
struct OptimizeStats {
  std::size_t nodes_before = 0, nodes_after = 0;  ///< nodes reachable from the root
  double overlap_before = 0, overlap_after = 0;   ///< overlap_volume() of each tree
  std::size_t tape_before = 0, tape_after = 0;    ///< instructions (0 when the tree has an ffd)
  std::size_t registers_before = 0, registers_after = 0;
  std::size_t flattened = 0;   ///< operator nodes spliced into their parent
  std::size_t groups = 0;      ///< group nodes made by regrouping
  std::size_t warps_pushed = 0, affines_composed = 0, affines_folded = 0, identities_removed = 0;
  std::size_t merged = 0;      ///< nodes that turned out equal to one already written
  std::size_t pruned = 0;      ///< subtrees removed as 0 everywhere
  std::size_t folded = 0;      ///< one-operand operators replaced by their operand
  std::size_t tasks = 0;       ///< subtrees rewritten as TBB tasks of their own
  double seconds = 0;
};

/// The optimized tree: the same field (to float rounding of sums taken in another order) with
/// the same threshold and mesher settings. Names and mesher hints stay on their nodes (a node
/// with either is never spliced into another). `stats`, when given, also gets the before/after
/// sizes, overlap and tape lengths, which cost two tape compilations.
Tree optimize(const Tree& tree, const OptimizeOptions& options = {}, OptimizeStats* stats = nullptr);

/// The summed volume in which the operands of each operator overlap: over every blend, union,
/// intersection and difference reachable from the root, the volume of the pairwise
/// intersections of its operands' support boxes. What regrouping lowers.
double overlap_volume(const Graph& graph, NodeId root);

/// Nodes reachable from root.
std::size_t reachable_nodes(const Graph& graph, NodeId root);

}  // namespace ht
