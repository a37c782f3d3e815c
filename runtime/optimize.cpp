// The optimizer's rewriting walk: one pass from the root over (node, context) pairs, writing
// the rewritten tree bottom-up through a merging GraphWriter, then a compaction that keeps what
// the root reaches and writes `auto` back where it means the same. See runtime/optimize.hpp.
#include "runtime/optimize.hpp"

#include "nodes/operators.hpp"
#include "runtime/graph_writer.hpp"
#include "runtime/node_params.hpp"
#include "runtime/optimize_affine.hpp"
#include "runtime/optimize_regroup.hpp"
#include "runtime/tape.hpp"

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <vector>

namespace ht {

using optimize_detail::Group;

namespace {

constexpr std::size_t kBarrPushLeaves = 4;  // twist, taper, bend go down over at most this many leaves

BooleanMode resolved(BooleanMode mode, bool under_blend) {
  return use_rfunction(mode, under_blend) ? BooleanMode::RFunction : BooleanMode::MinMax;
}

// The contexts each node of `g` is reached in from root: bit 0 alone, bit 1 under a blend.
std::vector<std::uint8_t> contexts(const Graph& g, NodeId root) {
  std::vector<std::uint8_t> mask(g.size(), 0);
  mask[root] = 1;
  for (NodeId n = root + 1; n-- > 0;) {
    if (!mask[n]) continue;
    const bool blends = g.kind[n] == NodeKind::Blend || g.kind[n] == NodeKind::LocalBlend;
    for (NodeId c : g.children_of(n)) mask[c] |= blends ? std::uint8_t(2) : mask[n];
  }
  return mask;
}

class Rewriter {
 public:
  // sizes: per node of g, the nodes of its subtree counted as a tree (saturating), which says
  // which operands are worth a task of their own.
  Rewriter(const Graph& g, const OptimizeOptions& o, OptimizeStats& s, const std::vector<std::uint32_t>& sizes)
      : g_(g), o_(o), s_(s), sizes_(sizes), w_(o.merge) {
    for (auto& m : memo_) m.assign(g.size(), kNone);
  }

  NodeId rewrite(NodeId n, bool ub) {
    NodeId& known = memo_[ub ? 1 : 0][n];
    if (known == kNone) known = fresh(n, ub);
    return known;
  }

  GraphWriter& writer() { return w_; }

 private:
  NodeId fresh(NodeId n, bool ub) {
    const NodeKind k = g_.kind[n];
    switch (k) {
      case NodeKind::Blend: return blend(n);
      case NodeKind::Union:
      case NodeKind::Intersection: return boolean(n, ub);
      case NodeKind::Difference: return difference(n, ub);
      case NodeKind::LocalBlend: {
        const auto c = g_.children_of(n);
        const NodeId kids[] = {rewrite(c[0], true), rewrite(c[1], true), rewrite(c[2], true)};
        return w_.add(k, {}, kids, resolved(g_.boolean[n], ub), g_.mesher[n], name(n));
      }
      default: break;
    }
    if (kind_family(k) == Family::Warp && k != NodeKind::Ffd && o_.warps && plain(g_, n))
      return warp(k, g_.params_of(n), rewrite(g_.children_of(n)[0], ub));
    std::vector<NodeId> kids;
    for (NodeId c : g_.children_of(n)) kids.push_back(rewrite(c, ub));
    return w_.copy(g_, n, kids);  // leaves, crops, ffds and warps kept as they are
  }

  std::string name(NodeId n) const { return g_.name[n] != kNone ? g_.names[g_.name[n]] : std::string(); }
  // A node without a name or a mesher hint may be spliced, folded or pushed through.
  static bool plain(const Graph& g, NodeId n) { return g.name[n] == kNone && g.mesher[n] == MesherHint::Auto; }
  bool plain_new(NodeId n) const { return plain(w_.graph(), n); }

  // -- warps ------------------------------------------------------------------------------
  // Whether the warp (kind k, parameters p, a node's pool slice) leaves every point in place.
  static bool identity(NodeKind k, std::span<const double> p) {
    if (k == NodeKind::Affine) return optimize_detail::affine_is_identity(p);
    return params::barr_is_identity(k, params::barr(k, p));
  }

