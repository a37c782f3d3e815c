// HybridTree's embedding API: the one header a program that uses the library includes. It is
// installed as <hybridtree/api.hpp> and needs nothing but the C++20 standard library; link
// HybridTree::hybridtree (find_package(HybridTree CONFIG REQUIRED)). The Python module
// (`import hybridtree`) is this API, function for function.
//
//   hybridtree::Tree tree = hybridtree::Tree::load("examples/bunny_garden.json");
//   std::vector<double> xyz = {0, 0, 0,  0.5, 0.2, 0.1};    // N = 2 points, x y z each
//   std::vector<double> f(2);
//   tree.field(xyz, f);                                      // f[i]: the field at point i
//   hybridtree::MeshOptions options;
//   options.precision = 0.02;                                // scene units; 0: the scene's
//   hybridtree::Mesh mesh = tree.mesh(options);              // vertices, triangles, statistics
//   hybridtree::write_mesh(mesh, "garden.ply");
//
// Ownership: every object here owns its data (std::vector, std::string); a Tree is a cheap,
// shared handle to an immutable model (copies share it, it lives as long as one copy does).
// Units: scene units throughout (points, precision, bounds). Arrays of points are contiguous
// (N, 3) arrays of doubles, x y z of point 0 first: std::span<const double> of 3N values.
//
// Thread safety: a Tree is immutable. Any number of threads may call field(), gradient() and
// mesh() on one Tree (or on copies of it) at once, with no locking on the caller's side; each
// call only reads the model. Results never depend on the number of threads, the caller's or the
// library's: every point, and every meshing job, is computed the same way whatever thread runs it.
// A Builder is not thread-safe (one thread builds; the Trees it returns are as above).
//
// Errors: every failure the library reports is a hybridtree::Error (below), with a message that
// names the file or JSON path at fault and the rule it breaks, e.g.
//   examples/x.json: root.children[2].radius: must be > 0
// Out-of-memory is std::bad_alloc as usual.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#if defined(__GNUC__) || defined(__clang__)
#define HYBRIDTREE_API __attribute__((visibility("default")))
#else
#define HYBRIDTREE_API
#endif

namespace hybridtree {

/// The library's version, "0.1.0".
HYBRIDTREE_API const char* version();

// ---------------------------------------------------------------------------------------------
// Errors: one base, a derived type per kind of failure. Catch Error for all of them.

class HYBRIDTREE_API Error : public std::runtime_error {
 public:
  Error(const std::string& message, std::string file = {}, std::string path = {});
  ~Error() override;
  /// The file the failure is about (a scene, a mesh, an output), or the name given to
  /// Tree::from_json; empty when none applies.
  const std::string& file() const noexcept { return file_; }
  /// The JSON path of the offending value ("root.children[2].radius"), or the builder key
  /// ("radius", "children[1]"), or the array ("points[17]"); empty when none applies.
  const std::string& path() const noexcept { return path_; }

