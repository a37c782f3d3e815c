#include "meshers/local_parts.hpp"

#include "meshers/relax.hpp"
#include "meshers/warp_mesh.hpp"
#include "runtime/tape.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <string>

namespace ht::local {


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
                     double max_edge) {
  const TapeEvaluator field(std::make_shared<const Tape>(compile_tape(in.graph, child, in.threshold, nullptr, under_blend)));
  const Aabb box = region.expanded(in.precision);
  return warp_mesh(mesh, [](const glm::dvec3& p) { return p; }, &field, in.threshold,
                   max_edge > 0 ? max_edge : 1.5 * in.precision, nullptr, &box);
}

void flip(TriangleMesh& m) {
  for (glm::uvec3& t : m.triangles) std::swap(t[1], t[2]);
}

bool overlaps(const Aabb& a, const Aabb& b) { return !intersect(a, b).empty(); }

namespace {

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

}  // namespace

// The surface of the node itself, polygonized only inside `clip`, in the bricks `wanted` accepts.
TriangleMesh patch(const LocalInput& in, const Aabb& clip, std::function<bool(const Aabb&)> wanted, LocalStats& st,
                   bool sharp) {
  PolygonizeOptions o = in.polygonize;
  o.sharp_features = o.sharp_features && sharp;
  o.precision = patch_precision(in, clip);
  st.patch_precision = o.precision;
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
                  std::vector<std::uint8_t>* seam) {
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

}  // namespace ht::local
