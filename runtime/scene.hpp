// Scene format v1 (SCENE_FORMAT.md): JSON in, a Tree out, or one SceneError that names the JSON
// path of the offending value and the rule it breaks:
//   scene.json: root.children[2].radius: must be > 0
// Unknown keys and unknown types are errors, not silently ignored.
#pragma once

#include "runtime/tree.hpp"

#include <filesystem>
#include <stdexcept>
#include <string>

namespace ht {

struct SceneError : std::runtime_error {
  /// A whole-file failure (cannot open, not JSON): the message starts with `source`.
  SceneError(std::string source_, const std::string& message) : std::runtime_error(message), source(std::move(source_)) {}
  /// A rule broken at a JSON path: "source: path: rule".
  SceneError(std::string source_, std::string path_, const std::string& rule)
      : std::runtime_error(source_ + ": " + path_ + ": " + rule), source(std::move(source_)), path(std::move(path_)) {}
  std::string source;  ///< the scene file, or the name given to load_scene_text
  std::string path;    ///< the JSON path ("root.children[2].radius"); empty for whole-file failures
};

/// A scene file larger than this is refused: scenes name their meshes' files rather than hold
/// them, so a bigger one is some other stream (a device, a mesh or an archive given by mistake).
inline constexpr std::size_t kMaxSceneBytes = std::size_t(256) << 20;

/// Loads a scene file; relative mesh paths are resolved against the file's folder. Anything that
/// can be read in order will do (a pipe, /dev/stdin); what does not start with '{' (after a
/// UTF-8 byte order mark at its start, and whitespace) or runs past kMaxSceneBytes is refused
/// once that much is read.
Tree load_scene(const std::filesystem::path& file);

/// Loads a scene from text; `source` names it in messages, `base_dir` resolves mesh paths.
Tree load_scene_text(const std::string& text, const std::filesystem::path& base_dir,
                     const std::string& source = "scene");

/// Deepest nesting of nodes a scene may have.
inline constexpr int kMaxSceneDepth = kMaxTreeDepth;

}  // namespace ht