 private:
  std::string file_, path_;
};

/// A scene that does not load: a file that cannot be read, text that is not JSON, a value that
/// breaks a rule of the format, a mesh file that is not a usable mesh.
class HYBRIDTREE_API SceneError : public Error {
 public:
  using Error::Error;
  ~SceneError() override;
};

/// A bad argument: an array of the wrong size, a point that is not finite, a builder argument
/// that breaks a rule (path() is the key), an option out of range, an unknown output extension.
class HYBRIDTREE_API InputError : public Error {
 public:
  using Error::Error;
  ~InputError() override;
};

/// A scene that loads but cannot be evaluated or meshed as asked: an unbounded solid to mesh,
/// a grid too large, an ffd whose deformed mesh is not a valid mesh. (An ffd whose child has
/// no surface at the precision is no error: it deforms nothing, and its field is 0.)
class HYBRIDTREE_API MeshingError : public Error {
 public:
  using Error::Error;
  ~MeshingError() override;
};

/// A meshing stage that would pass MeshOptions::memory_budget_gib, thrown before it allocates.
class HYBRIDTREE_API MemoryBudgetError : public MeshingError {
 public:
  MemoryBudgetError(const std::string& message, std::string file, std::size_t needed, std::size_t in_use,
                    std::size_t limit);
  ~MemoryBudgetError() override;
  std::size_t needed = 0, in_use = 0, limit = 0;  ///< bytes: the stage's need, already held, the budget
};

/// A mesh run stopped through MeshOptions::cancel.
class HYBRIDTREE_API CancelledError : public Error {
 public:
  using Error::Error;
  ~CancelledError() override;
};

/// A mesh file that could not be written (file() names it); nothing is left behind.
class HYBRIDTREE_API WriteError : public Error {
 public:
  using Error::Error;
  ~WriteError() override;
};

// ---------------------------------------------------------------------------------------------
// Evaluating and meshing a tree.

struct EvalOptions {
  /// Worker threads for this call (a TBB arena of this many); 0: all cores. >= 0.
  int threads = 0;
};

enum class Strategy : std::uint8_t {
  Scene,   ///< the scene's "mesher": {"strategy": ...}, else Auto
  Auto,    ///< each node its own way (the paper, sections 3.1-3.3)
  Global,  ///< polygonize the whole surface
  Local,   ///< the local strategy wherever one exists
};

struct MeshOptions {
  /// Target edge length, scene units; 0: the scene's mesher.precision, else 1/100 of its size.
  double precision = 0.0;
  Strategy strategy = Strategy::Scene;
  /// Worker threads for this run (a TBB arena); 0: all cores. The mesh is the same at any count.
  int threads = 0;
  /// The whole run's memory budget, GiB (> 0); a stage that would pass it throws
  /// MemoryBudgetError before allocating.
  double memory_budget_gib = 4.0;
  bool sharp_features = true;  ///< keep creases of Booleans, crops and mesh leaves sharp
  bool quality = true;         ///< the polygonizer's quality pass (well-shaped triangles)
  /// Called with the fraction of the work done, non-decreasing, ending at 1; calls are
  /// serialized but may come from any thread. It must not throw.
  std::function<void(double)> progress;
  /// Polled between jobs and bricks; when it reads true the run throws CancelledError. Not owned;
  /// must outlive the call.
  const std::atomic<bool>* cancel = nullptr;
};

struct MeshStats {
  std::size_t triangles = 0, vertices = 0;
  double precision = 0.0;       ///< the edge length used
  double seconds = 0.0;         ///< meshing time, wall clock
  bool watertight = false;      ///< closed, manifold and oriented (always, unless a bug)
  long genus = 0;
  std::string strategy;         ///< "auto", "global" or "local": what was asked
  std::string root_strategy;    ///< the root's job and why: "trim blend (low overlap)"
  /// Session::mesh only: the jobs taken from the session's cache (they did not run), by label
  /// ("name", else "type #id"), and the jobs that ran.
  std::vector<std::string> reused_nodes;
  std::size_t cache_misses = 0;
  /// Every figure, as the JSON document `hybridtree mesh --stats-json` writes (without the
  /// output file and the write time): per node strategy, reason, triangles and seconds; the
  /// checks (closed, manifold, genus, area, volume, angles, surface error); seconds per stage.
  std::string json;
};

/// A closed, oriented triangle mesh: vertices as a (V, 3) array of doubles, triangles as a
/// (T, 3) array of vertex indices, counter-clockwise seen from outside.
struct Mesh {
  std::vector<double> vertices;
  std::vector<std::uint32_t> triangles;
  MeshStats stats;
};

class HYBRIDTREE_API Tree {
 public:
  /// Loads a scene file (JSON, scene format 1); mesh paths are relative to its folder. Throws
  /// SceneError (file() the scene, path() the JSON path when a value breaks a rule). Loaded
  /// trees, and built ones, are run through the tree-rewriting optimizer, as the CLI's are: the
  /// same field (to float rounding of sums in another order), evaluated and meshed faster.
  static Tree load(const std::string& file);
  /// Loads a scene from JSON text; `base_dir` resolves mesh paths, `source` names the text in
  /// messages. Throws SceneError.
  static Tree from_json(const std::string& text, const std::string& base_dir = ".",
                        const std::string& source = "<text>");

  /// The tree as scene format v1 JSON (what Tree::from_json reads back into the same field):
  /// mesh files named relative to `scene_dir` where they can be. Throws InputError for a mesh
  /// that came from no file.
  std::string to_json(const std::string& scene_dir = ".") const;

