// The pieces the local strategies share (meshers/local_ops.hpp is their public face): fields of
// operands as batch functions, cut settings, operand refinement, the node's own patch, seam
// settings and stitching, the band's relaxation. Internal to meshers/local_*.cpp.
#pragma once

#include "meshers/cut.hpp"
#include "meshers/local_ops.hpp"
#include "meshers/surface_field.hpp"
#include "runtime/tape_eval.hpp"

#include <functional>
#include <limits>
#include <memory>
#include <span>
#include <vector>

namespace ht::local {

/// The side, in precisions, of the bricks the local strategies' fields are specialized to
/// (NodeField, node_surface()).
inline constexpr double kSurfaceBrickCells = 16.0;

// A node's field at points, exactly 0 outside its support box without evaluating there (most of
// a large mesh leaf lies outside a small operand's support), and inside it on tapes specialized
// to bricks of kSurfaceBrickCells precisions (SurfaceField). Copies share the bricks.
class NodeField {
 public:
  NodeField(const LocalInput& in, NodeId node, bool under_blend)
      : bricks_(std::make_shared<SurfaceField>(in.graph, node, in.threshold, glm::dvec3(0.0),
                                               kSurfaceBrickCells * in.precision, under_blend)),
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
    if (!inside.empty()) bricks_->values(inside, v);
    for (std::size_t k = 0; k < where.size(); ++k) values[where[k]] = v[k];
  }
  const Aabb& support() const { return support_; }

 private:
  std::shared_ptr<SurfaceField> bricks_;  // its values() may run from several threads at once
  Aabb support_;
};

/// Cuts snap vertices by at most kCutSnap of the precision, kCreaseCutSnap where the cut is a
/// crease (see CutOptions::snap_distance).
CutOptions cut_options(const LocalInput& in, bool crease = false);
/// For a blend patch's cut whose rim is then pulled back (meshers/bridge.hpp pull_back_boundary):
/// every triangle touching the cut goes, so where the new vertices sit on the crossing edges does
/// not matter and no roots are sought; nothing snaps (a snapped vertex would only lose its fan to
/// the pull-back as well). Not for a local blend's patch: there the snapped fans keep the bands
/// narrower than their limit on tests/test_local_ops.cpp's bunny on a perch.
CutOptions rim_cut_options();
/// Child i's mesh; throws LocalFailure when it has none.
const TriangleMesh& operand(const LocalInput& in, std::size_t i);
/// Rings of triangles around a cut's seam that its refinement covers.
inline constexpr int kSeamRings = 2;
/// Edges this many times the refinement's length are refined wherever they are: a seam can pass
/// through a coarse triangle between its corners without any of them seeing it.
inline constexpr double kCoarseEdges = 3.0;
/// The vertices within kSeamRings edges of a triangle whose corners inside `box` lie on both
/// sides of a cut's zero (`values`: the cut at each vertex), and the ends of edges longer than
/// `coarse`.
std::vector<std::uint8_t> near_seam(const TriangleMesh& mesh, const Aabb& box, std::span<const double> values,
                                    double coarse);
/// The operand's mesh (under a blend), its edges longer than 1.5 h split inside `region` widened
/// by h and near the seam `cut` makes (near_seam), new vertices projected onto the child's
/// surface, then cut (the part where cut < 0, as cut_mesh): a coarse mesh's long chords would
/// otherwise cut a curved seam short. Only near the seam: elsewhere the splits would only halve
/// the long sides of a scan's own thin triangles into thinner ones, outside the rings the bands'
/// remeshing reaches. Vertices already there stay bit for bit; the cut is evaluated once at each.
TriangleMesh refined_and_cut(const TriangleMesh& mesh, const LocalInput& in, NodeId child, const Aabb& region,
                             const BatchField& cut);
/// A Boolean operand's mesh, refined step by step (edges longer than `edge` split inside
/// `region`, new vertices projected with `surface`, as warp_mesh does) from a source it does not
/// copy. Between uses it may be dropped and is then made again by replaying the refinements
/// (warp_mesh is deterministic: the same bytes), so that a big child's mesh is not held twice
/// while the pieces are joined and searched. Without a source it owns its mesh (an earlier
/// step's result, refined at midpoints) and dropping does nothing. Not thread-safe.
class RefinedMesh {
 public:
  /// `source` must outlive this.
  RefinedMesh(const TriangleMesh& source, std::shared_ptr<const TapeEvaluator> surface, double threshold)
      : source_(&source), surface_(std::move(surface)), threshold_(threshold) {}
  RefinedMesh(TriangleMesh owned, double threshold) : threshold_(threshold), mesh_(std::move(owned)) {}

  /// False when the refinement would make more than `max_triangles` (then it stopped there, with
  /// edges still longer than `edge`: warp_mesh's cap).
  bool refine(const Aabb& region, double edge, std::size_t max_triangles = std::numeric_limits<std::size_t>::max());
  /// The same, but only near the seam `cut` makes inside `region` (near_seam, with long edges
  /// at kCoarseEdges * edge): splitting elsewhere would only halve a scan's own long thin
  /// triangles into slivers the seam never reaches. `cut` is evaluated at the vertices in
  /// `region` once; the flags are kept so that a replay splits the same edges.
  void refine_near_seam(const Aabb& region, double edge, const BatchField& cut);
  /// The mesh after every refinement so far (made again if it was dropped).
  const TriangleMesh& mesh();
  void drop() {
    if (!source_) return;
    mesh_ = TriangleMesh();
    made_ = false;
  }
  TriangleMesh release() &&;

