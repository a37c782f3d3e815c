// A brick's octants, as PolygonizeOptions::brick_filter names them (meshers/polygonize.hpp).
#include "meshers/polygonize.hpp"

#include "runtime/tape.hpp"

namespace ht {

Aabb octants::of(const Aabb& box, int k) {
  const glm::dvec3 mid = box.center();
  Aabb out;
  for (int a = 0; a < 3; ++a) {
    const bool upper = (k >> a) & 1;
    out.lo[a] = upper ? mid[a] : box.lo[a];
    out.hi[a] = upper ? box.hi[a] : mid[a];
  }
  return out;
}

std::uint8_t octants::crossing(const Graph& graph, NodeId node, double threshold, const Aabb& brick, double margin) {
  // The polygonizer's rule for a brick (meshers/polygonize.cpp classify): decided when the whole
  // range lies below T or at or above it.
  auto may_cross = [&](const Aabb& box) {
    const Interval iv = field_interval(graph, node, threshold, box.expanded(margin), false);
    return iv.lo < threshold && iv.hi >= threshold;
  };
  if (!may_cross(brick)) return 0;
  std::uint8_t mask = 0;
  for (int k = 0; k < 8; ++k)
    if (may_cross(of(brick, k))) mask = std::uint8_t(mask | (1u << k));
  return mask;
}

}  // namespace ht
