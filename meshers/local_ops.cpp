#include "meshers/local_ops.hpp"

#include "meshers/cut.hpp"
#include "meshers/relax.hpp"
#include "meshers/warp_mesh.hpp"
#include "meshers/bridge.hpp"
#include "meshers/caps.hpp"
#include "nodes/operators.hpp"
#include "runtime/tape.hpp"
#include "runtime/tape_eval.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace ht {
namespace {

// A node's field at points, exactly 0 outside its support box without running the tape there
// (most of a large mesh leaf lies outside a small operand's support).
class NodeField {
 public:
  NodeField(const LocalInput& in, NodeId node, bool under_blend)
      : eval_(std::make_shared<const TapeEvaluator>(
            std::make_shared<const Tape>(compile_tape(in.graph, node, in.threshold, nullptr, under_blend)))),
        support_(in.graph->support(node, under_blend)) {}

  void operator()(std::span<const glm::dvec3> points, std::span<double> values) const {
    std::vector<glm::dvec3> inside;
    std::vector<std::size_t> where;
    for (std::size_t i = 0; i < points.size(); ++i) {
      values[i] = 0.0;
      if (support_.contains(points[i])) {
        inside.push_back(points[i]);
        where.push_back(i);
      }
    }
    std::vector<double> v(inside.size());
    if (!inside.empty()) eval_->field(inside, v);
    for (std::size_t k = 0; k < where.size(); ++k) values[where[k]] = v[k];
  }
  const Aabb& support() const { return support_; }

