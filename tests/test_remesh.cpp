// Isotropic remeshing (meshers/remesh.hpp) as properties: the result is closed and manifold, and
// every vertex it moved or made lies on the surface (a vertex moved a fraction of an edge along
// its tangent plane and not projected back would be about 1e-2 h off: checked by leaving out the
// projection, which fails this test).
#include "meshers/mesh_checks.hpp"
#include "meshers/polygonize.hpp"
#include "meshers/remesh.hpp"
#include "runtime/builder.hpp"
#include "runtime/tape.hpp"
#include "runtime/tape_eval.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

namespace ht {
namespace {

constexpr double kT = 0.5;

// The largest |f - T| / |grad f| over the mesh's vertices: their distance to the surface, to first order.
double largest_vertex_error(const TriangleMesh& m, const TapeEvaluator& field) {
  std::vector<double> f(m.positions.size());
  std::vector<glm::dvec3> g(m.positions.size());
  field.gradient(m.positions, f, g);
  double worst = 0.0;
  for (std::size_t v = 0; v < f.size(); ++v) worst = std::max(worst, std::abs(f[v] - kT) / glm::length(g[v]));
  return worst;
}

TEST(Remesh, EveryVertexEndsOnTheSurface) {
  const double h = 0.04;
  for (int scene = 0; scene < 2; ++scene) {
    Builder b(kT);
    const Tree t = scene == 0 ? b.build(b.point({0, 0, 0}, {0.8}))
                              : b.build(b.blend({b.point({-0.2, 0, 0}, {0.6}), b.point({0.25, 0.05, 0}, {0.5})}));
    PolygonizeOptions o;
    o.precision = 0.7 * h;  // finer than the target: the remeshing collapses, flips and relaxes
    o.quality.enabled = false;
    o.sharp_features = false;
    TriangleMesh m = polygonize(t.graph_ptr(), t.root(), kT, o);
    const TapeEvaluator field(std::make_shared<const Tape>(compile_tape(t.graph_ptr(), t.root(), kT)));
    const double before = largest_vertex_error(m, field);
    std::vector<std::uint8_t> region(m.positions.size(), 1), fixed(m.positions.size(), 0);
    RemeshOptions ro;
    ro.target = h;
    RemeshStats st;
    remesh_region(m, region, fixed, gradient_of(field), kT, ro, &st);
    ASSERT_GT(st.collapses, 100u) << "scene " << scene;
    const MeshChecks c = check_mesh(m);
    EXPECT_TRUE(c.manifold()) << "scene " << scene;
    EXPECT_EQ(c.boundary_edges, 0u) << "scene " << scene;
    // The extraction's own vertices are within its refinement's tolerance.
    EXPECT_LT(largest_vertex_error(m, field), std::max(before, 2e-3 * h)) << "scene " << scene;
  }
}

}  // namespace
}  // namespace ht
