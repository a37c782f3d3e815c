// Trimmed blends and local blends (meshers/local_ops.hpp): operands cut where others act, the
// node's own surface polygonized only there, joined by bands.
#include "meshers/local_ops.hpp"

#include "meshers/local_parts.hpp"
#include "meshers/brick_extract.hpp"
#include "meshers/bridge.hpp"
#include "meshers/edges.hpp"
#include "meshers/relax.hpp"
#include "meshers/remesh.hpp"
#include "meshers/unfold.hpp"
#include "runtime/interval.hpp"
#include "runtime/tape.hpp"

#include <glm/common.hpp>
#include <glm/vector_relational.hpp>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <array>
#include <functional>
#include <numeric>
#include <cmath>
#include <mutex>
#include <span>
#include <string>
#include <tuple>
#include <vector>

namespace ht {

using namespace local;

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

// The operands' fields of a blend and the cut functions built from them. With
// g_i = sum over j != i of |f_j|: an operand's mesh is kept where g_i < eps (nothing else acts
// there), the patch where every g_i >= eps.
class BlendFields {
 public:
  BlendFields(const LocalInput& in, std::span<const NodeId> children) : eps(1e-3 * in.threshold) {
    for (NodeId child : children) fields.emplace_back(in, child, true);
  }
  /// g_i - eps for operand i; eps - min_i g_i for i == size() (the patch's cut). Operand i's
  /// cut reads the others only: its own field, often a mesh leaf's distance queries at each of
  /// its vertices, is not evaluated.
  BatchField cut(std::size_t i) const {
    return [fields = fields, eps = eps, i](std::span<const glm::dvec3> points, std::span<double> values) {
      const std::size_t n = points.size();
      std::vector<double> total(n, 0.0), largest(n, 0.0), f(n);
      for (std::size_t j = 0; j < fields.size(); ++j) {
        if (j == i) continue;
        fields[j](points, f);
        for (std::size_t k = 0; k < n; ++k) {
          total[k] += std::abs(f[k]);
          largest[k] = std::max(largest[k], std::abs(f[k]));
        }
      }
      for (std::size_t k = 0; k < n; ++k) values[k] = i < fields.size() ? total[k] - eps : eps - (total[k] - largest[k]);
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

// The patch's octants where the operands but the largest add up to at least 2 eps on the whole
// box one cell wider: the patch's cut keeps every vertex there and no edge from one crosses it
// (an edge stays within that box), so their cut values need not be computed; any negative value
// reads the same (meshers/cut.hpp reads values at the ends of crossing edges only).
class DeepOctants {
 public:
  void add(const Aabb& octant) {
    const std::lock_guard lock(mutex_);
    boxes_.push_back(octant);
  }
  /// The cut's values at the patch's vertices: -eps strictly inside a deep octant, else `cut`'s.
  std::vector<double> cut_values(const TriangleMesh& patch, const BatchField& cut, double eps) const {
    const std::size_t n = patch.positions.size();
    std::vector<std::uint8_t> deep(n, 0);
    if (!boxes_.empty()) {
      // The octants lie on one lattice: their corners' offsets from the lowest corner, in sides.
      const double side = boxes_.front().size().x;
      glm::dvec3 origin = boxes_.front().lo;
      for (const Aabb& b : boxes_) origin = glm::min(origin, b.lo);
      std::vector<glm::i64vec3> keys;
      for (const Aabb& b : boxes_) keys.push_back(glm::i64vec3(glm::round((b.lo - origin) / side)));
      const auto less = [](const glm::i64vec3& a, const glm::i64vec3& b) {
        return std::tie(a.x, a.y, a.z) < std::tie(b.x, b.y, b.z);
      };
      std::sort(keys.begin(), keys.end(), less);
      tbb::parallel_for(std::size_t(0), n, [&](std::size_t v) {
        const glm::dvec3 q = (patch.positions[v] - origin) / side, at = glm::floor(q), f = q - at;
        // On an octant's face (or within rounding of it) the vertex may belong to its neighbour.
        if (glm::any(glm::lessThan(f, glm::dvec3(1e-6))) || glm::any(glm::greaterThan(f, glm::dvec3(1.0 - 1e-6)))) return;
        deep[v] = std::binary_search(keys.begin(), keys.end(), glm::i64vec3(at), less);
      });
    }
    std::vector<glm::dvec3> asked;
    for (std::size_t v = 0; v < n; ++v)
      if (!deep[v]) asked.push_back(patch.positions[v]);
    std::vector<double> answers(asked.size()), values(n, -eps);
    cut(asked, answers);
    for (std::size_t v = 0, i = 0; v < n; ++v)
      if (!deep[v]) values[v] = answers[i++];
    return values;
  }

 private:
  std::mutex mutex_;
  std::vector<Aabb> boxes_;  // in no particular order (filled in parallel); read sorted
};

// The blend's own surface where two operands act, cut to where every g_i >= eps, pulled back
// one ring and its loops straightened: the far side of the bands.
TriangleMesh blend_patch(const LocalInput& in, const BlendFields& bf, const std::vector<Aabb>& meets, const Aabb& clip,
                         const BatchGradient& field, LocalStats& st) {
  const Graph* graph = in.graph.get();
  const auto c = graph->children_of(in.node);
  const double T = in.threshold, eps = bf.eps;
  // The patch's cut keeps where the operands' |f| but the largest add up to eps: so may they in
  // a box where their bounds on |f| (interval analysis) do. Tested on the octants of each brick,
  // one of the patch's cells wider (the cut's crossing edges lie in octants whose closed boxes
  // the region reaches; the margin is for rounding): on whole bricks two cells wider, 42 to 88%
  // of the patch's triangles on the examples lay where the cut then took them away. An octant
  // whose blend field (the sum of the operands', so its range is the sum of their ranges) lies on
  // one side of T holds no crossing edge, and is left out too: no triangle changes, a vertex
  // beside it may move within the refinement's tolerance (its first guess reads the points past
  // its edge's ends; tests/test_polygonize.cpp LeavingOutOneSidedOctantsChangesNoTriangle).
  // Whether an octant's box (widened) is kept, and whether it is deep (DeepOctants). A lower
  // bound of what all but the largest |f| add up to: the bounds' sum less the largest bound.
  // The children cheapest to bound first (by subtree size): all but the last bounding the sum of
  // the |f| but the largest from above, a box they leave under eps is turned down before the
  // costliest child's interval is taken (the wings beside a body of 250 curves).
  std::vector<std::size_t> order(c.size());
  std::iota(order.begin(), order.end(), std::size_t(0));
  std::vector<std::size_t> size(graph->size(), 0);
  const std::function<std::size_t(NodeId)> count = [&](NodeId n) {
    std::size_t k = 1;
    for (NodeId ch : graph->children_of(n)) k += count(ch);
    return size[n] = k;
  };
  for (NodeId child : c) count(child);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return size[c[a]] < size[c[b]]; });
  auto test = [graph, c, order, eps, T](const Aabb& box, bool& deep) {
    deep = false;
    std::array<Interval, kMaxLocalBlendOperands> iv{};  // c.size() of them (trim_blend checks)
    double known = 0.0;
    for (std::size_t k = 0; k < order.size(); ++k) {
      // The sum of all |f| but the largest is at most the sum of those known so far.
      if (k + 1 == order.size() && k > 0 && known < eps) return false;
      iv[order[k]] = field_interval(*graph, c[order[k]], T, box, true);
      known += std::max(iv[order[k]].hi, -iv[order[k]].lo);
    }
    // Summed in the children's order.
    double sum = 0.0, largest = 0.0, least_sum = 0.0, least_largest = 0.0;
    Interval blend;
    for (const Interval& i : std::span(iv).first(c.size())) {
      const double bound = std::max(i.hi, -i.lo), least = i.lo > 0 ? i.lo : i.hi < 0 ? -i.hi : 0.0;
      sum += bound;
      largest = std::max(largest, bound);
      least_sum += least;
      least_largest = std::max(least_largest, least);
      blend = interval::add(blend, i);
    }
    deep = least_sum - least_largest >= 2.0 * eps;
    return sum - largest >= eps && blend.lo < T && blend.hi >= T;
  };
  DeepOctants deep_octants;
  const TriangleMesh p = patch(in, clip, [meets, test, &deep_octants](const Aabb& brick) -> std::uint8_t {
    if (std::none_of(meets.begin(), meets.end(), [&](const Aabb& m) { return overlaps(m, brick); })) return 0;
    const double cell = brick.size().x / brick::kCells;  // one of the patch's cells
    bool deep = false;
    if (!test(brick.expanded(cell), deep)) return 0;
    std::uint8_t mask = 0;
    for (int k = 0; k < 8; ++k) {
      const Aabb octant = octants::of(brick, k);
      if (!test(octant.expanded(cell), deep)) continue;
      mask = std::uint8_t(mask | (1u << k));
      if (deep) deep_octants.add(octant);
    }
    return mask;
  }, st, false, c);  // a blend is smooth where operands meet; only where two act is kept
  const BatchField cut = bf.cut(c.size());
  TriangleMesh side = pull_back_boundary(cut_mesh(p, deep_octants.cut_values(p, cut, eps), cut, rim_cut_options()));
  relax_boundary(side, field, T);
  st.patch_triangles = side.triangles.size();
  return side;
}

// The operands' trimmed meshes and the patch joined by bands, evened out and untangled. Takes
// the pieces and the patch: they are freed once joined, before the remeshing's own scratch.
// `crease` flags the points of a crease among the pieces' vertices, in bridge() order (a local
// blend's union seam; empty for a trim blend's smooth result): followed through the remeshing
// (which keeps sharp creases of its own accord, and may move points of shallow ones), they
// collapse only into one another while folded triangles are mended, and the crease's band goes
// through the quality pass last (local::polish_seam).
TriangleMesh close_with_bands(std::vector<TriangleMesh>&& pieces, TriangleMesh&& side, const Aabb& clip,
                              const BatchGradient& field, const LocalInput& in, LocalStats& st,
                              std::vector<std::uint8_t> crease) {
  // Where a piece's boundary touches itself, bridge() cannot pair it: those fans go, and the
  // band reaches a ring further there.
  std::vector<std::uint8_t> kept_crease;
  std::size_t first = 0;
  for (TriangleMesh& piece : pieces) {
    if (piece.triangles.empty()) continue;
    const std::size_t n = piece.positions.size();
    std::vector<std::uint32_t> renumber;
    drop_pinched_fans(piece, &renumber);
    if (!crease.empty()) {
      const std::size_t at = kept_crease.size();
      kept_crease.resize(at + piece.positions.size(), 0);
      for (std::size_t v = 0; v < n; ++v)
        if (renumber[v] != ~0u) kept_crease[at + renumber[v]] = crease[first + v];
    }
    first += n;
  }
  if (!crease.empty()) crease = std::move(kept_crease);
  std::vector<const TriangleMesh*> ops;
  for (const TriangleMesh& piece : pieces)
    if (!piece.triangles.empty()) ops.push_back(&piece);
  std::uint32_t first_patch = 0;
  TriangleMesh out = bridge(ops, side, 8.0 * in.precision, &st.bridge, &first_patch);
  std::vector<TriangleMesh>().swap(pieces);
  side = TriangleMesh();
  relax_band(out, first_patch, field, in.threshold);
  crease.resize(out.positions.size(), 0);  // the patch's vertices are no crease points
  Aabb changed;
  if (in.remesh_seams) {
    // The patch, its bands and two rings of the operands beside them are remeshed: the bands'
    // and the patch's slivers go. The rest of the operands stays.
    std::vector<std::uint8_t> region(out.positions.size(), 0), band(out.positions.size(), 0), ops_only(out.positions.size(), 0);
    for (std::size_t v = first_patch; v < out.positions.size(); ++v) region[v] = 1;
    for (const glm::uvec3& t : out.triangles) {
      const bool mixed = std::min({t[0], t[1], t[2]}) < first_patch && std::max({t[0], t[1], t[2]}) >= first_patch;
      if (mixed)
        for (int k = 0; k < 3; ++k) band[t[k]] = 1;
    }
    for (std::size_t v = 0; v < first_patch; ++v) ops_only[v] = 1;
    const std::vector<std::uint8_t> near = rings_around(out, band, ops_only, 2);
    for (std::size_t v = 0; v < out.positions.size(); ++v) region[v] = region[v] || band[v] || near[v];
    RemeshOptions ro;  // at the operands' own edge length there, as the patch was made
    ro.target = st.patch_precision > 0 ? st.patch_precision : in.precision;
    for (std::size_t v = 0; v < out.positions.size(); ++v)
      if (region[v]) changed.grow(out.positions[v]);
    std::vector<std::uint32_t> renumber;
    remesh_region(out, region, std::vector<std::uint8_t>(out.positions.size(), 0), field, in.threshold, ro, &st.remesh,
                  &renumber);
    std::vector<std::uint8_t> moved(out.positions.size(), 0);
    for (std::size_t v = 0; v < renumber.size(); ++v)
      if (renumber[v] != ~0u) moved[renumber[v]] = crease[v];
    crease = std::move(moved);
  }
  // Look for intersections wherever the strategy or the remeshing changed the mesh.
  changed = merge(changed.expanded(in.precision), clip);
  // The crease points are not held to their crease here: sliding them toward their crease
  // neighbours' midpoint left crossings that free relaxation undid (a twisted box's junction
  // with a sphere), in a campaign of 110 local blends.
  st.self_intersections = untangle(out, std::vector<std::uint8_t>(out.positions.size(), 0), field, in.threshold, changed).size();
  // A triangle folded over crosses nothing, so untangling does not see it: an edge of it
  // collapses (a crease point only into another). One left is a defect the global polygonizer
  // does not have: the blend falls back.
  if (std::find(crease.begin(), crease.end(), 1) == crease.end()) crease.clear();
  const UnfoldStats folds = unfold_folded(out, crease, field, in.threshold, false);
  if (folds.pairs_after > 0) throw LocalFailure(std::to_string(folds.pairs_after) + " triangles folded over in the bands");
  if (!crease.empty() && in.remesh_seams && in.polygonize.quality.enabled && st.self_intersections == 0) {
    // The union's crease as welded keeps its operands' edges where they crossed it, however
    // close together; polished as a trim Boolean's seams are (the stitched one stays where the
    // polish made triangles cross or fold).
    TriangleMesh stitched = out;
    polish_seam(out, crease, *node_tape(in), in.threshold, in.precision);
    if (!intersections_in(out, changed).empty() || !folded_triangles(out, field).empty()) out = std::move(stitched);
  }
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
  auto cut_operands = [&] {
    for (std::size_t i = 0; i < c.size(); ++i) {
      if (i >= in.child_meshes.size() || !in.child_meshes[i] || in.child_meshes[i]->triangles.empty()) continue;
      const TriangleMesh& m = *in.child_meshes[i];
      st.operand_triangles += m.triangles.size();
      const BatchField cut = bf.cut(i);
      pieces.push_back(clip.empty() ? cut_mesh(m, cut, cut_options(in)) : refined_and_cut(m, in, c[i], clip, cut));
    }
    st.kept_triangles = count_triangles(pieces);
  };
  TriangleMesh out;
  if (meets.empty()) {
    cut_operands();
    out = join(std::move(pieces), seam_options(in, true), st);  // nothing meets: the operands' meshes as they are
  } else {
    SurfaceField surface = node_surface(in);
    const BatchGradient field = gradient_of(surface);
    // The patch reads the fields only, the operands' cuts their meshes: the two run side by
    // side, each filling the other's serial stretches (separate statistics, merged after).
    TriangleMesh side;
    LocalStats patch_stats;
    tbb::parallel_invoke(cut_operands, [&] { side = blend_patch(in, bf, meets, clip, field, patch_stats); });
    st.patched = patch_stats.patched;
    st.patch_precision = patch_stats.patch_precision;
    st.patch = patch_stats.patch;
    st.patch_triangles = patch_stats.patch_triangles;
    out = close_with_bands(std::move(pieces), std::move(side), clip, field, in, st, {});
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
  pieces.push_back(refined_and_cut(operand(in, 0), in, c[0], near, keep(fb)));
  pieces.push_back(refined_and_cut(operand(in, 1), in, c[1], near, keep(fa)));
  st.operand_triangles = operand(in, 0).triangles.size() + operand(in, 1).triangles.size();
  st.kept_triangles = count_triangles(pieces);
  // The union's crease is welded exactly (a tighter gap: where R acts the pieces part, and
  // their boundary there stays open for the bands).
  StitchOptions so = seam_options(in, false);
  so.max_gap = 0.3 * in.precision;
  so.allow_open = true;
  std::vector<std::uint8_t> seam;  // the union's crease, one flag per vertex of `joined`
  TriangleMesh joined = join(std::move(pieces), so, st, &seam);
  // stitch() flags every vertex of a piece's rim; where R acts the rim stays open for the bands,
  // and those are no crease points.
  for (const BoundaryEdge& e : boundary_edges(joined)) seam[e.from] = seam[e.to] = 0;
  SurfaceField surface = node_surface(in);
  const BatchGradient field = gradient_of(surface);
  TriangleMesh out;
  if (st.stitch.left_open == 0 || acts.empty()) {
    out = std::move(joined);
    st.self_intersections = intersections_in(out, near.expanded(2.0 * in.precision)).size();
    // As a trim Boolean's seam: a triangle folded over beside the crease is mended.
    unfold_folded(out, seam, field, T, false);
  } else {
    // The blended part: the node's surface where R may act, cut to where it does.
    const Graph* graph = in.graph.get();
    const NodeId region = c[2];
    const double margin = 2.0 * in.precision;
    const TriangleMesh p = patch(in, acts, [graph, region, T, eps, margin](const Aabb& brick) {
      return octants_where(brick, margin,
                           [&](const Aabb& box) { return field_interval(*graph, region, T, box, true).hi >= eps; });
    }, st, true);  // where the region fades out the surface turns into the union's crease
    const BatchField in_region = [fr, eps](std::span<const glm::dvec3> points, std::span<double> values) {
      fr(points, values);
      for (double& v : values) v = eps - v;
    };
    TriangleMesh side = pull_back_boundary(cut_mesh(p, in_region, cut_options(in)));
    relax_boundary(side, field, T);
    st.patch_triangles = side.triangles.size();
    std::vector<TriangleMesh> joined_pieces;
    joined_pieces.push_back(std::move(joined));
    // Crossings are looked for (and untangled) along the union's crease too, not only where R acts:
    // two operands meeting at a grazing angle cross there (a ring touching bunny00's chest).
    out = close_with_bands(std::move(joined_pieces), std::move(side), near, field, in, st, std::move(seam));
  }
  // A folded triangle left over is a defect the global polygonizer does not have: the node falls back.
  const std::size_t folded = folded_triangles(out, field).size();
  if (folded > 0) throw LocalFailure(std::to_string(folded) + " triangles folded over in the bands");
  if (stats) *stats = st;
  return out;
}

}  // namespace ht
