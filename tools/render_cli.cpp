#include "tools/render_cli.hpp"

#include "meshers/mesh_plan.hpp"
#include "meshers/mesh_run.hpp"
#include "nodes/mesh_leaf.hpp"
#include "runtime/scene.hpp"
#include "runtime/tape.hpp"
#include "tools/cli_io.hpp"
#include "tools/render.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>

namespace ht::cli {
namespace {

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && std::equal(tail.rbegin(), tail.rend(), s.rbegin(), [](char a, char b) {
           return std::tolower(static_cast<unsigned char>(a)) == b;
         });
}


}  // namespace

int cmd_render(const RenderArgs& a) {
  if (!ends_with(a.out, ".png")) throw InputError(a.out + ": the picture is written as PNG (use a .png name)");
  const auto t0 = std::chrono::steady_clock::now();
  std::shared_ptr<const TriangleMesh> mesh;
  std::vector<std::uint8_t> outlined;
  if (ends_with(a.input, ".json")) {
    const Tree tree = load_scene(a.input);
    MeshOptions options;
    options.precision = ht::default_precision(tree, a.precision);
    MeshResult result;
    try {
      result = mesh_tree(tree, options);
    } catch (const PolygonizeError& e) {
      throw InputError(a.input + ": " + e.what());
    } catch (const MemoryBudgetError& e) {
      throw InputError(a.input + ": " + e.what());
    } catch (const CompileError& e) {
      throw InputError(a.input + ": " + e.what());
    }
    mesh = result.mesh;
    // A vertex within a thousandth of the precision of a leaf's surface lies on it.
    outlined = render::on_mesh_leaves(*mesh, result.tree->graph(), 1e-3 * options.precision);
  } else {
    const auto leaf = MeshLeaf::load(a.input);
    mesh = leaf->surface();
    outlined.assign(mesh->triangles.size(), 1);
  }
  render::Options o;
  o.width = a.width;
  o.height = a.height;
  o.azimuth = a.azimuth;
  o.elevation = a.elevation;
  render::Image image;
  try {
    image = render::draw(*mesh, outlined, o);
  } catch (const render::RenderError& e) {
    throw InputError(a.input + ": " + e.what());
  }
  write_file_atomically(a.out, render::encode_png(image), "picture");
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::size_t drawn_as_leaf = 0;
  for (std::uint8_t f : outlined) drawn_as_leaf += f;
  std::printf("%s: %d x %d, %zu triangles (%zu on mesh leaves, outlined), %.3f s\n", a.out.c_str(), image.width,
              image.height, mesh->triangles.size(), drawn_as_leaf, s);
  return 0;
}

}  // namespace ht::cli
