#include "meshers/local_parts.hpp"

#include "meshers/polygonize.hpp"
#include "meshers/quality.hpp"
#include "meshers/quality_whole.hpp"
#include "meshers/relax.hpp"
#include "meshers/submesh.hpp"
#include "meshers/warp_mesh.hpp"
#include "runtime/tape.hpp"

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <string>

namespace ht::local {


TriangleMesh RefinedMesh::step(const TriangleMesh& from, const Step& s, bool* stopped) const {
  WarpRemeshStats st;
  TriangleMesh out = warp_mesh(from, [](const glm::dvec3& p) { return p; }, surface_.get(), threshold_, s.edge, &st,
                               &s.region, s.only, s.max_triangles);
  if (stopped) *stopped = st.stopped;
  return out;
}

const TriangleMesh& RefinedMesh::mesh() {
  if (!source_ || made_) return mesh_;
  mesh_ = TriangleMesh();
  for (std::size_t k = 0; k < steps_.size(); ++k) mesh_ = step(k == 0 ? *source_ : mesh_, steps_[k]);
  if (steps_.empty()) mesh_ = *source_;
  made_ = true;
  return mesh_;
}

bool RefinedMesh::push(Step s) {
  bool stopped = false;
  if (!source_) {
    mesh_ = step(mesh_, s, &stopped);
    return !stopped;
  }
  mesh_ = step(steps_.empty() ? *source_ : mesh(), s, &stopped);
  steps_.push_back(std::move(s));
  made_ = true;
  return !stopped;
}

bool RefinedMesh::refine(const Aabb& region, double edge, std::size_t max_triangles) {
  return push({region, edge, {}, max_triangles});
}

void RefinedMesh::refine_near_seam(const Aabb& region, double edge, const BatchField& cut) {
  const TriangleMesh& from = source_ && steps_.empty() ? *source_ : mesh();
  std::vector<std::uint32_t> inside;
  for (std::uint32_t v = 0; v < from.positions.size(); ++v)
    if (region.contains(from.positions[v])) inside.push_back(v);
  std::vector<glm::dvec3> points(inside.size());
  for (std::size_t k = 0; k < inside.size(); ++k) points[k] = from.positions[inside[k]];
  std::vector<double> at(inside.size()), values(from.positions.size(), 0.0);
  if (!points.empty()) cut(points, at);
  for (std::size_t k = 0; k < inside.size(); ++k) values[inside[k]] = at[k];
  push({region, edge, near_seam(from, region, values, kCoarseEdges * edge)});
}

TriangleMesh RefinedMesh::release() && {
  mesh();
  return std::move(mesh_);
}

// Cuts snap vertices by at most kCutSnap of the precision, kCreaseCutSnap at a crease (see
// CutOptions::snap_distance).
CutOptions cut_options(const LocalInput& in, bool crease) {
  CutOptions o;
  // At a crease, 0.15 of the precision, not 0.1: more of the cut's slivers go (the made
  // triangles' smallest angles: carved_box 0.47 -> 1.63 degrees, the spiky snake-woman's 0.30 ->
  // 3.16, the OpenVDB peer's csg 0.64 -> 1.99; the largest face error -11% to +32%). Not where
  // a blend's band follows the cut: the bowl's smallest smooth angle fell 6.3 -> 3.3 degrees.
  // (Measured 2026-12-05, 1a4cd58.)
  o.snap_distance = (crease ? kCreaseCutSnap : kCutSnap) * in.precision;
  return o;
}

CutOptions rim_cut_options() {
  CutOptions o;
  o.snap = 0.0;
  o.refine_steps = 0;
  return o;
}

const TriangleMesh& operand(const LocalInput& in, std::size_t i) {
  if (i >= in.child_meshes.size() || !in.child_meshes[i])
    throw LocalFailure("operand " + std::to_string(i) + " has no mesh");
  return *in.child_meshes[i];
}

// A seam's triangles are those whose corners lie on both sides of the cut; a coarse triangle can
// hold a whole seam between its corners, so long edges count wherever they are.
std::vector<std::uint8_t> near_seam(const TriangleMesh& mesh, const Aabb& box, std::span<const double> values,
                                    double coarse) {
  std::vector<std::int8_t> side(mesh.positions.size(), 0);  // 0: outside the box
  for (std::size_t v = 0; v < side.size(); ++v)
    if (box.contains(mesh.positions[v])) side[v] = values[v] > 0 ? 1 : -1;
  std::vector<std::uint8_t> crossed(mesh.positions.size(), 0), any(mesh.positions.size(), 1),
      long_edge(mesh.positions.size(), 0);
  for (const glm::uvec3& t : mesh.triangles) {
    const int s0 = side[t[0]], s1 = side[t[1]], s2 = side[t[2]];
    if (s0 * s1 < 0 || s1 * s2 < 0 || s0 * s2 < 0)
      for (int k = 0; k < 3; ++k) crossed[t[k]] = 1;
    for (int k = 0; k < 3; ++k)
      if (glm::length(mesh.positions[t[k]] - mesh.positions[t[(k + 1) % 3]]) > coarse)
        long_edge[t[k]] = long_edge[t[(k + 1) % 3]] = 1;
  }
  std::vector<std::uint8_t> near = rings_around(mesh, crossed, any, kSeamRings);
  for (std::size_t v = 0; v < near.size(); ++v) near[v] = near[v] || crossed[v] || long_edge[v];
  return near;
}

TriangleMesh refined_and_cut(const TriangleMesh& mesh, const LocalInput& in, NodeId child, const Aabb& region,
                             const BatchField& cut) {
  std::vector<double> values(mesh.positions.size());
  if (!values.empty()) cut(mesh.positions, values);
  const TapeEvaluator field(std::make_shared<const Tape>(compile_tape(in.graph, child, in.threshold, nullptr, true)));
  const Aabb box = region.expanded(in.precision);
  const TriangleMesh r = warp_mesh(mesh, [](const glm::dvec3& p) { return p; }, &field, in.threshold, 1.5 * in.precision,
                                   nullptr, &box, near_seam(mesh, box, values, kCoarseEdges * 1.5 * in.precision));
  // The refinement keeps the vertices' order and appends the new ones: only those are evaluated.
  const std::size_t n = mesh.positions.size();
  values.resize(r.positions.size());
  if (r.positions.size() > n)
    cut(std::span(r.positions).subspan(n), std::span(values).subspan(n));
  CutOptions o = cut_options(in);
  o.snap_freely_from = n;
  return cut_mesh(r, values, cut, o);
}

void flip(TriangleMesh& m) {
  for (glm::uvec3& t : m.triangles) std::swap(t[1], t[2]);
}

bool overlaps(const Aabb& a, const Aabb& b) { return !intersect(a, b).empty(); }

namespace {

// The patch's cell size: the precision, or finer where the operands' meshes are finer inside
// the patch's box, so that both sides of a seam sample it alike (the paper: "a sampling rate
// that adapts to the length of the edges"). At most 2x finer: the patch is remeshed at that
// length, and 4x finer (as before) made a scan blended at a coarser precision cost 16 times the
// requested cells per area (the snake-woman's head: a patch of 98k triangles at h / 4, 0.50 of
// its 0.87 s) for a surface finer than asked.
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
  return std::clamp(lengths[lengths.size() / 2], 0.5 * in.precision, in.precision);
}

}  // namespace

