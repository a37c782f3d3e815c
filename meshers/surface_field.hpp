// The field of one node near its surface, at the cost of the tapes specialized to small boxes.
//
// The root tape of a big tree pays for every primitive at every point; the polygonizer instead
// specializes a tape to each brick it meshes (runtime/tape.hpp), a few instructions long. The
// passes that move vertices after meshing (meshers/quality.hpp) evaluate the field at every
// vertex several times, so they use the same bricks: points are binned by the brick that holds
// them and each bin is evaluated with that brick's tape. The polygonizer hands its tapes over;
// bricks nobody handed over are compiled on first use.
//
// A brick's tape equals the node's tape inside the brick, so the result does not depend on which
// bricks exist; it is the same at any thread count.
//
// Thread safety: values() runs in parallel inside and may be called from several threads at
// once (bricks met for the first time are compiled outside a lock and filed under it).
#pragma once

#include "runtime/graph.hpp"

#include <glm/vec3.hpp>

#include <cstdint>
#include <memory>
#include <shared_mutex>
#include <span>
#include <unordered_map>
#include <vector>

namespace ht {

class TapeEvaluator;
struct Tape;

class SurfaceField {
 public:
  /// Bricks of side `brick` (world units, > 0) on a lattice through `origin`. `under_blend` as in
  /// compile_tape().
  SurfaceField(std::shared_ptr<const Graph> graph, NodeId root, double threshold, glm::dvec3 origin, double brick,
               bool under_blend = false);
  ~SurfaceField();
  SurfaceField(const SurfaceField&) = delete;
  SurfaceField& operator=(const SurfaceField&) = delete;

  /// Takes a tape already specialized to brick `b` (origin + b * brick, side brick).
  void adopt(glm::ivec3 b, std::shared_ptr<const Tape> tape);

  /// The field at each point; values has points.size() entries.
  void values(std::span<const glm::dvec3> points, std::span<double> values);
  /// The field (when values is not empty) and its gradient at each point.
  void gradient(std::span<const glm::dvec3> points, std::span<double> values, std::span<glm::dvec3> gradients);

  double threshold() const { return threshold_; }
  std::size_t bricks() const {
    const std::shared_lock lock(mutex_);
    return evaluators_.size();
  }

 private:
  /// Points sorted by brick, the runs of each brick, and each run's evaluator (compiled if new).
  struct Bins {
    std::vector<std::pair<std::uint64_t, std::uint32_t>> order;
    std::vector<std::size_t> runs;  ///< run r is order[runs[r], runs[r + 1])
    std::vector<const TapeEvaluator*> eval;
  };
  Bins bin(std::span<const glm::dvec3> points);
  std::uint64_t key_of(const glm::dvec3& p) const;
  std::shared_ptr<const Graph> graph_;
  NodeId root_;
  double threshold_;
  glm::dvec3 origin_;
  double brick_;
  bool under_blend_;
  mutable std::shared_mutex mutex_;  // guards evaluators_
  std::unordered_map<std::uint64_t, std::unique_ptr<TapeEvaluator>> evaluators_;
};

}  // namespace ht
