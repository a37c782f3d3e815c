// The grid's overlapping box pairs (meshers/box_pairs.hpp) against all pairs compared directly:
// boxes on a coarse lattice of coordinates, so that many touch exactly (a shared face, edge or
// corner counts), some skipped; each pair once; and a grid that would be too sparse declines.
#include "meshers/box_pairs.hpp"
#include "tests/support/test_support.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <mutex>
#include <span>
#include <random>
#include <vector>

namespace ht {
namespace {

using glm::dvec3;
using test::Rng;
using test::seeded;

std::vector<std::uint64_t> brute_force(const std::vector<dvec3>& lo, const std::vector<dvec3>& hi,
                                       const std::vector<std::uint8_t>& skip) {
  std::vector<std::uint64_t> out;
  for (std::size_t i = 0; i < lo.size(); ++i)
    for (std::size_t j = i + 1; j < lo.size(); ++j) {
      bool meet = !skip[i] && !skip[j];
      for (int k = 0; k < 3 && meet; ++k) meet = lo[i][k] <= hi[j][k] && lo[j][k] <= hi[i][k];
      if (meet) out.push_back(std::uint64_t(i) << 32 | j);
    }
  return out;
}

TEST(BoxPairs, GridFindsEveryOverlapOnce) {
  Rng rng = seeded();
  std::uniform_int_distribution<int> at(0, 40), side(0, 6);
  std::uniform_int_distribution<int> coin(0, 9);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<dvec3> lo(600), hi(600);
    std::vector<std::uint8_t> skip(600);
    for (std::size_t i = 0; i < lo.size(); ++i) {
      // Quarter units: exact in double, so boxes share faces, edges and corners exactly.
      lo[i] = 0.25 * dvec3(at(rng), at(rng), at(rng)) - dvec3(3.0);
      hi[i] = lo[i] + 0.25 * dvec3(side(rng), side(rng), side(rng));
      skip[i] = coin(rng) == 0;
    }
    const auto lists = grid_box_pairs(lo, hi, skip);
    ASSERT_TRUE(lists.has_value()) << trial;
    std::vector<std::uint64_t> got;
    for (const auto& l : *lists) got.insert(got.end(), l.begin(), l.end());
    std::sort(got.begin(), got.end());
    EXPECT_EQ(std::adjacent_find(got.begin(), got.end()), got.end()) << "a pair reported twice, trial " << trial;
    EXPECT_EQ(got, brute_force(lo, hi, skip)) << trial;
  }
}

// Boxes that all meet one cell (a fan of long thin triangles around one vertex): the square of
// them are pairs, handed over in bounded batches (one batch held the 2 GB of a 20,000-triangle
// fan's pairs before), each pair once.
TEST(BoxPairs, ACrowdedCellHandsItsPairsOverInBatches) {
  Rng rng = seeded();
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<dvec3> lo, hi;
  for (int i = 0; i < 1500; ++i) {  // long thin boxes from the origin outward
    const dvec3 end(u(rng), u(rng), u(rng)), side = 0.01 * dvec3(u(rng), u(rng), u(rng));
    lo.push_back(glm::min(dvec3(0.0), glm::min(end, end + side)));
    hi.push_back(glm::max(dvec3(0.0), glm::max(end, end + side)));
  }
  const std::vector<std::uint8_t> skip(lo.size(), 0);
  std::mutex m;
  std::vector<std::uint64_t> all;
  std::size_t largest = 0, batches = 0;
  const bool gridded = grid_box_pairs(lo, hi, skip, [&](std::span<const std::uint64_t> batch) {
    const std::lock_guard lock(m);
    all.insert(all.end(), batch.begin(), batch.end());
    largest = std::max(largest, batch.size());
    ++batches;
  }, BoxPairOptions{1e9, 1e9});
  ASSERT_TRUE(gridded);
  std::sort(all.begin(), all.end());
  EXPECT_EQ(all, brute_force(lo, hi, skip));
  EXPECT_EQ(all.size(), 1500u * 1499u / 2u);  // every box holds the origin
  EXPECT_LE(largest, std::size_t(1) << 16);
  EXPECT_GT(batches, 10u);
}

TEST(BoxPairs, SparseBoxesDecline) {
  // Two small boxes a million sides apart: the grid would be almost all empty cells.
  const std::vector<dvec3> lo{dvec3(0.0), dvec3(1e6)}, hi{dvec3(1.0), dvec3(1e6 + 1.0)};
  const std::vector<std::uint8_t> skip(2, 0);
  EXPECT_FALSE(grid_box_pairs(lo, hi, skip).has_value());
}

}  // namespace
}  // namespace ht