 private:
  std::shared_ptr<const TapeEvaluator> eval_;
  Aabb support_;
};


// Cuts snap vertices by at most a tenth of the precision (see CutOptions::snap_distance).
CutOptions cut_options(const LocalInput& in) {
  CutOptions o;
  o.snap_distance = 0.1 * in.precision;
  return o;
}

const TriangleMesh& operand(const LocalInput& in, std::size_t i) {
  if (i >= in.child_meshes.size() || !in.child_meshes[i])
    throw LocalFailure("operand " + std::to_string(i) + " has no mesh");
  return *in.child_meshes[i];
}

// The operand's mesh with its edges longer than the precision split where `region` says the
// other operands act (new vertices projected onto the operand's own surface): a coarse mesh's
// long chords would otherwise cut a curved seam short. Vertices already there stay bit for bit.
TriangleMesh refined(const TriangleMesh& mesh, const LocalInput& in, NodeId child, bool under_blend, const Aabb& region,
                     double max_edge = 0.0) {
  const TapeEvaluator field(std::make_shared<const Tape>(compile_tape(in.graph, child, in.threshold, nullptr, under_blend)));
  const Aabb box = region.expanded(in.precision);
  return warp_mesh(mesh, [](const glm::dvec3& p) { return p; }, &field, in.threshold,
                   max_edge > 0 ? max_edge : 1.5 * in.precision, nullptr, &box);
}

void flip(TriangleMesh& m) {
  for (glm::uvec3& t : m.triangles) std::swap(t[1], t[2]);
}

bool overlaps(const Aabb& a, const Aabb& b) { return !intersect(a, b).empty(); }

// The patch's cell size: the precision, or finer where the operands' meshes are finer inside
// the patch's box, so that both sides of a seam sample it alike (the paper: "a sampling rate
// that adapts to the length of the edges"). At most 4x finer.
double patch_precision(const LocalInput& in, const Aabb& box) {
  std::vector<double> lengths;
  for (const auto& m : in.child_meshes) {
    if (!m) continue;
    for (const glm::uvec3& t : m->triangles) {
      const glm::dvec3 a = m->positions[t[0]], b = m->positions[t[1]], c = m->positions[t[2]];
      if (!box.contains((a + b + c) / 3.0)) continue;
      lengths.push_back((glm::length(b - a) + glm::length(c - b) + glm::length(a - c)) / 3.0);
    }
  }
  if (lengths.empty()) return in.precision;
  std::nth_element(lengths.begin(), lengths.begin() + std::ptrdiff_t(lengths.size() / 2), lengths.end());
  return std::clamp(lengths[lengths.size() / 2], 0.25 * in.precision, in.precision);
}

// The surface of the node itself, polygonized only inside `clip`, in the bricks `wanted` accepts.
TriangleMesh patch(const LocalInput& in, const Aabb& clip, std::function<bool(const Aabb&)> wanted, LocalStats& st,
                   bool sharp) {
  PolygonizeOptions o = in.polygonize;
  o.sharp_features = o.sharp_features && sharp;
  o.precision = patch_precision(in, clip);
  o.clip = clip;
  o.brick_filter = std::move(wanted);
  o.progress = {};
  st.patched = true;
  return polygonize(in.graph, in.node, in.threshold, o, &st.patch);
}

// Seams of this node: gaps up to 3/4 of the precision; `onto_earlier` where the pieces meet
// smoothly, not at a crease (meshers/stitch.hpp).
StitchOptions seam_options(const LocalInput& in, bool onto_earlier) {
  StitchOptions so;
  so.max_gap = 0.75 * in.precision;
  so.onto_earlier = onto_earlier;
  return so;
}

// Stitches the non-empty pieces.
TriangleMesh join(const std::vector<TriangleMesh>& pieces, const StitchOptions& so, LocalStats& st,
                  std::vector<std::uint8_t>* seam = nullptr) {
  std::vector<const TriangleMesh*> ptrs;
  for (const TriangleMesh& p : pieces)
    if (!p.triangles.empty()) ptrs.push_back(&p);
  return stitch(ptrs, so, &st.stitch, seam);
}

// The node's own field, where a result's vertices are projected back.
std::shared_ptr<const TapeEvaluator> node_tape(const LocalInput& in) {
  return std::make_shared<const TapeEvaluator>(std::make_shared<const Tape>(compile_tape(in.graph, in.node, in.threshold)));
}

// The operands' pieces as one mesh, in the order bridge() lays them out.
TriangleMesh join_operands(const std::vector<const TriangleMesh*>& ops) {
  TriangleMesh m;
  for (const TriangleMesh* p : ops) append(m, *p);
  return m;
}

// Evens out the band: the patch's vertices along it and one ring behind them move toward their
// neighbours' centroid within the tangent plane and back onto the node's surface. The operands'
// vertices stay where they are.
void relax_band(TriangleMesh& m, std::uint32_t first_patch, const TapeEvaluator& field, double T) {
  std::vector<std::uint8_t> band(m.positions.size(), 0), patch(m.positions.size(), 0);
  for (const glm::uvec3& t : m.triangles) {
    const bool mixed = (t[0] < first_patch || t[1] < first_patch || t[2] < first_patch) &&
                       (t[0] >= first_patch || t[1] >= first_patch || t[2] >= first_patch);
    if (mixed)
      for (int k = 0; k < 3; ++k) band[t[k]] |= t[k] >= first_patch;
  }
  for (std::size_t v = first_patch; v < m.positions.size(); ++v) patch[v] = 1;
  std::vector<std::uint8_t> movable = rings_around(m, band, patch, 1);
  for (std::size_t v = 0; v < m.positions.size(); ++v) movable[v] |= band[v];
  relax_vertices(m, movable, field, T);
}

std::size_t count_triangles(const std::vector<TriangleMesh>& pieces) {
  std::size_t n = 0;
  for (const TriangleMesh& p : pieces) n += p.triangles.size();
  return n;
}

}  // namespace

double blend_overlap(const Graph& g, NodeId n) {
  const auto c = g.children_of(n);
  auto volume = [](const Aabb& b) { return b.empty() ? 0.0 : b.size().x * b.size().y * b.size().z; };
  double rho = 0.0;
  for (std::size_t i = 0; i < c.size(); ++i)
    for (std::size_t j = i + 1; j < c.size(); ++j) {
      const Aabb& a = g.support(c[i], true);
      const Aabb& b = g.support(c[j], true);
      if (!a.finite() || !b.finite()) return 1.0;
      const double both = volume(intersect(a, b)), either = volume(a) + volume(b) - both;
      if (either > 0) rho = std::max(rho, both / either);
    }
  return rho;
}

