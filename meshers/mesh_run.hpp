// One meshing run as the command line and the embedding API (runtime/api.hpp) make it: the
// precision and strategy a scene asks for, the mesh plan (meshers/mesh_plan.hpp), the checks of
// what it returns (meshers/mesh_checks.hpp, surface error included) and the statistics document
// (`hybridtree mesh --stats-json`, the API's MeshStats::json). Both front ends call this, so a
// scene meshed from C++, Python or the shell gives the same mesh and the same figures.
#pragma once

#include "meshers/disk_cache.hpp"
#include "meshers/mesh_checks.hpp"
#include "meshers/mesh_plan.hpp"
#include "runtime/tree.hpp"

#include <atomic>
#include <functional>
#include <optional>
#include <string>

namespace ht {

/// The precision a scene asks for: `requested` when > 0, else the scene's mesher.precision, else
/// 1/100 of its solid's size (1 for an unbounded or empty solid).
double default_precision(const Tree& tree, double requested);

/// Throws PolygonizeError (saying what to use instead) when the solid reaches past kMaxCoordinate
/// (meshers/polygonize.hpp unmeshable_extent), when `precision` is finer than doubles resolve
/// where the solid lies (unresolvable_precision) or coarser than the box
/// the scene's solid lies in is across: no part of the surface could be resolved, and the mesh
/// would come out empty or meaningless. run_mesh() checks it.
void check_precision(const Tree& tree, double precision);

/// Throws FloatRangeError (runtime/tape.hpp) when a number some node's field needs does not hold
/// as a float, compiling every subtree free of unprepared ffds. run_mesh() checks it first.
void check_float_range(const Tree& tree);

struct MeshRunOptions {
  double precision = 0.0;   ///< edge length, world units; 0: default_precision()
  std::string strategy;     ///< "auto", "global" or "local"; empty: the scene's mesher.strategy
  double memory_gib = 4.0;  ///< the run's memory budget (runtime/memory_budget.hpp), GiB
  bool sharp_features = true;
  bool quality = true;
  std::function<void(double)> progress;     ///< as MeshOptions::progress
  const std::atomic<bool>* cancel = nullptr;  ///< as MeshOptions::cancel
  /// As MeshOptions::cache (not owned). With a disk level (NodeCache::disk()), the run trims
  /// the folder to its bound (DiskCache::trim) when it has meshed.
  NodeCache* cache = nullptr;
  /// The checks' costly part: the self-intersecting pairs (a search of the whole mesh) and the
  /// surface error (the field at every vertex and face centre). Without it `checks` holds the
  /// topology, shapes and volume, self_intersecting_pairs 0 and no surface error.
  bool full_checks = true;
};

struct MeshRun {
  MeshOptions options;       ///< what the plan ran with
  std::string strategy;      ///< "auto", "global" or "local"
  MeshResult result;         ///< the mesh (never null) and one report per job
  MeshChecks checks;         ///< of result.mesh; with full_checks, surface error included when it is not empty
  std::optional<DiskCacheStats> disk;  ///< with a disk level: what this run counted there
  double mesh_seconds = 0.0, check_seconds = 0.0;
};

/// Meshes the tree's root and checks the result. Throws what mesh_tree() throws (PolygonizeError,
/// MeshCancelled, MemoryBudgetError, CompileError). Calls on one tree from several threads are
/// independent.
MeshRun run_mesh(const Tree& tree, const MeshRunOptions& options);

/// "trim blend (low overlap)": the strategy of the root's job and why.
std::string root_strategy(const MeshRun& run, NodeId root);

/// The statistics as JSON text (2-space indent, ending in a newline), the document `hybridtree
/// mesh --stats-json` writes: per node the strategy, why, triangles and seconds; the checks; the
/// polygonizer's bricks, crease, snap and quality figures; seconds per stage; with a node cache,
/// "cache": {"hits", "misses", "reused_nodes": [labels]} (jobs reused, jobs run), and with its
/// disk level "disk": {"hits", "misses", "written", "write_failures", "evicted", "ignored":
/// {reason: files}} (reasons as to_string(DiskIgnore), those that occurred). `output` and
/// `write_seconds` are left out when `output` is empty (nothing was written yet).
std::string mesh_stats_json(const Tree& tree, const MeshRun& run, const std::string& scene, double load_seconds,
                            const std::string& output = {}, double write_seconds = 0.0);

}  // namespace ht
