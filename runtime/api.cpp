// The embedding API (runtime/api.hpp) over the library: scenes load through runtime/scene.hpp,
// fields run the compiled tape, meshes go through the same run as `hybridtree mesh`
// (meshers/mesh_run.hpp) and are written by meshers/mesh_io.hpp.
#include "runtime/api.hpp"

#include "meshers/ffd.hpp"
#include "meshers/mesh_io.hpp"
#include "meshers/mesh_run.hpp"
#include "meshers/polygonize.hpp"
#include "nodes/mesh_leaf.hpp"
#include "runtime/api_impl.hpp"
#include "runtime/builder.hpp"
#include "runtime/memory_budget.hpp"
#include "runtime/optimize.hpp"
#include "runtime/scene.hpp"
#include "runtime/scene_write.hpp"
#include "runtime/tape.hpp"
#include "runtime/tape_eval.hpp"
#include "runtime/tree_eval.hpp"

#include <glm/vec3.hpp>
#include <tbb/task_arena.h>

#include <chrono>
#include <cmath>
#include <new>

namespace hybridtree {

const char* version() { return "0.1.0"; }

Error::Error(const std::string& message, std::string file, std::string path)
    : std::runtime_error(message), file_(std::move(file)), path_(std::move(path)) {}
Error::~Error() = default;
SceneError::~SceneError() = default;
InputError::~InputError() = default;
MeshingError::~MeshingError() = default;
MemoryBudgetError::MemoryBudgetError(const std::string& message, std::string file, std::size_t needed_,
                                     std::size_t in_use_, std::size_t limit_)
    : MeshingError(message, std::move(file)), needed(needed_), in_use(in_use_), limit(limit_) {}
MemoryBudgetError::~MemoryBudgetError() = default;
CancelledError::~CancelledError() = default;
WriteError::~WriteError() = default;

void rethrow_as_api_error(const std::string& file) {
  const std::string prefix = file.empty() ? "" : file + ": ";
  try {
    throw;
  } catch (const Error&) {
    throw;
  } catch (const ht::SceneError& e) {
    throw SceneError(e.what(), e.source, e.path);
  } catch (const ht::BuildError& e) {
    throw InputError(e.key + ": " + e.what(), {}, e.key);
  } catch (const ht::MeshError& e) {
    throw SceneError(e.what(), file);
  } catch (const ht::MeshCancelled& e) {
    throw CancelledError(prefix + e.what(), file);
  } catch (const ht::MemoryBudgetError& e) {
    throw MemoryBudgetError(prefix + e.what(), file, e.needed, e.in_use, e.limit);
  } catch (const ht::PolygonizeError& e) {
    throw MeshingError(prefix + e.what(), file);
  } catch (const ht::CompileError& e) {
    throw MeshingError(prefix + e.what(), file);
  } catch (const ht::EvalError& e) {
    throw MeshingError(prefix + e.what(), file);
  } catch (const ht::MeshWriteError& e) {
    throw WriteError(e.what(), file);
  } catch (const std::bad_alloc&) {
    throw;
  } catch (const std::exception& e) {
    throw Error(e.what(), file);
  }
}

const ht::Tree& Tree::Impl::field_tree() const {
  std::call_once(once_, [this] {
    field_tree_.emplace(ht::prepare_ffd(loaded, ht::default_precision(loaded, 0.0)));
    field_tree_->evaluator();  // compiled here, so a scene that cannot compile fails on this call
  });
  return *field_tree_;
}

Tree::Tree(std::shared_ptr<const Impl> impl) : impl_(std::move(impl)) {}
Tree::Tree(const Tree&) = default;
Tree::Tree(Tree&&) noexcept = default;
Tree& Tree::operator=(const Tree&) = default;
Tree& Tree::operator=(Tree&&) noexcept = default;
Tree::~Tree() = default;

namespace {

using clock = std::chrono::steady_clock;
double seconds_since(clock::time_point t) { return std::chrono::duration<double>(clock::now() - t).count(); }

// Runs f on `threads` workers (0: TBB's default arena, all cores).
template <class F>
auto in_arena(int threads, F&& f) -> decltype(f()) {
  if (threads < 0) throw InputError("threads: must be >= 0, not " + std::to_string(threads), {}, "threads");
  if (threads == 0) return f();
  tbb::task_arena arena(threads);
  return arena.execute(f);
}

// The points as vectors, after checking the sizes and that every coordinate is finite.
std::span<const glm::dvec3> checked_points(std::span<const double> xyz, std::size_t out_size,
                                           std::size_t out_per_point, const char* out_name) {
  static_assert(sizeof(glm::dvec3) == 3 * sizeof(double), "glm::dvec3 must be three packed doubles");
  if (xyz.size() % 3 != 0)
    throw InputError("points: expected an (n, 3) array of x y z, got " + std::to_string(xyz.size()) +
                         " numbers (not a multiple of 3)", {}, "points");
  const std::size_t n = xyz.size() / 3;
  if (out_size != n * out_per_point)
    throw InputError(std::string(out_name) + ": expected " + std::to_string(n * out_per_point) + " numbers for " +
                         std::to_string(n) + " points, got " + std::to_string(out_size), {}, out_name);
  for (std::size_t i = 0; i < xyz.size(); ++i)
    if (!std::isfinite(xyz[i])) {
      const std::string at = "points[" + std::to_string(i / 3) + "]";
      throw InputError(at + ": coordinate " + std::to_string(i % 3) + " is not a finite number", {}, at);
    }
  return {reinterpret_cast<const glm::dvec3*>(xyz.data()), n};
}

}  // namespace

Tree Tree::load(const std::string& file) {
  return guarded(file, [&] {
    const auto t0 = clock::now();
    ht::Tree loaded = ht::optimize(ht::load_scene(file));
    return Tree(std::make_shared<const Impl>(std::move(loaded), file, seconds_since(t0)));
  });
}

Tree Tree::from_json(const std::string& text, const std::string& base_dir, const std::string& source) {
  return guarded(source, [&] {
    const auto t0 = clock::now();
    ht::Tree loaded = ht::optimize(ht::load_scene_text(text, base_dir, source));
    return Tree(std::make_shared<const Impl>(std::move(loaded), source, seconds_since(t0)));
  });
}

std::string Tree::to_json(const std::string& scene_dir) const {
  return guarded(impl_->source, [&] {
    try {
      return ht::write_scene_text(impl_->loaded, scene_dir);
    } catch (const ht::SceneWriteError& e) {
      throw InputError(impl_->source + ": " + e.what(), impl_->source, {});
    }
  });
}

double Tree::threshold() const { return impl_->loaded.threshold(); }

std::array<double, 6> Tree::bounds() const {
  const ht::Aabb& b = impl_->loaded.graph().support(impl_->loaded.root(), false);
  return {b.lo.x, b.lo.y, b.lo.z, b.hi.x, b.hi.y, b.hi.z};
}

void Tree::field(std::span<const double> points, std::span<double> values, const EvalOptions& options) const {
  const std::span<const glm::dvec3> p = checked_points(points, values.size(), 1, "values");
  guarded(impl_->source, [&] {
    const ht::Tree& tree = impl_->field_tree();
    in_arena(options.threads, [&] { tree.field(p, values); });
  });
}

void Tree::gradient(std::span<const double> points, std::span<double> gradients, std::span<double> values,
                    const EvalOptions& options) const {
  const std::span<const glm::dvec3> p = checked_points(points, gradients.size(), 3, "gradients");
  if (!values.empty() && values.size() != p.size())
    throw InputError("values: expected " + std::to_string(p.size()) + " numbers or none, got " +
                         std::to_string(values.size()), {}, "values");
  const std::span<glm::dvec3> g(reinterpret_cast<glm::dvec3*>(gradients.data()), p.size());
  guarded(impl_->source, [&] {
    const ht::Tree& tree = impl_->field_tree();
    in_arena(options.threads, [&] { tree.evaluator().gradient(p, values, g); });
  });
}

}  // namespace hybridtree