 private:
  struct Step {
    Aabb region;
    double edge;
    std::vector<std::uint8_t> only;  // empty: every vertex
    std::size_t max_triangles = std::numeric_limits<std::size_t>::max();
  };
  TriangleMesh step(const TriangleMesh& from, const Step& s, bool* stopped = nullptr) const;
  bool push(Step s);
  const TriangleMesh* source_ = nullptr;
  std::shared_ptr<const TapeEvaluator> surface_;
  double threshold_;
  TriangleMesh mesh_;
  std::vector<Step> steps_;  // with a source: each refinement, to replay
  bool made_ = false;                           // mesh_ holds every step
};
/// Turns every triangle over.
void flip(TriangleMesh& m);
bool overlaps(const Aabb& a, const Aabb& b);
/// The node's own surface, polygonized only inside `clip`, in the bricks `wanted` accepts, at
/// the operands' edge length there (at most 2x finer than h), sharp features only if `sharp`.
/// `operands`, when not empty, are the blend's (PolygonizeOptions::region_operands): only cells
/// where two of them act are meshed.
TriangleMesh patch(const LocalInput& in, const Aabb& clip, std::function<std::uint8_t(const Aabb&)> wanted,
                   LocalStats& st, bool sharp, std::span<const NodeId> operands = {});
/// The octants of `brick` (octants::of) on which `acts`, given an octant's box widened by
/// `margin`, may be true; none when it may not be on the whole brick widened so. A patch's
/// filter: the interval bounds it rests on loosen with the box.
std::uint8_t octants_where(const Aabb& brick, double margin, const std::function<bool(const Aabb&)>& acts);
/// How far a cut may move an operand's own vertex onto its root, in precisions
/// (CutOptions::snap_distance): along a blend's seam, and along a crease (Booleans, crops).
inline constexpr double kCutSnap = 0.1, kCreaseCutSnap = 0.15;
/// StitchOptions::weld_fraction at creases (below 1/2: a welded point cannot pass its neighbour).
inline constexpr double kCreaseWeldFraction = 0.45;
/// Seams of this node: gaps up to 3/4 of the precision; `onto_earlier` where the pieces meet
/// smoothly, not at a crease (meshers/stitch.hpp); at a crease welds reach kCreaseWeldFraction.
StitchOptions seam_options(const LocalInput& in, bool onto_earlier);
/// Stitches the non-empty pieces, taking them (freed as they are copied in); `seam` as in stitch().
TriangleMesh join(std::vector<TriangleMesh>&& pieces, const StitchOptions& so, LocalStats& st,
                  std::vector<std::uint8_t>* seam = nullptr);
/// The node's own field, where a result's vertices are projected back.
std::shared_ptr<const TapeEvaluator> node_tape(const LocalInput& in);

/// A seam's band through the quality pass (meshers/quality.hpp): the triangles within
/// kPolishRings + 1 rings of a `seam` vertex (one flag per vertex; resized to the mesh) are taken
/// out and improved as the polygonizer's are beside a crease. The seam's points are the crease
/// points (their chains evened along the seam, meshers/quality_creases.cpp), the kPolishRings rings
/// around them move and collapse with every step measured against `field` (threshold T, each
/// collapse's or flip's faces within kSeamOffStepCells precisions h of the surface), the ring
/// beyond is locked; the triangles away from the seam stay bit for bit. The stitch and the cuts
/// leave seam points wherever the operands' edges cross the seam, however close together: this
/// evens them (examples/carved_box.json's made triangles' first percentile 14.3 -> 24.4
/// degrees). `seam` receives the flags renumbered. Sequential; deterministic.
inline constexpr int kPolishRings = 2;
inline constexpr double kSeamOffStepCells = 0.01;
void polish_seam(TriangleMesh& mesh, std::vector<std::uint8_t>& seam, const TapeEvaluator& field, double T, double h);
/// The same field on tapes specialized to bricks of kSurfaceBrickCells precisions (on a lattice
/// through the origin, compiled as points reach them): what the passes that move many vertices
/// (relaxation, remeshing, untangling) evaluate, since the node's whole tape pays for every
/// primitive of a big tree at every point.
SurfaceField node_surface(const LocalInput& in);
/// The operands' pieces as one mesh, in the order bridge() lays them out.
TriangleMesh join_operands(const std::vector<const TriangleMesh*>& ops);
/// Evens out a band: the patch's vertices along it (those from `first_patch` on that share a
/// triangle with an operand's) and one ring behind them relax, projected onto the node's surface.
void relax_band(TriangleMesh& m, std::uint32_t first_patch, const BatchGradient& field, double T);
std::size_t count_triangles(const std::vector<TriangleMesh>& pieces);

}  // namespace ht::local