namespace {

// An operand of one Boolean step: its mesh, its field, where that field may be non-zero, and the
// tape that projects the vertices its refinement adds (the operand's own; none for the result of
// earlier steps, whose refinement splits at midpoints: no single surface is its own).
struct BooleanOperand {
  TriangleMesh mesh;
  BatchField field;
  Aabb support;
  std::shared_ptr<const TapeEvaluator> surface;
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
  auto refine = [&](BooleanOperand& o, const Aabb& region, double edge) {
    o.mesh = warp_mesh(o.mesh, [](const glm::dvec3& p) { return p; }, o.surface.get(), T, edge, nullptr, &region);
  };
  double edge = 1.5 * in.precision;
  refine(a, meet.expanded(in.precision), edge);
  refine(b, meet.expanded(in.precision), edge);
  TriangleMesh out;
  for (int round = 0;; ++round) {
    std::vector<TriangleMesh> pieces;
    pieces.push_back(cut_mesh(a.mesh, keep_a_outside ? shifted(b.field, 1, -T) : shifted(b.field, -1, T), cut_options(in)));
    pieces.push_back(cut_mesh(b.mesh, keep_b_outside ? shifted(a.field, 1, -T) : shifted(a.field, -1, T), cut_options(in)));
    if (kind == NodeKind::Difference) flip(pieces[1]);
    st.kept_triangles = count_triangles(pieces);
    std::vector<std::uint8_t> seam;
    out = join(pieces, seam_options(in, false), st, &seam);
    // The seam is the crease: it stays. Only where the operands meet can the result intersect.
    st.self_intersections = untangle(out, seam, node_field, T, near);
    if (st.self_intersections == 0 || round == 2) break;
    Aabb hot;
    for (const auto& pair : intersections_in(out, near))
      for (std::uint32_t t : pair)
        for (int k = 0; k < 3; ++k) hot.grow(out.positions[out.triangles[t][k]]);
    edge *= 0.5;
    refine(a, hot.expanded(in.precision), edge);
    refine(b, hot.expanded(in.precision), edge);
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
    return BooleanOperand{operand(in, i), [f](std::span<const glm::dvec3> p, std::span<double> v) { f(p, v); }, f.support(),
                          std::make_shared<const TapeEvaluator>(
                              std::make_shared<const Tape>(compile_tape(in.graph, c[i], in.threshold)))};
  };
  BooleanOperand acc = operand_of(0);
  for (std::size_t i = 1; i < c.size(); ++i) {
    BooleanOperand b = operand_of(i);
    acc.mesh = boolean_step(in, kind, acc, b, *node_field, st);
    if (st.self_intersections) break;
    fold_into(acc, b, kind, in.threshold);
    acc.surface = nullptr;
  }
  if (stats) *stats = st;
  return std::move(acc.mesh);
}

namespace {

// The operands' fields of a blend and the cut functions built from them. With
// g_i = sum over j != i of |f_j|: an operand's mesh is kept where g_i < eps (nothing else acts
// there), the patch where every g_i >= eps.
class BlendFields {
 public:
  BlendFields(const LocalInput& in, std::span<const NodeId> children) : eps(1e-3 * in.threshold) {
    for (NodeId child : children) fields.emplace_back(in, child, true);
  }
  /// g_i - eps for operand i; eps - min_i g_i for i == size() (the patch's cut).
  BatchField cut(std::size_t i) const {
    return [this, i](std::span<const glm::dvec3> points, std::span<double> values) {
      const std::size_t n = points.size();
      std::vector<double> total(n, 0.0), largest(n, 0.0), own(n, 0.0), f(n);
      for (std::size_t j = 0; j < fields.size(); ++j) {
        fields[j](points, f);
        for (std::size_t k = 0; k < n; ++k) {
          total[k] += std::abs(f[k]);
          largest[k] = std::max(largest[k], std::abs(f[k]));
          if (j == i) own[k] = std::abs(f[k]);
        }
      }
      for (std::size_t k = 0; k < n; ++k)
        values[k] = i < fields.size() ? (total[k] - own[k]) - eps : eps - (total[k] - largest[k]);
    };
  }
  /// Where two operands' supports meet, widened by `margin`; `clip` receives their union.
  std::vector<Aabb> meets(double margin, Aabb& clip) const {
    std::vector<Aabb> out;
    for (std::size_t i = 0; i < fields.size(); ++i)
      for (std::size_t j = i + 1; j < fields.size(); ++j) {
        const Aabb both = intersect(fields[i].support(), fields[j].support());
        if (!both.empty()) out.push_back(both.expanded(margin)), clip = merge(clip, out.back());
      }
    return out;
  }