// The surface of the node itself, polygonized only inside `clip`, in the bricks `wanted` accepts.
TriangleMesh patch(const LocalInput& in, const Aabb& clip, std::function<std::uint8_t(const Aabb&)> wanted,
                   LocalStats& st, bool sharp, std::span<const NodeId> operands) {
  PolygonizeOptions o = in.polygonize;
  o.region_operands.assign(operands.begin(), operands.end());
  o.sharp_features = o.sharp_features && sharp;
  o.precision = patch_precision(in, clip);
  st.patch_precision = o.precision;
  o.clip = clip;
  o.brick_filter = std::move(wanted);
  o.progress = {};
  st.patched = true;
  return polygonize(in.graph, in.node, in.threshold, o, &st.patch);
}

std::uint8_t octants_where(const Aabb& brick, double margin, const std::function<bool(const Aabb&)>& acts) {
  if (!acts(brick.expanded(margin))) return 0;
  std::uint8_t mask = 0;
  for (int k = 0; k < 8; ++k)
    if (acts(octants::of(brick, k).expanded(margin))) mask = std::uint8_t(mask | (1u << k));
  return mask;
}

// Seams of this node: gaps up to 3/4 of the precision; `onto_earlier` where the pieces meet
// smoothly, not at a crease (meshers/stitch.hpp). At a crease both cuts' points lie on the seam
// itself, so a weld slides a point along it: welding within 0.45 of the shorter boundary edge
// instead of 0.3 (less than half, so no point passes its neighbour) leaves fewer seam edges a
// hair long between the two cuts' points, each with a sliver on either side
// (examples/carved_box.json: the made triangles' first percentile 9.29 -> 11.22 degrees).
StitchOptions seam_options(const LocalInput& in, bool onto_earlier) {
  StitchOptions so;
  so.max_gap = 0.75 * in.precision;
  so.onto_earlier = onto_earlier;
  if (!onto_earlier) so.weld_fraction = kCreaseWeldFraction;
  return so;
}

