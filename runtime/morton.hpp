// Spatial order of a batch of points along a Morton curve of its box: what lets the tape's
// Skip guards skip whole blocks when the caller's points come in no order.
#pragma once

#include <glm/common.hpp>
#include <glm/vec3.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace ht::morton {

inline std::uint64_t spread_bits(std::uint32_t v) {  // 10 bits to every third of 30
  std::uint64_t x = v & 0x3ffu;
  x = (x | x << 16) & 0x30000ffull;
  x = (x | x << 8) & 0x300f00full;
  x = (x | x << 4) & 0x30c30c3ull;
  x = (x | x << 2) & 0x9249249ull;
  return x;
}

/// The indices 0..n-1 ordered by the Morton code of coord(i) (a glm::vec3) in the box of all
/// points, 10 bits an axis; ties by index, so the order is total and the same at any thread
/// count. NaN coordinates count as the box's low end.
template <class Coord>
std::vector<std::uint32_t> order(std::size_t n, Coord coord) {
  glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  for (std::size_t i = 0; i < n; ++i) {
    const glm::vec3 p = coord(i);
    lo = glm::min(lo, p);  // NaN coordinates leave the box as it is
    hi = glm::max(hi, p);
  }
  const glm::vec3 extent = hi - lo;
  std::vector<std::uint64_t> keys(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const glm::vec3 p = coord(i);
      std::uint64_t code = 0;
      for (int a = 0; a < 3; ++a) {
        const float t = extent[a] > 0.0f ? (p[a] - lo[a]) / extent[a] : 0.0f;
        const float q = t >= 0.0f ? std::min(t, 1.0f) * 1023.0f : 0.0f;  // NaN falls to 0
        code |= spread_bits(static_cast<std::uint32_t>(q)) << a;
      }
      keys[i] = code << 32 | i;
    }
  });
  tbb::parallel_sort(keys.begin(), keys.end());
  std::vector<std::uint32_t> out(n);
  for (std::size_t i = 0; i < n; ++i) out[i] = static_cast<std::uint32_t>(keys[i]);
  return out;
}

}  // namespace ht::morton
