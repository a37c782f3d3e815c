// The inside of the embedding API (runtime/api.hpp): what a hybridtree::Tree holds, and the one
// place where the library's internal exceptions become hybridtree::Error types. Not installed.
#pragma once

#include "runtime/api.hpp"
#include "runtime/tree.hpp"

#include <exception>
#include <mutex>
#include <optional>
#include <string>

namespace hybridtree {

struct Tree::Impl {
  Impl(ht::Tree loaded_, std::string source_, double load_seconds_)
      : loaded(std::move(loaded_)), source(std::move(source_)), load_seconds(load_seconds_) {}
  /// The tree as loaded: meshing starts from it (the mesh plan prepares its ffds itself).
  ht::Tree loaded;
  std::string source;  ///< the scene file, the name given to from_json, or "<builder>"
  double load_seconds = 0.0;
  /// The tree the field is evaluated on: `loaded` with its ffd nodes prepared at the default
  /// precision (as `hybridtree eval` does), made once, on first use, by whichever thread
  /// needs it first.
  const ht::Tree& field_tree() const;

 private:
  mutable std::once_flag once_;
  mutable std::optional<ht::Tree> field_tree_;
};

/// Rethrows the exception being handled as a hybridtree::Error: SceneError, BuildError (as
/// InputError, path() the key), PolygonizeError, CompileError and EvalError (MeshingError),
/// MemoryBudgetError, MeshCancelled (CancelledError), MeshWriteError (WriteError); any other
/// std::exception becomes an Error with its message; std::bad_alloc passes unchanged. `file`
/// names what the call was about; meshing messages are prefixed with it. Call inside a catch.
[[noreturn]] void rethrow_as_api_error(const std::string& file);

/// Runs f(), translating what it throws (rethrow_as_api_error).
template <class F>
auto guarded(const std::string& file, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (...) {
    rethrow_as_api_error(file);
  }
}

}  // namespace hybridtree
