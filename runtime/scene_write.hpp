// Scene format v1 out (SCENE_FORMAT.md): a Tree written as the JSON document that loads back
// into the same tree (load_scene, runtime/scene.hpp), e.g. what `hybridtree optimize -o` writes.
// Numbers are written with 17 significant digits, so every parameter reads back bit for bit. A
// node shared by several parents is written under each (JSON is a tree); the loader reads its
// meshes once all the same. Affine maps are written as their matrix.
#pragma once

#include "runtime/tree.hpp"

#include <filesystem>
#include <stdexcept>
#include <string>

namespace ht {

/// A tree that scene format v1 cannot hold: a mesh leaf made in memory (no file to name).
struct SceneWriteError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// The scene as JSON text. Mesh files are named relative to `scene_dir` (the folder the text
/// will be saved in) where they can be, else by absolute path.
std::string write_scene_text(const Tree& tree, const std::filesystem::path& scene_dir);

}  // namespace ht
