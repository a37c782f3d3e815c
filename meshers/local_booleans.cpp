// Trimmed Booleans (meshers/local_ops.hpp): a left fold of binary steps, each cutting both meshes
// along the other's surface and welding the two seams into one.
#include "meshers/local_ops.hpp"

#include "meshers/local_parts.hpp"
#include "meshers/relax.hpp"
#include "meshers/unfold.hpp"
#include "meshers/warp_mesh.hpp"
#include "runtime/tape.hpp"

#include <algorithm>
#include <string>
#include <vector>

namespace ht {

using namespace local;

namespace {

// An operand of one Boolean step: its mesh, its field, where that field may be non-zero, and the
// tape that projects the vertices its refinement adds (the operand's own; none for the result of
// earlier steps, whose refinement splits at midpoints: no single surface is its own). An operand
// straight from a child job refines that job's mesh without copying it between cuts
// (RefinedMesh).
struct BooleanOperand {
  RefinedMesh shape;
  BatchField field;
  Aabb support;
};

BatchField shifted(const BatchField& f, double a, double b) {
  return [f, a, b](std::span<const glm::dvec3> points, std::span<double> values) {
    f(points, values);
    for (double& v : values) v = a * v + b;
  };
}

// a op b, both trimmed along the other's surface and stitched. The cuts sample the other
// operand at vertices: a triangle can hide a small excursion of the other surface, and the seams
// then cross. Where they do, both meshes are refined (edges halved each round) and cut again.
TriangleMesh boolean_step(const LocalInput& in, NodeKind kind, BooleanOperand& a, BooleanOperand& b,
                          const TapeEvaluator& node_field, LocalStats& st) {
  const double T = in.threshold;
  // Keep A where B does not change it, and B where A does not: outside the other for a union,
  // inside it for an intersection; a difference keeps A outside B and B inside A, turned over.
  const bool keep_a_outside = kind != NodeKind::Intersection;
  const bool keep_b_outside = kind == NodeKind::Union;
  const Aabb meet = intersect(a.support, b.support), near = meet.expanded(2.0 * in.precision);
  // A round halves the edges inside the crossing seams' box: at most four times the triangles
  // there. Where the operands lie on each other the box spans them and their slivers split
  // without end (847k triangles from 6k, then an intersection search of 15 GB); past eight
  // times the operand's mesh as it stands (plus 65,536), the Boolean is polygonized instead.
  auto refine = [&](BooleanOperand& o, const Aabb& region, double edge) {
    const std::size_t before = o.shape.mesh().triangles.size();
    if (!o.shape.refine(region, edge, 8 * before + 65536))
      throw LocalFailure("the seams still cross, and halving the operands' edges to " + std::to_string(edge) +
                         " near them would take more than " + std::to_string(8 * before + 65536) + " triangles");
  };
  auto cut = [&](BooleanOperand& o, const BatchField& f) {
    TriangleMesh piece = cut_mesh(o.shape.mesh(), f, cut_options(in, true));
    o.shape.drop();
    return piece;
  };
  double edge = 1.5 * in.precision;
  // First only near the seams: each operand's surface is cut where the other's field is T.
  a.shape.refine_near_seam(meet.expanded(in.precision), edge, shifted(b.field, 1, -T));
  b.shape.refine_near_seam(meet.expanded(in.precision), edge, shifted(a.field, 1, -T));
  TriangleMesh out;
  std::vector<std::uint8_t> seam;
  for (int round = 0;; ++round) {
    std::vector<TriangleMesh> pieces;
    pieces.push_back(cut(a, keep_a_outside ? shifted(b.field, 1, -T) : shifted(b.field, -1, T)));
    pieces.push_back(cut(b, keep_b_outside ? shifted(a.field, 1, -T) : shifted(a.field, -1, T)));
    if (kind == NodeKind::Difference) flip(pieces[1]);
    st.kept_triangles = count_triangles(pieces);
    seam.clear();  // stitch appends one flag per vertex of this round's result
    out = join(std::move(pieces), seam_options(in, false), st, &seam);
    // The seam is the crease: it stays. Only where the operands meet can the result intersect.
    auto crossing = intersections_in(out, near);
    // A seam crossing where a triangle hid the other surface's excursion is a few pairs (at most
    // 9 in the tests' scenes); many more is two surfaces lying on each other (two copies of a
    // ball intersected: 3,904 pairs on 7,808 triangles), which untangling and refining only
    // multiply (tests/data/stress/coincident_operands_4gb.json: 15 GB and two minutes before).
    if (crossing.size() > 64 + out.triangles.size() / 16)
      throw LocalFailure(std::to_string(crossing.size()) + " pairs of the result's " +
                         std::to_string(out.triangles.size()) +
                         " triangles cross: the operands lie on each other (or cross themselves)");
    if (!crossing.empty()) {
      std::vector<std::uint8_t> at(out.positions.size(), 0);
      for (const auto& pair : crossing)
        for (std::uint32_t t : pair)
          for (int k = 0; k < 3; ++k) at[out.triangles[t][k]] = 1;
      crossing = untangle(out, seam, gradient_of(node_field), T, near, 3, {}, at);
    }
    st.self_intersections = crossing.size();
    if (st.self_intersections == 0 || round == 2) break;
    Aabb hot;
    for (const auto& pair : crossing)
      for (std::uint32_t t : pair)
        for (int k = 0; k < 3; ++k) hot.grow(out.positions[out.triangles[t][k]]);
    edge *= 0.5;
    refine(a, hot.expanded(in.precision), edge);
    refine(b, hot.expanded(in.precision), edge);
  }
  // A triangle folded over beside the seam crosses nothing, so untangling does not see it; an
  // edge of it collapses (a seam point only into another), or its corners off the seam relax.
  unfold_folded(out, seam, gradient_of(node_field), T, false);
  // The seam's band through the quality pass, unless the seams are to be left as stitched
  // (LocalInput::remesh_seams) or the pass is off; where polishing made two triangles cross
  // (its steps are local), or folded a triangle over a neighbour (crossing nothing: a merge on
  // a knife-edge seam is held to each face's own normal, not to the other sheet), the stitched
  // band stays.
  if (in.remesh_seams && in.polygonize.quality.enabled && st.self_intersections == 0) {
    TriangleMesh stitched = out;
    std::vector<std::uint8_t> stitched_seam = seam;
    const std::size_t folds = folded_triangles(out, gradient_of(node_field)).size();
    polish_seam(out, seam, node_field, T, in.precision);
    if (!intersections_in(out, near).empty() || folded_triangles(out, gradient_of(node_field)).size() > folds)
      out = std::move(stitched), seam = std::move(stitched_seam);
  }
  return out;
}

// The field and support of a op b (min/max: the surface is the same under R-functions).
void fold_into(BooleanOperand& acc, const BooleanOperand& b, NodeKind kind, double T) {
  const BatchField fa = acc.field, fb = b.field;
  acc.field = [fa, fb, kind, T](std::span<const glm::dvec3> points, std::span<double> values) {
    std::vector<double> other(points.size());
    fa(points, values);
    fb(points, other);
    for (std::size_t k = 0; k < points.size(); ++k)
      values[k] = kind == NodeKind::Union          ? std::max(values[k], other[k])
                  : kind == NodeKind::Intersection ? std::min(values[k], other[k])
                                                   : std::max(0.0, std::min(values[k], 2.0 * T - other[k]));
  };
  if (kind == NodeKind::Union) acc.support = merge(acc.support, b.support);
  if (kind == NodeKind::Intersection) acc.support = intersect(acc.support, b.support);
}

}  // namespace

TriangleMesh trim_boolean(const LocalInput& in, LocalStats* stats) {
  LocalStats st;
  const Graph& g = *in.graph;
  const auto c = g.children_of(in.node);
  if (c.size() > kMaxLocalBooleanOperands)
    throw LocalFailure("a Boolean of " + std::to_string(c.size()) + " operands (local meshing folds at most " +
                       std::to_string(kMaxLocalBooleanOperands) + ")");
  const NodeKind kind = g.kind[in.node];
  const auto node_field = node_tape(in);
  // A left fold of binary steps, as the format defines the n-ary Booleans.
  auto operand_of = [&](std::size_t i) {
    const NodeField f(in, c[i], false);
    st.operand_triangles += operand(in, i).triangles.size();
    return BooleanOperand{RefinedMesh(operand(in, i),
                                      std::make_shared<const TapeEvaluator>(
                                          std::make_shared<const Tape>(compile_tape(in.graph, c[i], in.threshold))),
                                      in.threshold),
                          [f](std::span<const glm::dvec3> p, std::span<double> v) { f(p, v); }, f.support()};
  };
  BooleanOperand acc = operand_of(0);
  for (std::size_t i = 1; i < c.size(); ++i) {
    BooleanOperand b = operand_of(i);
    acc.shape = RefinedMesh(boolean_step(in, kind, acc, b, *node_field, st), in.threshold);
    if (st.self_intersections) break;
    fold_into(acc, b, kind, in.threshold);
  }
  if (stats) *stats = st;
  return std::move(acc.shape).release();
}

}  // namespace ht