  std::size_t leaves(NodeId n) {  // of the new graph, memoized
    if (n < leaves_.size() && leaves_[n]) return leaves_[n];
    const Graph& g = w_.graph();
    std::size_t count = g.child_count[n] == 0 ? 1 : 0;
    for (NodeId c : g.children_of(n)) count += leaves(c);
    if (leaves_.size() <= n) leaves_.resize(g.size(), 0);
    return leaves_[n] = count;
  }

  // The warp (kind k, parameters p) applied to `child`, a node of the new graph.
  NodeId warp(NodeKind k, std::span<const double> p, NodeId child) {
    const Graph& g = w_.graph();
    if (identity(k, p)) {
      ++s_.identities_removed;
      return child;
    }
    const NodeKind ck = g.kind[child];
    if (k == NodeKind::Affine && plain_new(child)) {
      std::vector<double> q;
      if (ck == NodeKind::Affine && optimize_detail::compose_affine(p, g.params_of(child), q)) {
        ++s_.affines_composed;
        return warp(k, q, g.children_of(child)[0]);
      }
      if (kind_family(ck) == Family::Primitive && optimize_detail::fold_affine(ck, p, g.params_of(child), q)) {
        ++s_.affines_folded;
        return w_.add(ck, q, {});
      }
    }
    const bool through = ck == NodeKind::Blend || ck == NodeKind::Union || ck == NodeKind::Intersection ||
                         ck == NodeKind::Difference || ck == NodeKind::LocalBlend;
    if (through && plain_new(child) && (k == NodeKind::Affine || leaves(child) <= kBarrPushLeaves)) {
      ++s_.warps_pushed;
      const std::vector<NodeId> inner(g.children_of(child).begin(), g.children_of(child).end());
      const BooleanMode mode = g.boolean[child];
      std::vector<NodeId> kids;
      for (NodeId c : inner) kids.push_back(warp(k, p, c));
      return w_.add(ck, {}, kids, mode);
    }
    const NodeId kids[] = {child};
    return w_.add(k, p, kids);
  }

  // -- operators --------------------------------------------------------------------------
  // The operands of n once nested plain nodes of the same kind and mode are spliced in, read
  // on the old graph (a chain of binary blends however deep becomes one list, with no node
  // written for its links). `spliceable` says which child to descend into.
  template <class Spliceable>
  std::vector<NodeId> operands(NodeId n, Spliceable spliceable) {
    std::vector<NodeId> out;
    std::vector<std::pair<NodeId, std::size_t>> todo{{n, 0}};
    while (!todo.empty()) {
      auto& [node, next] = todo.back();
      const auto c = g_.children_of(node);
      if (next == c.size()) {
        todo.pop_back();
        continue;
      }
      const std::size_t i = next++;
      if (o_.flatten && spliceable(c[i], i) && plain(g_, c[i])) {
        ++s_.flattened;
        todo.push_back({c[i], 0});
        continue;
      }
      out.push_back(c[i]);
    }
    return out;
  }

  NodeId blend(NodeId n) {
    const auto terms = operands(n, [&](NodeId c, std::size_t) { return g_.kind[c] == NodeKind::Blend; });
    rewrite_in_parallel(terms, true);
    std::vector<NodeId> kids;
    for (NodeId c : terms) {
      if (o_.prune && g_.support(c, true).empty()) {  // 0 everywhere: a term that adds nothing
        ++s_.pruned;
        continue;
      }
      splice(NodeKind::Blend, BooleanMode::Auto, rewrite(c, true), kids);
    }
    if (kids.empty())  // every term is 0: keep them, the node must exist
      for (NodeId c : terms) kids.push_back(rewrite(c, true));
    return group(NodeKind::Blend, BooleanMode::Auto, kids, true, n);
  }