  /// Below eps an operand's field moves the others' surfaces by at most eps / |grad f|.
  const double eps;
  std::vector<NodeField> fields;
};

// The blend's own surface where two operands act, cut to where every g_i >= eps, pulled back
// one ring and its loops straightened: the far side of the bands.
TriangleMesh blend_patch(const LocalInput& in, const BlendFields& bf, const std::vector<Aabb>& meets, const Aabb& clip,
                         const TapeEvaluator& field, LocalStats& st) {
  const Graph* graph = in.graph.get();
  const auto c = graph->children_of(in.node);
  const double margin = 2.0 * in.precision, T = in.threshold, eps = bf.eps;
  // Only bricks where two operands may both reach eps (interval analysis), two cells wider.
  const TriangleMesh p = patch(in, clip, [meets, graph, c, eps, margin, T](const Aabb& brick) {
    if (std::none_of(meets.begin(), meets.end(), [&](const Aabb& m) { return overlaps(m, brick); })) return false;
    const Aabb wide = brick.expanded(margin);
    int acting = 0;
    for (NodeId child : c) {
      const Interval iv = field_interval(*graph, child, T, wide, true);
      acting += iv.hi >= eps || iv.lo <= -eps;
    }
    return acting >= 2;
  }, st, false);  // a blend is smooth where operands meet
  TriangleMesh side = pull_back_boundary(cut_mesh(p, bf.cut(c.size()), cut_options(in)));
  relax_boundary(side, field, T);
  st.patch_triangles = side.triangles.size();
  return side;
}

// The operands' trimmed meshes and the patch joined by bands, evened out and untangled.
TriangleMesh close_with_bands(const std::vector<TriangleMesh>& pieces, const TriangleMesh& side, const Aabb& clip,
                              const TapeEvaluator& field, const LocalInput& in, LocalStats& st) {
  std::vector<const TriangleMesh*> ops;
  for (const TriangleMesh& piece : pieces)
    if (!piece.triangles.empty()) ops.push_back(&piece);
  std::uint32_t first_patch = 0;
  TriangleMesh out = bridge(ops, side, 8.0 * in.precision, &st.bridge, &first_patch);
  relax_band(out, first_patch, field, in.threshold);
  // The operands' trimmed edges stay; everything else may move to undo a fold.
  std::vector<std::uint8_t> fixed(out.positions.size(), 0);
  for (const auto& loop : boundary_loops(join_operands(ops)))
    for (std::uint32_t v : loop) fixed[v] = 1;
  st.self_intersections = untangle(out, fixed, field, in.threshold, clip);
  return out;
}

}  // namespace

TriangleMesh trim_blend(const LocalInput& in, LocalStats* stats) {
  LocalStats st;
  const auto c = in.graph->children_of(in.node);
  if (c.size() > kMaxLocalBlendOperands)
    throw LocalFailure("a blend of " + std::to_string(c.size()) + " operands (local meshing takes at most " +
                       std::to_string(kMaxLocalBlendOperands) + ")");
  const BlendFields bf(in, c);
  Aabb clip;
  const std::vector<Aabb> meets = bf.meets(2.0 * in.precision, clip);
  std::vector<TriangleMesh> pieces;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (i >= in.child_meshes.size() || !in.child_meshes[i] || in.child_meshes[i]->triangles.empty()) continue;
    const TriangleMesh& m = *in.child_meshes[i];
    st.operand_triangles += m.triangles.size();
    pieces.push_back(cut_mesh(clip.empty() ? m : refined(m, in, c[i], true, clip), bf.cut(i), cut_options(in)));
  }
  st.kept_triangles = count_triangles(pieces);
  TriangleMesh out;
  if (meets.empty()) {
    out = join(pieces, seam_options(in, true), st);  // nothing meets: the operands' meshes as they are
  } else {
    const auto field = node_tape(in);
    out = close_with_bands(pieces, blend_patch(in, bf, meets, clip, *field, st), clip, *field, in, st);
  }
  if (stats) *stats = st;
  return out;
}

