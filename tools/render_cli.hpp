// `hybridtree render (SCENE | MESH) -o out.png`: the scene meshed with its default strategy at
// its precision (or a closed mesh file as it is) and drawn by tools/render.hpp, the triangles
// that lie on a mesh leaf outlined (all of a mesh file's).
#pragma once

#include <string>

namespace ht::cli {

struct RenderArgs {
  std::string input, out;
  int width = 800, height = 600;
  double azimuth = 35.0, elevation = 25.0, precision = 0.0;
};

/// Writes the picture atomically; returns the exit status. Throws InputError (a bad input or
/// output), SceneError, MeshError and the meshing errors, as `mesh` does.
int cmd_render(const RenderArgs& args);

}  // namespace ht::cli