// Stitches the non-empty pieces.
TriangleMesh join(std::vector<TriangleMesh>&& pieces, const StitchOptions& so, LocalStats& st,
                  std::vector<std::uint8_t>* seam) {
  std::erase_if(pieces, [](const TriangleMesh& p) { return p.triangles.empty(); });
  return stitch(std::move(pieces), so, &st.stitch, seam);
}

// The node's own field, where a result's vertices are projected back.
std::shared_ptr<const TapeEvaluator> node_tape(const LocalInput& in) {
  return std::make_shared<const TapeEvaluator>(std::make_shared<const Tape>(compile_tape(in.graph, in.node, in.threshold)));
}

SurfaceField node_surface(const LocalInput& in) {
  return SurfaceField(in.graph, in.node, in.threshold, glm::dvec3(0.0), kSurfaceBrickCells * in.precision);
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
void relax_band(TriangleMesh& m, std::uint32_t first_patch, const BatchGradient& field, double T) {
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

void polish_seam(TriangleMesh& out, std::vector<std::uint8_t>& seam, const TapeEvaluator& node_field, double T, double h) {
  seam.resize(out.positions.size(), 0);
  const std::vector<std::uint8_t> any(out.positions.size(), 1);
  const std::vector<std::uint8_t> band = rings_around(out, seam, any, kPolishRings);  // the seam not included
  // Only the triangles at the seam and its band are taken out (one ring more, locked, so that
  // the band's rings are whole): the rest of the mesh is not touched at all.
  std::vector<std::uint8_t> region = rings_around(out, seam, any, kPolishRings + 1);
  for (std::size_t v = 0; v < region.size(); ++v) region[v] |= seam[v];
  // Each seam's band is a part of its own (a Boolean's two seams, say), improved in parallel.
  Pieces pieces = take_region(out, region, true);
  if (pieces.parts.empty()) return;
  const BatchField field = [&node_field](std::span<const glm::dvec3> p, std::span<double> v) { node_field.field(p, v); };
  QualityOptions options;
  options.off_step_cells = kSeamOffStepCells;
  const std::size_t count = pieces.parts.size();
  std::vector<TriangleMesh> changed(count);
  std::vector<std::vector<std::uint32_t>> origin(count);
  tbb::parallel_for(std::size_t(0), count, [&](std::size_t i) {
    Submesh& part = pieces.parts[i];
    const std::size_t n = part.mesh.positions.size();
    std::vector<std::uint8_t> locked(n, 1), crease(n, 0);
    for (std::size_t v = 0; v < n; ++v) {
      const std::uint32_t w = part.origin[v];
      crease[v] = seam[w];
      if (!part.rim[v] && !seam[w] && band[w]) locked[v] = kNearCrease;
    }
    QualityStats st;
    changed[i] = std::move(part.mesh);
    improve_whole(changed[i], locked, crease, field, T, h, options, st, origin[i]);
    for (std::uint32_t& o : origin[i])
      if (o != ~0u) o = part.origin[o];
  });
  std::vector<std::uint32_t> renumber;
  const std::size_t before = out.positions.size();
  put_back(out, pieces, changed, origin, &renumber);
  std::vector<std::uint8_t> now(out.positions.size(), 0);
  for (std::size_t v = 0; v < before; ++v)
    if (renumber[v] != ~0u) now[renumber[v]] = seam[v];
  seam = std::move(now);
}

}  // namespace ht::local
