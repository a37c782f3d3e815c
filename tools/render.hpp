// Headless pictures of a mesh: Embree ray casting, shaded, with chosen triangles outlined (the
// paper's Figure 1 draws the parts that come from mesh leaves in wireframe).
//
// The camera looks at the mesh's bounding sphere from a direction given by azimuth (degrees
// around +y, 0 looking down -z) and elevation (degrees above the horizon), with a 30-degree
// vertical field of view, y up. Each pixel averages 2 x 2 rays. The picture depends only on its
// inputs (the same bytes at any thread count).
#pragma once

#include "meshers/triangle_mesh.hpp"
#include "runtime/graph.hpp"

#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace ht::render {

struct Options {
  int width = 800, height = 600;  ///< pixels, each in [16, 8192]
  double azimuth = 35.0, elevation = 25.0;  ///< degrees
};

struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  ///< rows top to bottom, 3 bytes a pixel
};

/// Thrown for options or inputs it cannot draw, and files it cannot write; what() says which.
struct RenderError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// The picture of `mesh`; triangles whose flag in `outlined` (empty, or one per triangle) is set
/// are drawn lighter with their edges dark.
Image draw(const TriangleMesh& mesh, std::span<const std::uint8_t> outlined, const Options& options);

/// The triangles whose three vertices lie on the surface of one of the graph's mesh leaves
/// (within `tolerance`, world units): in a meshed scene, what came from the leaves' meshes.
std::vector<std::uint8_t> on_mesh_leaves(const TriangleMesh& mesh, const Graph& graph, double tolerance);

/// The image as PNG bytes (stb_image_write); the caller writes them (atomically, tools/cli_io.hpp).
std::string encode_png(const Image& image);

}  // namespace ht::render