  NodeId boolean(NodeId n, bool ub) {
    const NodeKind k = g_.kind[n];
    const BooleanMode mode = resolved(g_.boolean[n], ub);
    const bool rf = mode == BooleanMode::RFunction;
    // Same kind, same mode in this context; R-functions do not associate: only the first operand.
    const auto c = operands(n, [&](NodeId child, std::size_t i) {
      return g_.kind[child] == k && resolved(g_.boolean[child], ub) == mode && (!rf || i == 0);
    });
    rewrite_in_parallel(c, ub);
    // max(x, 0) = x where x >= 0, which holds when any operand is non-negative.
    bool any_nonneg = false;
    for (NodeId child : c) any_nonneg = any_nonneg || g_.nonnegative[child];
    std::vector<NodeId> kids;
    for (std::size_t i = 0; i < c.size(); ++i) {
      if (o_.prune && k == NodeKind::Union && !rf && any_nonneg && g_.support(c[i], ub).empty() && c.size() > 1) {
        ++s_.pruned;
        continue;
      }
      const NodeId r = rewrite(c[i], ub);
      if (rf && !kids.empty()) kids.push_back(r);
      else splice(k, mode, r, kids);
    }
    if (kids.empty()) kids.push_back(rewrite(c[0], ub));
    return group(k, mode, kids, ub, n);
  }

  NodeId difference(NodeId n, bool ub) {
    const BooleanMode mode = resolved(g_.boolean[n], ub);
    // (A - B) - C = A - B - C: the first operand's chain of differences is read as one.
    const auto c = operands(n, [&](NodeId child, std::size_t i) {
      return i == 0 && g_.kind[child] == NodeKind::Difference && resolved(g_.boolean[child], ub) == mode;
    });
    std::vector<NodeId> kids;
    for (NodeId child : c) kids.push_back(rewrite(child, ub));
    // With min/max, A - B1 - ... - Bn = A - (B1 u ... u Bn): the subtrahends regroup as a union.
    if (mode == BooleanMode::MinMax && o_.regroup && kids.size() - 1 > std::size_t(o_.group_size)) {
      const std::vector<NodeId> sub(kids.begin() + 1, kids.end());
      const NodeId u = group(NodeKind::Union, mode, sub, ub, kNone);
      kids = {kids[0], u};
    }
    return w_.add(NodeKind::Difference, {}, kids, mode, g_.mesher[n], name(n));
  }

  // Independent subtrees as TBB tasks: operands big enough to pay for it are rewritten each by
  // a Rewriter of its own into its own writer, then joined into this one in operand order, node
  // by node in the order one walk would have written them; the merging writer makes what the
  // tasks wrote twice (a subtree two operands share) one node again. The same graph results
  // at any thread count.
  void rewrite_in_parallel(std::span<const NodeId> operands, bool ub) {
    std::vector<NodeId> big;
    for (NodeId c : operands)
      if (memo_[ub ? 1 : 0][c] == kNone && sizes_[c] >= kTaskNodes && std::find(big.begin(), big.end(), c) == big.end())
        big.push_back(c);
    if (!o_.parallel || big.size() < 2) return;
    s_.tasks += big.size();
    std::vector<OptimizeStats> stats(big.size());
    std::vector<std::unique_ptr<Rewriter>> tasks(big.size());
    std::vector<NodeId> roots(big.size());
    tbb::parallel_for(std::size_t(0), big.size(), [&](std::size_t i) {
      tasks[i] = std::make_unique<Rewriter>(g_, o_, stats[i], sizes_);
      roots[i] = tasks[i]->rewrite(big[i], ub);
    });
    for (std::size_t i = 0; i < big.size(); ++i) {
      memo_[ub ? 1 : 0][big[i]] = join(tasks[i]->writer().graph(), roots[i]);
      add_counts(stats[i]);
    }
  }

  // Copies what `root` reaches in `part` into this writer; returns root's id here.
  NodeId join(const Graph& part, NodeId root) {
    const std::vector<std::uint8_t> reached = contexts(part, root);
    std::vector<NodeId> id(part.size(), kNone);
    std::vector<NodeId> kids;
    for (NodeId n = 0; n <= root; ++n) {
      if (!reached[n]) continue;
      kids.clear();
      for (NodeId c : part.children_of(n)) kids.push_back(id[c]);
      id[n] = w_.copy(part, n, kids);
    }
    return id[root];
  }

  void add_counts(const OptimizeStats& t) {
    s_.flattened += t.flattened, s_.groups += t.groups, s_.warps_pushed += t.warps_pushed;
    s_.affines_composed += t.affines_composed, s_.affines_folded += t.affines_folded;
    s_.identities_removed += t.identities_removed, s_.pruned += t.pruned, s_.folded += t.folded, s_.tasks += t.tasks;
  }

