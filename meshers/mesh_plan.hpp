// The mesh plan: one job per node that the result needs, run on a TBB flow graph (the paper,
// sections 3.1-3.3; the ARCHITECTURE's "mesh plan").
//
// Planning walks the tree from the root once and gives every node it reaches one job, indexed
// by node id, so a subtree used twice is meshed once. A job waits for the jobs it reads:
//   shared leaf     a mesh leaf's own mesh (shared, not copied); no inputs
//   sweep           a primitive's sweep mesh (meshers/sweep.hpp); if the tube overlaps itself
//                   (a curve that comes back near itself) the job polygonizes instead
//   warped child    the child's mesh moved by the warp, stretched edges split
//   deformed child  an ffd: the child's mesh deformed by the lattice becomes the ffd's mesh and
//                   its field (meshers/ffd.hpp); every job whose field reads the ffd waits for it
//   trim blend / Boolean / crop / local blend   the local strategies (meshers/local_ops.hpp) on
//                   the children's meshes; the result is checked (closed, manifold, oriented,
//                   no degenerate triangle, no self-intersection) and, failing that, the node is
//                   polygonized globally and the report says why
//   global          the polygonizer on the node's subtree (meshers/polygonize.hpp); the
//                   subtree's own nodes need no jobs, except the ffds its field reads
// A blend is trimmed when its overlap ratio rho is at most MeshOptions::blend_overlap, else
// polygonized; walking from the root, the first blend whose rho is too high takes its whole
// subtree. Per-node `mesher` hints win over the requested strategy.
//
// Independent subtrees run in parallel. The mesh is the same, byte for byte, at any thread
// count: every job is deterministic and reads only its inputs.
#pragma once

#include "meshers/local_ops.hpp"
#include "meshers/polygonize.hpp"
#include "meshers/triangle_mesh.hpp"
#include "runtime/tree.hpp"

#include <atomic>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ht {

class NodeCache;

/// The strategy asked for: each node's own (auto), polygonize everything at the root (global),
/// or the local strategy wherever one exists (local).
enum class MeshStrategy : std::uint8_t { Auto, Global, Local };

/// What a job did.
enum class JobStrategy : std::uint8_t {
  SharedLeaf, Sweep, WarpedChild, DeformedChild, Global, TrimBlend, TrimBoolean, TrimCrop, TrimLocalBlend,
  Empty  ///< the node's solid is surely empty (runtime/tape.hpp solid_empty): no mesh; below the
         ///< root, only the ffds under it are prepared (a parent may evaluate its field)
};
/// Why it did that.
enum class JobReason : std::uint8_t {
  Kind,           ///< the node kind's own strategy
  Hint,           ///< the node's `mesher` hint
  Requested,      ///< the requested strategy (MeshOptions::strategy)
  LowOverlap,     ///< a blend with rho <= blend_overlap
  HighOverlap,    ///< a blend with rho > blend_overlap
  NoLocalMethod,  ///< no local strategy for this node (n-ary Booleans, blends of many operands)
  WindingLeaf,    ///< a mesh leaf with "inside": "winding": its own mesh is not its solid's surface
                  ///< (polygonized), unless it is after all (SharedLeaf: meshers/winding_surface.hpp)
  Fallback,       ///< the local strategy failed; see NodeReport::fallback_cause
  EmptyBounds,    ///< the node's solid is surely empty by its bounds or strengths (JobStrategy::Empty)
  UnboundedOperand,  ///< an operand's own solid is unbounded (no mesh to trim): polygonized
};
const char* to_string(JobStrategy s);
const char* to_string(JobReason r);

struct NodeReport {
  NodeId node = kNone;
  JobStrategy strategy = JobStrategy::Global;
  JobReason reason = JobReason::Kind;
  double rho = -1.0;               ///< blends: the overlap ratio; -1 elsewhere
  std::string fallback_cause;      ///< with JobReason::Fallback: what the local strategy hit
  std::size_t triangles = 0;
  double seconds = 0.0;
  bool polygonized = false;        ///< the polygonizer ran (global, or a local patch)
  PolygonizeStats polygonize;      ///< its statistics
  LocalStats local;                ///< trim strategies
  std::size_t edges_split = 0;     ///< warped child: local remeshing
  /// Global polygonizations redone at kRefineFactor times the precision, each with what the
  /// coarser one left (its grid under-resolved the surface): "precision P: N degenerate triangles".
  std::vector<std::string> refinements;
  bool reused = false;             ///< taken from MeshOptions::cache; the job did not run
};

/// At most this many finer tries of a global polygonization whose repair left defects.
inline constexpr int kRefinements = 3;
inline constexpr double kRefineFactor = 0.9;

struct MeshOptions {
  double precision = 0.0;  ///< target edge length, world units; > 0
  MeshStrategy strategy = MeshStrategy::Auto;
  double blend_overlap = 0.5;  ///< the paper's rho threshold
  /// Memory budget, sharp features and vertex refinement of every polygonizer run (precision,
  /// progress and cancel are set from the fields here). The budget is the whole run's: the mesh
  /// leaves, every polygonizer grid and quality pass, and every node mesh the plan keeps take
  /// from one MemoryBudget (polygonize.budget, else one of polygonize.memory_budget bytes). A
  /// node's mesh is dropped and given back once the jobs that read it are done (not the root's).
  PolygonizeOptions polygonize;
  /// The fraction of the work done, non-decreasing, ending at 1. Calls are serialized but may
  /// come from any thread.
  std::function<void(double)> progress;
  /// Polled between jobs and inside the polygonizer; when it reads true the run throws
  /// MeshCancelled (meshers/polygonize.hpp).
  const std::atomic<bool>* cancel = nullptr;
  /// Remesh what the local strategies make (blend patches and bands, meshers/remesh.hpp).
  bool remesh_seams = true;
  /// Node results kept across runs (meshers/node_cache.hpp; not owned, may be shared by runs on
  /// several threads). A job whose key is cached does not run; the mesh is the same, byte for
  /// byte, as without the cache. Jobs that read an ffd's field, and runs with a brick_filter,
  /// are not cached.
  NodeCache* cache = nullptr;
};

struct MeshResult {
  std::shared_ptr<const TriangleMesh> mesh;
  std::vector<NodeReport> nodes;  ///< one per job, by node id
  /// The tree with its ffd nodes prepared: evaluate the result's field with it.
  std::optional<Tree> tree;
};

/// Meshes the tree's root. Throws PolygonizeError (an unbounded solid),
/// MemoryBudgetError (a stage that would pass the budget, before it allocates), MeshCancelled,
/// CompileError. Calls on one Tree from several threads are
/// independent (each run compiles its own tapes; the tree is only read).
MeshResult mesh_tree(const Tree& tree, const MeshOptions& options);

/// Runs only the jobs that the tree's field needs (its ffd nodes and what they deform) and
/// returns the prepared tree (the tree itself when nothing needs preparing).
Tree prepare_fields(const Tree& tree, const MeshOptions& options);

}  // namespace ht
