// A brick's octants, as PolygonizeOptions::brick_filter names them (meshers/polygonize.hpp).
#include "meshers/polygonize.hpp"

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

}  // namespace ht