  // Appends r to kids, or r's operands when r is a plain node of the same kind and mode.
  void splice(NodeKind k, BooleanMode mode, NodeId r, std::vector<NodeId>& kids) {
    const Graph& g = w_.graph();
    const bool same = g.kind[r] == k && g.boolean[r] == mode && plain_new(r) &&
                      (k == NodeKind::Blend || k == NodeKind::Difference || mode == BooleanMode::MinMax || kids.empty());
    if (o_.flatten && same && (k != NodeKind::Difference || kids.empty())) {
      ++s_.flattened;
      const auto inner = g.children_of(r);
      kids.insert(kids.end(), inner.begin(), inner.end());
      return;
    }
    kids.push_back(r);
  }

  // The n-ary node of kind k over kids (new ids), regrouped in space where that keeps the field
  // (sums, and min/max unions), folded away when it has one operand. `from` gives the name and
  // the hint (kNone: none).
  NodeId group(NodeKind k, BooleanMode mode, std::vector<NodeId> kids, bool kids_under_blend, NodeId from) {
    const MesherHint hint = from != kNone ? g_.mesher[from] : MesherHint::Auto;
    std::string label = from != kNone ? name(from) : std::string();
    if (o_.fold && kids.size() == 1 && hint == MesherHint::Auto && label.empty()) {
      ++s_.folded;
      return kids[0];
    }
    const bool regroupable = k == NodeKind::Blend || (k == NodeKind::Union && mode == BooleanMode::MinMax);
    if (!o_.regroup || !regroupable || kids.size() <= std::size_t(o_.group_size))
      return w_.add(k, {}, kids, mode, hint, std::move(label));
    std::vector<Aabb> boxes;
    for (NodeId c : kids) boxes.push_back(w_.graph().support(c, kids_under_blend));
    const Group top = optimize_detail::spatial_groups(boxes, o_.group_size);
    std::vector<NodeId> parts = emit_parts(k, mode, top, kids);
    return w_.add(k, {}, parts, mode, hint, std::move(label));
  }

  std::vector<NodeId> emit_parts(NodeKind k, BooleanMode mode, const Group& grp, const std::vector<NodeId>& kids) {
    std::vector<NodeId> out;
    for (std::uint32_t i : grp.items) out.push_back(kids[i]);
    for (const Group& part : grp.parts) {
      std::vector<NodeId> inner = emit_parts(k, mode, part, kids);
      if (inner.size() == 1) {
        out.push_back(inner[0]);
        continue;
      }
      ++s_.groups;
      out.push_back(w_.add(k, {}, inner, mode));
    }
    return out;
  }

  static constexpr std::uint32_t kTaskNodes = 256;  // a subtree smaller than this is not worth a task

