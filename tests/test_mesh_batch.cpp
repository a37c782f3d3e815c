// MeshLeaf::query_batch answers every block of points as query() answers each point: distance
// (within the radius, else infinity) and inside, for blocks near the surface, far from it inside
// and outside, straddling it, and scattered at random; closed and winding leaves.
#include "nodes/mesh_leaf.hpp"
#include "tests/support/test_support.hpp"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

using namespace ht;

namespace {

// Blocks of 8 x 8 x 4 points `step` apart at random places of the mesh's box grown by a tenth,
// and blocks of 256 random points of the box.
void expect_batch_equals_points(const MeshLeaf& leaf, const std::string& what) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Aabb box = leaf.bounds().expanded(0.1 * glm::length(leaf.bounds().size()));
  const double diag = glm::length(box.size());
  std::size_t far_blocks = 0, inside_points = 0;
  for (int block = 0; block < 300; ++block) {
    std::vector<float> xs(256), ys(256), zs(256);
    const bool scattered = block % 5 == 0;
    const double step = diag * (block % 3 == 0 ? 0.002 : 0.01);
    const glm::dvec3 at = box.lo + glm::dvec3(u(rng), u(rng), u(rng)) * box.size();
    for (int i = 0; i < 256; ++i) {
      const glm::dvec3 p = scattered ? box.lo + glm::dvec3(u(rng), u(rng), u(rng)) * box.size()
                                     : at + step * glm::dvec3(i % 8, (i / 8) % 8, i / 64);
      xs[std::size_t(i)] = float(p.x), ys[std::size_t(i)] = float(p.y), zs[std::size_t(i)] = float(p.z);
    }
    const float radius = float(diag * (block % 2 == 0 ? 0.01 : 0.03));
    std::vector<float> d(256);
    std::vector<std::uint8_t> in(256);
    leaf.query_batch(xs.data(), ys.data(), zs.data(), 256, radius, d.data(), in.data());
    bool all_far = true;
    for (int i = 0; i < 256; ++i) {
      const MeshLeaf::Closest c = leaf.query({xs[std::size_t(i)], ys[std::size_t(i)], zs[std::size_t(i)]}, double(radius));
      const float want = std::isfinite(c.distance) ? float(c.distance) : std::numeric_limits<float>::infinity();
      ASSERT_EQ(d[std::size_t(i)], want) << what << " block " << block << " point " << i;
      ASSERT_EQ(in[std::size_t(i)], c.inside ? 1 : 0) << what << " block " << block << " point " << i;
      all_far &= !std::isfinite(c.distance);
      inside_points += in[std::size_t(i)];
    }
    far_blocks += all_far ? 1 : 0;
  }
  // Both kinds of block were met: the shared answer and the per-point one.
  EXPECT_GT(far_blocks, 30u) << what;
  EXPECT_LT(far_blocks, 270u) << what;
  EXPECT_GT(inside_points, 1000u) << what;
}

}  // namespace

TEST(MeshBatch, BlocksAnswerAsTheirPointsOnClosedMeshes) {
  for (const char* name : {"bunny00.off", "eight.off", "knot2.off"}) {
    const auto leaf = MeshLeaf::load(test::cgal_mesh(name));
    expect_batch_equals_points(*leaf, name);
  }
}

TEST(MeshBatch, BlocksAnswerAsTheirPointsOnWindingMeshes) {
  // eight.off with every 40th triangle removed: open, decided by its winding number, which the
  // batch may not share across a block.
  const auto closed = MeshLeaf::load(test::cgal_mesh("eight.off"));
  std::vector<glm::uvec3> tris;
  for (std::size_t t = 0; t < closed->triangles().size(); ++t)
    if (t % 40 != 0) tris.push_back(closed->triangles()[t]);
  const auto open = MeshLeaf::from_triangles(closed->positions(), tris, "eight with holes", false, MeshInside::Winding);
  expect_batch_equals_points(*open, "eight with holes");
}
