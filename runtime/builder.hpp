// The C++ way to build a HybridTree, in the spirit of the paper's declarative interface
// (section 4):
//
//   ht::Builder b;                                   // threshold T = 0.5
//   auto victory = b.mesh("victory.obj", {.radius = 0.1});
//   auto wings   = b.crop(victory, {-1, -1, 0}, {1, 1, 1});
//   auto body    = b.segment({0, 0, 0}, {0, 0, 2}, {.radius = 0.6});
//   ht::Tree tree = b.build(b.blend({body, wings}));
//   double f = tree.field({0, 0, 1});
//
// Every call validates its arguments and throws BuildError naming the offending key; the scene
// loader (runtime/scene.hpp) drives the same calls and prefixes the JSON path. Children must be
// ids this builder returned. A node may be used by several parents.
#pragma once

#include "nodes/mesh_inside.hpp"
#include "runtime/graph.hpp"
#include "runtime/graph_writer.hpp"
#include "runtime/tree.hpp"

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include <filesystem>
#include <initializer_list>
#include <span>
#include <stdexcept>
#include <string>

namespace ht {

class MeshCache;

/// A rejected argument: `key` is the node key at fault ("radius", "children[1]", "points[3]"),
/// what() the rule it breaks ("must be > 0").
struct BuildError : std::invalid_argument {
  BuildError(std::string key_, const std::string& rule) : std::invalid_argument(rule), key(std::move(key_)) {}
  std::string key;
};

/// Falloff of a skeletal primitive, mesh leaf or ffd: radius of influence R > 0, strength F != 0.
struct Falloff {
  double radius = 1.0;
  double strength = 1.0;
};

enum class Axis : int { X = 0, Y = 1, Z = 2 };

class Builder {
 public:
  explicit Builder(double threshold = 0.5);
  ~Builder();
  Builder(const Builder&) = delete;
  Builder& operator=(const Builder&) = delete;

  double threshold() const { return threshold_; }
  /// Nodes made so far (ids are 0 .. size() - 1).
  std::size_t size() const { return writer_.size(); }

  // Skeletal primitives (SCENE_FORMAT.md, "Skeletal primitives").
  NodeId point(glm::dvec3 center, Falloff f);
  NodeId segment(glm::dvec3 a, glm::dvec3 b, Falloff f);
  NodeId circle(glm::dvec3 center, glm::dvec3 normal, double circle_radius, Falloff f);
  NodeId disc(glm::dvec3 center, glm::dvec3 normal, double disc_radius, Falloff f);
  NodeId triangle(glm::dvec3 a, glm::dvec3 b, glm::dvec3 c, Falloff f);
  /// Catmull-Rom spline through >= 2 points; distances within 0.5e-4 R of exact.
  NodeId curve(std::span<const glm::dvec3> points, Falloff f);
  NodeId box(glm::dvec3 min, glm::dvec3 max, Falloff f);
  NodeId cylinder(glm::dvec3 a, glm::dvec3 b, double cylinder_radius, Falloff f);
  NodeId cone_sphere(glm::dvec3 a, glm::dvec3 b, double radius_a, double radius_b, Falloff f);

  /// A mesh leaf from a file (loaded once per builder however often it is named), or from a
  /// mesh already loaded. Requires |F| > T. `inside` chooses how inside is decided (closed
  /// meshes only, or the generalized winding number: nodes/mesh_leaf.hpp MeshInside). Throws
  /// BuildError("file", ...) for unusable meshes (the message names the defect).
  NodeId mesh(const std::filesystem::path& file, Falloff f, bool repair = false,
              MeshInside inside = MeshInside::Closed);
  NodeId mesh(std::shared_ptr<const MeshLeaf> leaf, Falloff f);
  /// Loads these mesh files (paths as mesh() takes them) in parallel ahead of the mesh() calls
  /// that will name them; a file that fails is left for mesh() to report.
  void prefetch_meshes(std::span<const MeshFileRequest> files);

  // Operators.
  NodeId blend(std::span<const NodeId> children);
  NodeId blend(std::initializer_list<NodeId> c) { return blend(std::span<const NodeId>(c.begin(), c.size())); }
  NodeId unite(std::span<const NodeId> children, BooleanMode mode = BooleanMode::Auto);
  NodeId unite(std::initializer_list<NodeId> c, BooleanMode mode = BooleanMode::Auto) {
    return unite(std::span<const NodeId>(c.begin(), c.size()), mode);
  }
  NodeId intersect(std::span<const NodeId> children, BooleanMode mode = BooleanMode::Auto);
  NodeId intersect(std::initializer_list<NodeId> c, BooleanMode mode = BooleanMode::Auto) {
    return intersect(std::span<const NodeId>(c.begin(), c.size()), mode);
  }
  /// children[0] minus each of the others, left to right.
  NodeId subtract(std::span<const NodeId> children, BooleanMode mode = BooleanMode::Auto);
  NodeId subtract(std::initializer_list<NodeId> c, BooleanMode mode = BooleanMode::Auto) {
    return subtract(std::span<const NodeId>(c.begin(), c.size()), mode);
  }
  NodeId local_blend(NodeId a, NodeId b, NodeId region, BooleanMode mode = BooleanMode::Auto);
  NodeId crop(NodeId child, glm::dvec3 min, glm::dvec3 max);

  // Warps: each maps its child's space to world space.
  /// The forward affine map (last row must be 0 0 0 1; the linear part invertible).
  NodeId affine(NodeId child, const glm::dmat4& forward);
  NodeId twist(NodeId child, Axis axis, glm::dvec3 center, double rate);
  NodeId taper(NodeId child, Axis axis, glm::dvec3 center, double h0, double h1, double s0, double s1);
  NodeId bend(NodeId child, Axis axis, glm::dvec3 center, double h0, double h1, double rate);
  /// Lattice [min, max] with dims intervals per axis and (l+1)(m+1)(n+1) control points, x
  /// fastest; its field is the pseudo-distance of its child's deformed mesh (needs meshing).
  NodeId ffd(NodeId child, glm::dvec3 min, glm::dvec3 max, glm::ivec3 dims,
             std::span<const glm::dvec3> points, Falloff f);

  void set_name(NodeId node, std::string name);
  void set_mesher(NodeId node, MesherHint hint);
  void set_mesher_settings(const MesherSettings& settings) { settings_ = settings; }
  /// Where relative mesh paths are resolved (the scene file's folder); default: working folder.
  void set_base_dir(std::filesystem::path dir) { base_dir_ = std::move(dir); }

  /// Seals the arena and returns the tree rooted at `root` (Tree(root) in the paper). The
  /// builder stays usable: later nodes go into a new arena copy.
  Tree build(NodeId root);

 private:
  NodeId add(NodeKind kind, std::span<const double> params, std::span<const NodeId> children,
             BooleanMode mode = BooleanMode::Auto);
  NodeId add_primitive(NodeKind kind, std::span<const double> skeleton, Falloff f);
  void check_children(std::span<const NodeId> children, std::size_t min_count);

  double threshold_;
  std::filesystem::path base_dir_;
  MesherSettings settings_;
  GraphWriter writer_;
  std::unique_ptr<MeshCache> cache_;
};

}  // namespace ht