  const Graph& g_;
  const OptimizeOptions& o_;
  OptimizeStats& s_;
  const std::vector<std::uint32_t>& sizes_;
  GraphWriter w_;
  std::vector<NodeId> memo_[2];
  std::vector<std::size_t> leaves_;
};

// Keeps what root reaches, in post-order from the root (children in order, each node once), so
// the ids depend on the tree alone, not on the order the rewriting wrote nodes in; each explicit
// Boolean mode is written back as `auto` where `auto` means the same in every context the node
// is reached in.
std::pair<Graph, NodeId> compact(const Graph& g, NodeId root) {
  const std::vector<std::uint8_t> mask = contexts(g, root);
  GraphWriter out;
  std::vector<NodeId> id(g.size(), kNone);
  std::vector<std::pair<NodeId, std::size_t>> todo{{root, 0}};
  std::vector<NodeId> kids;
  while (!todo.empty()) {
    auto& [n, next] = todo.back();
    const auto c = g.children_of(n);
    if (next < c.size()) {
      const NodeId child = c[next++];
      if (id[child] == kNone) todo.push_back({child, 0});
      continue;
    }
    const NodeId node = n;
    todo.pop_back();
    if (id[node] != kNone) continue;  // reached twice before it was written
    kids.clear();
    for (NodeId child : g.children_of(node)) kids.push_back(id[child]);
    id[node] = out.copy(g, node, kids);
    const BooleanMode m = g.boolean[node];
    if (m == BooleanMode::Auto) continue;
    bool same = true;
    for (int ub = 0; ub < 2; ++ub)
      if (mask[node] & (1 << ub)) same = same && use_rfunction(BooleanMode::Auto, ub == 1) == (m == BooleanMode::RFunction);
    if (same) out.set_boolean(id[node], BooleanMode::Auto);
  }
  return {out.take(), id[root]};
}

void measure(const Graph& g, NodeId root, double T, std::size_t& nodes, double& overlap, std::size_t& tape,
             std::size_t& registers, const std::shared_ptr<const Graph>& shared) {
  nodes = reachable_nodes(g, root);
  overlap = overlap_volume(g, root);
  try {
    const Tape t = compile_tape(shared, root, T);
    tape = t.size();
    registers = t.registers;
  } catch (const CompileError&) {  // an ffd not yet meshed
    tape = registers = 0;
  }
}

}  // namespace

Tree optimize(const Tree& tree, const OptimizeOptions& options, OptimizeStats* stats) {
  const auto start = std::chrono::steady_clock::now();
  OptimizeStats local;
  OptimizeStats& s = stats ? *stats : local;
  s = OptimizeStats{};
  const Graph& g = tree.graph();
  std::vector<std::uint32_t> sizes(g.size());
  for (NodeId n = 0; n < g.size(); ++n) {
    std::uint64_t count = 1;
    for (NodeId c : g.children_of(n)) count += sizes[c];
    sizes[n] = static_cast<std::uint32_t>(std::min<std::uint64_t>(count, 1u << 30));
  }
  Rewriter rw(g, options, s, sizes);
  const NodeId root = rw.rewrite(tree.root(), false);
  s.merged = rw.writer().merged();
  auto [graph, new_root] = compact(rw.writer().graph(), root);
  auto shared = std::make_shared<const Graph>(std::move(graph));
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (stats) {  // two tape compilations and an overlap sweep: only for a caller who reads them
    tbb::parallel_invoke(
        [&] {
          measure(tree.graph(), tree.root(), tree.threshold(), s.nodes_before, s.overlap_before, s.tape_before,
                  s.registers_before, tree.graph_ptr());
        },
        [&, root = new_root] {
          measure(*shared, root, tree.threshold(), s.nodes_after, s.overlap_after, s.tape_after, s.registers_after, shared);
        });
  }
  return Tree(shared, new_root, tree.threshold(), tree.mesher_settings());
}

std::size_t reachable_nodes(const Graph& g, NodeId root) {
  const std::vector<std::uint8_t> mask = contexts(g, root);
  return static_cast<std::size_t>(std::count_if(mask.begin(), mask.end(), [](std::uint8_t m) { return m != 0; }));
}

double overlap_volume(const Graph& g, NodeId root) {
  const std::vector<std::uint8_t> mask = contexts(g, root);
  double total = 0.0;
  std::vector<Aabb> boxes;
  std::vector<std::uint32_t> order;
  for (NodeId n = 0; n <= root; ++n) {
    const NodeKind k = g.kind[n];
    if (!mask[n] || (k != NodeKind::Blend && k != NodeKind::Union && k != NodeKind::Intersection && k != NodeKind::Difference))
      continue;
    const bool ub = (mask[n] & 2) || k == NodeKind::Blend;
    boxes.clear();
    for (NodeId c : g.children_of(n)) boxes.push_back(g.support(c, ub));
    // Sweep along x: only boxes whose x ranges meet can overlap.
    order.resize(boxes.size());
    for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
      return boxes[a].lo.x < boxes[b].lo.x || (boxes[a].lo.x == boxes[b].lo.x && a < b);
    });
    for (std::size_t i = 0; i < order.size(); ++i)
      for (std::size_t j = i + 1; j < order.size() && boxes[order[j]].lo.x <= boxes[order[i]].hi.x; ++j) {
        const double v = volume(intersect(boxes[order[i]], boxes[order[j]]));
        if (std::isfinite(v)) total += v;
      }
  }
  return total;
}

}  // namespace ht