  /// The threshold T: the surface is {field = T}, the solid {field >= T}.
  double threshold() const;
  /// The box outside which the field is 0 ({lo x, lo y, lo z, hi x, hi y, hi z}); infinite
  /// coordinates for an unbounded field, lo > hi for an empty one.
  std::array<double, 6> bounds() const;

  /// The field at n = points.size() / 3 points (the compiled tape: float SIMD blocks, values
  /// within float precision of the double reference). values.size() must be n. Throws
  /// InputError for sizes that do not match or a point that is not finite (path "points[i]"),
  /// MeshingError for a scene whose field needs meshing that fails (an ffd).
  void field(std::span<const double> points, std::span<double> values, const EvalOptions& options = {}) const;
  /// The gradient (forward-mode differentiation of the same tape): gradients is (n, 3), values
  /// (n) or empty. Same contract as field().
  void gradient(std::span<const double> points, std::span<double> gradients, std::span<double> values = {},
                const EvalOptions& options = {}) const;

  /// Meshes the surface. Throws MeshingError, MemoryBudgetError, CancelledError, InputError (an
  /// option out of range).
  Mesh mesh(const MeshOptions& options = {}) const;

  Tree(const Tree&);
  Tree(Tree&&) noexcept;
  Tree& operator=(const Tree&);
  Tree& operator=(Tree&&) noexcept;
  ~Tree();

  struct Impl;  ///< runtime/api_impl.hpp

 private:
  friend class Builder;
  friend class Session;
  explicit Tree(std::shared_ptr<const Impl> impl);
  std::shared_ptr<const Impl> impl_;
};

/// A meshing session: keeps node results (each job's mesh, keyed by a content hash of its
/// subtree, the precision and every option that changes output) across calls, so that meshing
/// an edited tree runs only the jobs whose subtree changed. The mesh is the same, byte for byte,
/// as Tree::mesh of the same tree. Edit by building or loading the new tree (Tree::from_json of
/// edited JSON, a Builder): unchanged subtrees are found by content, wherever they sit.
///
///   hybridtree::Session session(512u << 20);                   // cache bound, bytes
///   hybridtree::Mesh first = session.mesh(tree, options);
///   hybridtree::Mesh again = session.mesh(edited_tree, options);  // again.stats.reused_nodes
///
/// Bounded: least-recently-used entries go first. Thread-safe: calls from several threads may
/// share one session. Not cached: jobs that read an ffd's field.
///
/// With a folder, the cache has a second level on disk, shared by every session and process
/// that names it, as `hybridtree mesh --cache DIR` (README, "On disk"): a job or part missing in
/// memory is read from it, each new one written to it; bad or stale files are ignored with a
/// warning on stderr; after each mesh() the folder is trimmed to `folder_bytes`.
class HYBRIDTREE_API Session {
 public:
  explicit Session(std::size_t cache_bytes = std::size_t(1) << 30);
  /// Throws InputError when `folder` cannot be made or is not a folder.
  Session(std::size_t cache_bytes, const std::string& folder, std::uint64_t folder_bytes = std::uint64_t(1) << 30);
  /// As tree.mesh(options), reusing and filling the cache; stats.reused_nodes and
  /// stats.cache_misses say what was reused, and stats.json has "cache".
  Mesh mesh(const Tree& tree, const MeshOptions& options = {});
  /// Bytes the cache holds now, and its entries: job results and parts of global
  /// polygonizations (bricks, quality-pass slabs and bands), within the bound given.
  std::size_t cache_bytes() const;
  std::size_t cache_entries() const;
  /// Empties the memory level (not the folder).
  void clear();

  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;
  ~Session();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Writes a mesh: .ply (binary), .obj, .off (ASCII, 17 digits) or .stl (binary), by extension,
/// atomically (a failure leaves no file). The bytes are those `hybridtree mesh` writes. Throws
/// InputError (unknown extension, an index out of range, sizes not multiples of 3), WriteError.
HYBRIDTREE_API void write_mesh(std::span<const double> vertices, std::span<const std::uint32_t> triangles,
                               const std::string& file);
HYBRIDTREE_API void write_mesh(const Mesh& mesh, const std::string& file);

// ---------------------------------------------------------------------------------------------
// Building a tree in code: the scene format's nodes, one call each (../shared/SCENE_FORMAT.md).

using Node = std::uint32_t;            ///< a node of the builder that returned it
using Vec3 = std::array<double, 3>;    ///< x, y, z
/// Falloff of a primitive or mesh leaf: radius of influence R > 0, strength F != 0.
struct Falloff {
  double radius = 1.0;
  double strength = 1.0;
};
enum class Axis : int { X = 0, Y = 1, Z = 2 };
/// How a Boolean combines its operands (SCENE_FORMAT.md): `Auto` picks R-functions under a
/// blend and min/max elsewhere.
enum class BooleanMode : int { Auto = 0, MinMax = 1, RFunction = 2 };
/// How a node asks to be meshed (the scene format's `mesher` on operators and warps).
enum class MesherHint : int { Auto = 0, Global = 1, Local = 2 };

/// Every call checks its arguments and throws InputError whose path() is the key at fault
/// ("radius", "children[1]") and whose message is "key: rule". Children must be nodes this
/// builder returned; a node may have several parents. Not thread-safe.
class HYBRIDTREE_API Builder {
 public:
  explicit Builder(double threshold = 0.5);
  ~Builder();
  Builder(const Builder&) = delete;
  Builder& operator=(const Builder&) = delete;

