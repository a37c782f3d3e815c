#include "meshers/ffd.hpp"

#include "meshers/mesh_plan.hpp"
#include "meshers/polygonize.hpp"
#include "meshers/self_intersections.hpp"
#include "meshers/unfold.hpp"
#include "meshers/warp_mesh.hpp"
#include "runtime/tape_eval.hpp"
#include "nodes/mesh_leaf.hpp"
#include "nodes/warps.hpp"
#include "runtime/graph_writer.hpp"
#include "runtime/node_params.hpp"

#include <tbb/parallel_invoke.h>

#include <array>
#include <exception>
#include <limits>
#include <string>
#include <vector>

namespace ht {
namespace {

constexpr int kUnfoldRounds = 8;

void collect(const Graph& g, NodeId n, std::vector<std::uint8_t>& seen) {
  if (seen[n]) return;
  seen[n] = 1;
  for (NodeId c : g.children_of(n)) collect(g, c, seen);
}

}  // namespace

bool needs_ffd_preparation(const Graph& g, NodeId root) {
  std::vector<std::uint8_t> seen(g.size(), 0);
  collect(g, root, seen);
  for (NodeId n = 0; n < g.size(); ++n)
    if (seen[n] && params::ffd_unprepared(g, n)) return true;
  return false;
}

// Edges a lattice stretches more than this many times its median are across a tear (see
// warp_mesh): a smooth lattice that stretches one part of the child 32 times more than the rest
// is extreme, and its edges there stay long.
constexpr double kFfdTearStretch = 32.0;

std::shared_ptr<const MeshLeaf> deform_child_mesh(const std::shared_ptr<const Graph>& graph, NodeId n,
                                                  const TriangleMesh& child_mesh, double max_edge, double threshold,
                                                  std::size_t* crossing, MemoryBudget* budget) {
  const Graph& g = *graph;
  if (child_mesh.triangles.empty())
    throw PolygonizeError("ffd node " + g.label(n) + ": its child's surface is empty, there is nothing to deform");
  TriangleMesh mesh;
  if (max_edge > 0) {
    // Edges the lattice stretches are split (new vertices on the child's surface) before they
    // are moved, so a strongly bent region is not spanned by long flat triangles that cut into
    // their neighbours.
    const TapeEvaluator child_field(std::make_shared<const Tape>(compile_tape(graph, g.children_of(n)[0], threshold)));
    const std::size_t room =
        budget ? std::size_t(double(budget->limit() - std::min(budget->in_use(), budget->limit())) / kDeformedBytesPerTriangle)
               : std::numeric_limits<std::size_t>::max();
    WarpRemeshStats ws;
    mesh = warp_mesh(child_mesh, forward_map(g, n), &child_field, threshold, max_edge, &ws, nullptr, {}, room,
                     kFfdTearStretch);
    if (ws.stopped) {
      const double bytes = kDeformedBytesPerTriangle * (double(room) + 1.0);
      throw MemoryBudgetError("the deformed mesh of ffd node " + g.label(n) + " (more than " + std::to_string(room) +
                                  " triangles) needs " + format_bytes(bytes) + ", over the memory budget of " +
                                  format_bytes(double(budget->limit())),
                              std::size_t(bytes), budget->in_use(), budget->limit());
    }
  } else {
    mesh = child_mesh;
    const double* params = g.params_of(n).data();
    for (glm::dvec3& v : mesh.positions) v = warp_forward(NodeKind::Ffd, params, v);
  }
  // A fold the child's mesh all but made (two sheets of a thin band a hair apart) can close
  // under the lattice; its intersecting triangles give up edges (meshers/unfold.hpp). The search
  // and the mesh leaf that takes it to find nothing are built side by side (the leaf's build is
  // mostly serial); when it does find pairs, the leaf is built again from the unfolded mesh.
  const std::string name = "deformed mesh of ffd node " + g.label(n);
  auto build = [&name](std::vector<glm::dvec3> p, std::vector<glm::uvec3> t, bool intersection_free,
                       MeshInside inside = MeshInside::Closed) {
    try {
      return MeshLeaf::from_triangles(std::move(p), std::move(t), name, false, inside, intersection_free);
    } catch (const MeshError& e) {
      throw PolygonizeError(e.what());
    }
  };
  std::vector<std::array<std::uint32_t, 2>> pairs;
  std::shared_ptr<const MeshLeaf> leaf;
  std::exception_ptr failed;
  tbb::parallel_invoke([&] { pairs = find_self_intersections(mesh, std::numeric_limits<std::size_t>::max()).examples; },
                       [&] {
                         try {
                           leaf = build(mesh.positions, mesh.triangles, true);
                         } catch (...) {
                           failed = std::current_exception();
                         }
                       });
  if (crossing) *crossing = 0;
  if (pairs.empty()) {
    if (failed) std::rethrow_exception(failed);
    return leaf;
  }
  std::vector<std::uint8_t> no_crease;
  unfold(mesh, no_crease, pairs, kUnfoldRounds);
  if (crossing) *crossing = pairs.size();
  // `pairs` now holds every intersecting pair left; with none, MeshLeaf need not search again.
  // With some, ray parity and pseudo-normals disagree about the inside where the mesh crosses
  // itself (a torn lattice's whole outside came out inside): the winding number decides there.
  return build(std::move(mesh.positions), std::move(mesh.triangles), pairs.empty(),
               pairs.empty() ? MeshInside::Closed : MeshInside::Winding);
}

std::shared_ptr<const Graph> attach_ffd_mesh(const Graph& graph, NodeId n, std::shared_ptr<const MeshLeaf> leaf) {
  GraphWriter writer(graph);
  writer.attach_mesh(n, std::move(leaf));
  return std::make_shared<const Graph>(writer.take());
}

std::shared_ptr<const Graph> attach_empty_ffd(const Graph& graph, NodeId n) {
  GraphWriter writer(graph);
  writer.empty_ffd(n);
  return std::make_shared<const Graph>(writer.take());
}

Tree prepare_ffd(const Tree& tree, double precision) {
  MeshOptions o;
  o.precision = precision;
  return prepare_fields(tree, o);
}

}  // namespace ht