TriangleMesh trim_local_blend(const LocalInput& in, LocalStats* stats) {
  LocalStats st;
  const auto c = in.graph->children_of(in.node);  // a, b, region
  const double T = in.threshold, eps = 1e-3;      // fR blends fully at 1
  const NodeField fa(in, c[0], true), fb(in, c[1], true), fr(in, c[2], true);
  // Keep an operand where the other does not reach it (the union's part) and R does not act.
  auto keep = [&fr, T, eps](const NodeField& other) -> BatchField {
    return [other, fr, T, eps](std::span<const glm::dvec3> points, std::span<double> values) {
      std::vector<double> r(points.size());
      other(points, values);
      fr(points, r);
      for (std::size_t k = 0; k < points.size(); ++k) values[k] = std::max(values[k] - T, r[k] - eps);
    };
  };
  const Aabb both = intersect(fa.support(), fb.support());
  const Aabb acts = intersect(fr.support(), merge(fa.support(), fb.support())).expanded(2.0 * in.precision);
  const Aabb near = merge(both, acts);
  std::vector<TriangleMesh> pieces;
  pieces.push_back(cut_mesh(refined(operand(in, 0), in, c[0], true, near), keep(fb), cut_options(in)));
  pieces.push_back(cut_mesh(refined(operand(in, 1), in, c[1], true, near), keep(fa), cut_options(in)));
  st.operand_triangles = operand(in, 0).triangles.size() + operand(in, 1).triangles.size();
  st.kept_triangles = count_triangles(pieces);
  // The union's crease is welded exactly (a tighter gap: where R acts the pieces part, and
  // their boundary there stays open for the bands).
  StitchOptions so = seam_options(in, false);
  so.max_gap = 0.3 * in.precision;
  so.allow_open = true;
  const TriangleMesh joined = join(pieces, so, st);
  TriangleMesh out;
  if (st.stitch.left_open == 0 || acts.empty()) {
    out = joined;
    st.self_intersections = intersections_in(out, near.expanded(2.0 * in.precision)).size();
  } else {
    // The blended part: the node's surface where R may act, cut to where it does.
    const Graph* graph = in.graph.get();
    const NodeId region = c[2];
    const double margin = 2.0 * in.precision;
    const TriangleMesh p = patch(in, acts, [graph, region, T, eps, margin](const Aabb& brick) {
      return field_interval(*graph, region, T, brick.expanded(margin), true).hi >= eps;
    }, st, true);  // where the region fades out the surface turns into the union's crease
    const BatchField in_region = [fr, eps](std::span<const glm::dvec3> points, std::span<double> values) {
      fr(points, values);
      for (double& v : values) v = eps - v;
    };
    const auto field = node_tape(in);
    TriangleMesh side = pull_back_boundary(cut_mesh(p, in_region, cut_options(in)));
    relax_boundary(side, *field, T);
    st.patch_triangles = side.triangles.size();
    out = close_with_bands({joined}, side, acts, *field, in, st);
  }
  if (stats) *stats = st;
  return out;
}

TriangleMesh trim_crop(const LocalInput& in, LocalStats* stats) {
  LocalStats st;
  const double* box6 = in.graph->params_of(in.node).data();
  const Aabb box{{box6[0], box6[1], box6[2]}, {box6[3], box6[4], box6[5]}};
  st.operand_triangles = operand(in, 0).triangles.size();
  TriangleMesh out = operand(in, 0);
  // One face at a time: cut by its plane, then close the openings, which all lie in that plane,
  // with planar caps. The next plane cuts those caps too, along the box's edge, so openings
  // that cross an edge of the box come out as two caps meeting on it.
  for (int face = 0; face < 6; ++face) {
    const int axis = face / 2;
    const bool hi = face % 2 == 1;
    const double at = hi ? box.hi[axis] : box.lo[axis], sign = hi ? 1.0 : -1.0;
    const BatchField plane = [axis, at, sign](std::span<const glm::dvec3> points, std::span<double> values) {
      for (std::size_t k = 0; k < points.size(); ++k) values[k] = sign * (points[k][axis] - at);
    };
    if (std::none_of(out.positions.begin(), out.positions.end(), [&](const glm::dvec3& p) { return sign * (p[axis] - at) >= 0; }))
      continue;
    out = cut_mesh(out, plane, cut_options(in));
    CapStats caps;
    try {
      cap_box_openings(out, box, 1e-6 * std::max(1.0, glm::length(box.size())), &caps);
    } catch (const CapError& e) {
      throw LocalFailure(e.what());
    }
    st.patch_triangles += caps.triangles;
  }
  st.kept_triangles = out.triangles.size() - st.patch_triangles;
  // Only the cut and its caps are new: look for intersections next to the box's faces.
  st.self_intersections = intersections_in(out, box.expanded(2.0 * in.precision)).size();
  if (stats) *stats = st;
  return out;
}

}  // namespace ht