  Node point(Vec3 center, Falloff f);
  Node segment(Vec3 a, Vec3 b, Falloff f);
  Node circle(Vec3 center, Vec3 normal, double circle_radius, Falloff f);
  Node disc(Vec3 center, Vec3 normal, double disc_radius, Falloff f);
  Node triangle(Vec3 a, Vec3 b, Vec3 c, Falloff f);
  /// Catmull-Rom spline through >= 2 points given as a (n, 3) array.
  Node curve(std::span<const double> points, Falloff f);
  Node box(Vec3 min, Vec3 max, Falloff f);
  Node cylinder(Vec3 a, Vec3 b, double cylinder_radius, Falloff f);
  Node cone_sphere(Vec3 a, Vec3 b, double radius_a, double radius_b, Falloff f);
  /// A closed mesh file (OFF, OBJ, PLY, STL; loaded once however often it is named). `repair`
  /// closes small holes; `winding` decides inside by the generalized winding number instead.
  Node mesh(const std::string& file, Falloff f, bool repair = false, bool winding = false);

  Node blend(std::span<const Node> children);
  Node unite(std::span<const Node> children, BooleanMode mode = BooleanMode::Auto);
  Node intersect(std::span<const Node> children, BooleanMode mode = BooleanMode::Auto);
  /// children[0] minus each of the others.
  Node subtract(std::span<const Node> children, BooleanMode mode = BooleanMode::Auto);
  Node local_blend(Node a, Node b, Node region, BooleanMode mode = BooleanMode::Auto);
  Node crop(Node child, Vec3 min, Vec3 max);

  /// The forward affine map, row-major 4 x 4 (last row 0 0 0 1, linear part invertible).
  Node affine(Node child, const std::array<double, 16>& forward);
  Node twist(Node child, Axis axis, Vec3 center, double rate);
  Node taper(Node child, Axis axis, Vec3 center, double h0, double h1, double s0, double s1);
  Node bend(Node child, Axis axis, Vec3 center, double h0, double h1, double rate);
  /// Free-form deformation: lattice [min, max] with dims intervals an axis and
  /// (l+1)(m+1)(n+1) control points as an (n, 3) array, x fastest. Its field is the
  /// pseudo-distance of its child's deformed mesh (made when the tree is meshed), with f.
  Node ffd(Node child, Vec3 min, Vec3 max, std::array<int, 3> dims, std::span<const double> points, Falloff f);

  /// Names a node (messages and statistics name it; the optimizer never splices it away).
  void set_name(Node node, const std::string& name);
  /// How an operator or warp asks to be meshed.
  void set_mesher(Node node, MesherHint hint);

  /// The tree rooted at `root`; the builder stays usable.
  Tree build(Node root);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hybridtree
