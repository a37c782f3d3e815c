// The passes over a global polygonization's extracted mesh after its vertices are joined and
// snapped (meshers/polygonize.cpp): the crease step and the quality pass, and the unfolding of
// what either leaves intersecting. Internal to the polygonizer. Single-threaded callers; the
// passes run their own parallel loops.
#pragma once

#include "meshers/features.hpp"
#include "meshers/polygonize.hpp"
#include "meshers/quality.hpp"
#include "meshers/surface_field.hpp"
#include "runtime/aabb.hpp"
#include "runtime/graph.hpp"
#include "runtime/memory_budget.hpp"
#include "runtime/tape.hpp"
#include "runtime/tape_eval.hpp"

#include <glm/vec3.hpp>

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace ht {

// The root's tape, compiled the first time a phase needs it.
struct RootField {
  std::shared_ptr<const Graph> graph;
  NodeId root;
  double T;
  std::shared_ptr<const TapeEvaluator> eval;
  const TapeEvaluator& get() {
    if (!eval) eval = std::make_shared<const TapeEvaluator>(std::make_shared<const Tape>(compile_tape(graph, root, T)));
    return *eval;
  }
};

/// Creases: the edges that cross them split (meshers/features.hpp, `normals` per vertex from the
/// extraction); where the pieces fold into each other, crease points slide along their crease
/// and the vertices away from it relax (meshers/relax.hpp untangle), and what stays folded is
/// collapsed (meshers/unfold.hpp). `on_crease` holds the snapped crease points and receives the
/// step's too, one flag per vertex of the result. Triangles folded over without crossing anything
/// are collapsed too (meshers/unfold.hpp unfold_folded).
void crease_phase(RootField& field, const FeatureOptions& features, double h, TriangleMesh& mesh,
                  const std::vector<glm::vec3>& normals, std::vector<std::uint8_t>& on_crease, PolygonizeStats& stats);

/// What a polygonization's quality phase asks of a second run: boxes whose vertices it keeps as
/// extracted, around intersecting pairs the pass left (`crossing`: the second run's result is
/// taken) or triangles it left folded over (the better of the two runs is taken).
struct RetryRequest {
  std::vector<Aabb> boxes;
  bool crossing = false;
};

/// The quality pass (meshers/quality.hpp) on the bricks' own tapes, crease points kept, the
/// vertices inside the `locks` boxes kept where extraction put them; what it leaves intersecting
/// is unfolded, and triangles folded over are collapsed (meshers/unfold.hpp unfold_folded).
/// Returns, when `locks` is empty and pairs or folds are left, boxes around them: the caller
/// runs the pass again from the extracted mesh with those as `locks`.
RetryRequest quality_phase(SurfaceField& field, RootField& root_field, double h, const QualityOptions& options,
                           MemoryBudget& budget, TriangleMesh& mesh, const std::vector<std::uint8_t>& on_crease,
                           const QualityReuse* reuse, std::span<const Aabb> locks, PolygonizeStats& stats);

}  // namespace ht
