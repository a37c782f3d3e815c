// The gradient of a mesh leaf on its surface (SCENE_FORMAT.md: the one-sided limit from outside,
// along the inward angle-weighted pseudo-normal, never zero), in both engines, at every vertex,
// edge midpoint and face centre of real and generated meshes, alone and under warps.
#include "nodes/mesh_leaf.hpp"
#include "nodes/warps.hpp"
#include "runtime/builder.hpp"
#include "runtime/tape_eval.hpp"
#include "tests/support/test_support.hpp"

#include <glm/geometric.hpp>
#include <glm/mat4x4.hpp>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <span>
#include <string>
#include <vector>

namespace ht {
namespace {

using glm::dvec3;

// A point on the mesh, the outward normal the test computes for it on its own (face normal,
// sum of the two face normals, angle-weighted vertex normal), and what kind of feature it is.
struct SurfacePoint {
  dvec3 p, outward;
  int kind;  // 0 vertex, 1 edge midpoint, 2 face centre
};

std::vector<SurfacePoint> surface_points(const MeshLeaf& leaf, std::size_t max_per_kind) {
  const auto& pos = leaf.positions();
  const auto& tri = leaf.triangles();
  std::vector<dvec3> face_n(tri.size()), vertex_n(pos.size(), dvec3(0.0));
  for (std::size_t t = 0; t < tri.size(); ++t) {
    const dvec3 a = pos[tri[t][0]], b = pos[tri[t][1]], c = pos[tri[t][2]];
    face_n[t] = glm::normalize(glm::cross(b - a, c - a));
    const dvec3 corner[3] = {a, b, c};
    for (int k = 0; k < 3; ++k) {
      const dvec3 e1 = glm::normalize(corner[(k + 1) % 3] - corner[k]), e2 = glm::normalize(corner[(k + 2) % 3] - corner[k]);
      vertex_n[tri[t][k]] += std::acos(std::clamp(glm::dot(e1, e2), -1.0, 1.0)) * face_n[t];
    }
  }
  std::vector<SurfacePoint> out;
  const std::size_t vstep = std::max<std::size_t>(1, pos.size() / max_per_kind);
  for (std::size_t v = 0; v < pos.size(); v += vstep) out.push_back({pos[v], glm::normalize(vertex_n[v]), 0});
  const std::size_t tstep = std::max<std::size_t>(1, tri.size() / max_per_kind);
  for (std::size_t t = 0; t < tri.size(); t += tstep) {
    const dvec3 a = pos[tri[t][0]], b = pos[tri[t][1]], c = pos[tri[t][2]];
    out.push_back({(a + b + c) / 3.0, face_n[t], 2});
    // The midpoint of edge 0 (a, b) and its other face, found by brute force over the faces.
    for (std::size_t g = 0; g < tri.size(); ++g) {
      if (g == t) continue;
      int shared = 0;
      for (int k = 0; k < 3; ++k) shared += (tri[g][k] == tri[t][0]) + (tri[g][k] == tri[t][1]);
      if (shared == 2) {
        out.push_back({(a + b) / 2.0, glm::normalize(face_n[t] + face_n[g]), 1});
        break;
      }
    }
  }
  return out;
}

// The closed box [-1, 1]^3 as 12 triangles, outward: every edge and vertex a sharp feature.
std::shared_ptr<const MeshLeaf> box_leaf() {
  std::vector<dvec3> p;
  for (int i = 0; i < 8; ++i) p.emplace_back(i & 1 ? 1.0 : -1.0, i & 2 ? 1.0 : -1.0, i & 4 ? 1.0 : -1.0);
  std::vector<glm::uvec3> t = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                               {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return MeshLeaf::from_triangles(std::move(p), std::move(t), "box");
}

// Central differences of the reference field at p, step h.
dvec3 fd_gradient(const Tree& tree, const dvec3& p, double h) {
  dvec3 g;
  for (int axis = 0; axis < 3; ++axis) {
    dvec3 a = p, b = p;
    a[axis] += h;
    b[axis] -= h;
    g[axis] = (tree.reference(a) - tree.reference(b)) / (2 * h);
  }
  return g;
}

double cosine(const dvec3& a, const dvec3& b) { return glm::dot(a, b) / (glm::length(a) * glm::length(b)); }

struct Warp {
  std::string name;
  std::function<NodeId(Builder&, NodeId)> wrap;        // the tree: the leaf under this warp
  std::function<dvec3(const dvec3&)> forward;          // w, leaf space to world space
};

std::vector<Warp> warps() {
  return {{"none", [](Builder&, NodeId n) { return n; }, [](const dvec3& p) { return p; }},
          {"twist",
           [](Builder& b, NodeId n) { return b.twist(n, Axis::Z, {0.1, 0, 0}, 1.3); },
           [](const dvec3& p) {
             const double params[kTwistParams] = {2, 0.1, 0, 0, 1.3};
             return warp_forward(NodeKind::Twist, params, p);
           }},
          {"affine",
           [](Builder& b, NodeId n) {
             const glm::dmat4 m(1.5, 0.2, -0.1, 0.0, 0.3, 0.7, 0.25, 0.0, -0.2, 0.1, 1.1, 0.0, 0.3, -0.2, 0.1, 1.0);
             return b.affine(n, m);
           },
           nullptr}};
}

// Every surface point of `leaf`, alone and under each warp: both engines give a nonzero
// gradient that points inward, they agree, and it has the direction of the limit from outside
// (central differences a little way out along the outward normal) and the magnitude |f'(r0)|.
void check_surface_gradients(std::shared_ptr<const MeshLeaf> leaf, double radius, std::size_t per_kind) {
  const double scale = glm::length(leaf->bounds().hi - leaf->bounds().lo);
  const std::vector<SurfacePoint> pts = surface_points(*leaf, per_kind);
  const MeshFieldParams prm = mesh_field_params(radius, 1.0, 0.5);
  const double u = 1 - prm.r0 * prm.r0 / (prm.kernel_radius * prm.kernel_radius);
  const double slope = 6.0 * prm.r0 / (prm.kernel_radius * prm.kernel_radius) * u * u;
  for (const Warp& warp : warps()) {
    Builder b(0.5);
    const NodeId root = warp.wrap(b, b.mesh(leaf, {radius, 1.0}));
    const Tree tree = b.build(root);
    const Graph& g = tree.graph();
    // The affine map's forward transform, from the graph's parameters.
    auto forward = warp.forward ? warp.forward : [&](const dvec3& p) { return warp_forward(NodeKind::Affine, g.params_of(root).data(), p); };
    std::vector<dvec3> world(pts.size()), tape(pts.size()), ref(pts.size());
    for (std::size_t i = 0; i < pts.size(); ++i) world[i] = forward(pts[i].p);
    tree.gradient(world, tape);
    tree.reference_gradient(world, ref);
    std::size_t worst_kind = 0;
    double worst = 1.0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const std::string at = warp.name + " kind " + std::to_string(pts[i].kind) + " point " + std::to_string(i);
      ASSERT_GT(glm::length(tape[i]), 0.0) << at;
      ASSERT_GT(glm::length(ref[i]), 0.0) << at;
      const double eps = 1e-4 * scale;
      const dvec3 out_step = forward(pts[i].p + eps * pts[i].outward) - world[i];
      EXPECT_LT(glm::dot(tape[i], out_step), 0.0) << at;
      EXPECT_LT(glm::dot(ref[i], out_step), 0.0) << at;
      EXPECT_GT(cosine(tape[i], ref[i]), 1 - 1e-5) << at;
      EXPECT_NEAR(glm::length(tape[i]) / glm::length(ref[i]), 1.0, 1e-3) << at;
      // The limit from outside: differences at a point just off the surface, steps far smaller.
      const dvec3 fd = fd_gradient(tree, world[i] + 1e-3 * out_step, 1e-8 * scale);
      const double c = cosine(ref[i], fd);
      if (c < worst) worst = c, worst_kind = static_cast<std::size_t>(pts[i].kind);
      EXPECT_GT(c, pts[i].kind == 2 ? 0.9999 : 0.99) << at;
      if (warp.name == "none") {
        EXPECT_NEAR(glm::length(ref[i]), slope, 1e-9 * slope) << at;
      }
    }
    std::printf("%s, %s: worst cosine to the limit from outside %.6f (at a %s)\n", leaf->name().c_str(), warp.name.c_str(),
                worst, worst_kind == 0 ? "vertex" : worst_kind == 1 ? "edge" : "face");
  }
}

TEST(MeshGradient, BoxAtVerticesEdgesAndFaces) { check_surface_gradients(box_leaf(), 0.3, 100); }

TEST(MeshGradient, BunnyAtVerticesEdgesAndFaces) {
  check_surface_gradients(MeshLeaf::load(test::cgal_mesh("bunny00.off")), 0.05, 400);
}

// Exactly on the box's corner the gradient is the inward pseudo-normal: the diagonal.
TEST(MeshGradient, BoxCornerGradientIsTheDiagonal) {
  Builder b(0.5);
  const Tree tree = b.build(b.mesh(box_leaf(), {0.3, 1.0}));
  for (const dvec3& p : {dvec3(1, 1, 1), dvec3(-1, 1, -1)}) {
    EXPECT_GT(cosine(tree.gradient(p), -p), 1 - 1e-6);
    EXPECT_GT(cosine(tree.reference_gradient(p), -p), 1 - 1e-9);
  }
  // An edge midpoint: the bisector of its two faces.
  EXPECT_GT(cosine(tree.reference_gradient(dvec3(1, 0, 1)), dvec3(-1, 0, -1)), 1 - 1e-9);
}

// The tape's gradient loop carries state from point to point (a bound from the previous point's
// nearest point, a far point's side passed on): rows of points a fiftieth of the box apart,
// across the bunny and beyond its radius, answer as each point does alone, bit for bit.
TEST(MeshGradient, RowsAnswerAsPointsAlone) {
  Builder b(0.5);
  const auto leaf = MeshLeaf::load(test::cgal_mesh("bunny00.off"));
  const double diag = glm::length(leaf->bounds().size());
  const Tree tree = b.build(b.mesh(leaf, {0.05 * diag}));
  std::vector<dvec3> pts;
  for (int row = 0; row < 64; ++row) {
    const double y = leaf->bounds().lo.y + leaf->bounds().size().y * (row % 8 + 0.5) / 8.0;
    const double z = leaf->bounds().lo.z + leaf->bounds().size().z * (row / 8 + 0.5) / 8.0;
    for (int i = 0; i < 64; ++i) pts.push_back({leaf->bounds().lo.x - 0.2 * diag + 0.02 * diag * i, y, z});
  }
  const TapeEvaluator& tape = tree.evaluator();
  std::vector<dvec3> together(pts.size());
  std::vector<double> values(pts.size());
  tape.gradient(pts, values, together);
  std::size_t inside = 0, far = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    dvec3 alone;
    double value;
    tape.gradient(std::span(&pts[i], 1), std::span(&value, 1), std::span(&alone, 1));
    ASSERT_EQ(values[i], value) << i;  // beyond the radius only the side tells 0 from the plateau
    ASSERT_EQ(together[i], alone) << i;
    inside += value > 0.99;
    far += value == 0.0;
  }
  EXPECT_GT(inside, 100u);
  EXPECT_GT(far, 100u);
}

}  // namespace
}  // namespace ht
