#include "meshers/brick_region.hpp"

#include "runtime/tape_eval.hpp"

#include <algorithm>
#include <cmath>

namespace ht::brick {

void sum_operands(std::span<const std::shared_ptr<const Tape>> operands, const float* xs, const float* ys,
                  const float* zs, int n, float* value, float* region) {
  float f[kBlock], largest[kBlock];
  for (int i = 0; i < n; ++i) value[i] = 0.0f, region[i] = 0.0f, largest[i] = 0.0f;
  for (const auto& tape : operands) {
    TapeEvaluator(tape).field_block(xs, ys, zs, n, f);
    for (int i = 0; i < n; ++i) {
      value[i] += f[i];
      region[i] += std::abs(f[i]);
      largest[i] = std::max(largest[i], std::abs(f[i]));
    }
  }
  for (int i = 0; i < n; ++i) region[i] -= largest[i];
}

void region_cells(const float* region, std::uint8_t* keep) {
  auto acts = [region](int i, int j, int k) { return region[i + kPoints * (j + kPoints * k)] > 0.0f; };  // NaN: no
  for (int k = 0; k < kCells; ++k)
    for (int j = 0; j < kCells; ++j)
      for (int i = 0; i < kCells; ++i) {
        bool any = false;
        for (int c = 0; c < 8 && !any; ++c) any = acts(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
        keep[i + kCells * (j + kCells * k)] = any ? 1 : 0;
      }
}

}  // namespace ht::brick
