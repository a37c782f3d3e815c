// A Curve instruction's evaluation over a block of lanes (runtime/tape_eval.cpp's own: included
// by it alone, inlined into each instruction-set build of its loops). A curve's polyline has
// dozens of segments and most points of a block lie outside its support, so the lanes inside the
// support box are gathered into a dense list first, and then those within some group's ball:
// the segments run over full vectors of points that need them (points in no order, as a user's
// batch, leave one or two lanes of sixteen inside); the others are 0 at once.
#pragma once

#include "runtime/tape.hpp"
#include "runtime/tape_eval.hpp"
#include "runtime/tape_ops.hpp"

#include <algorithm>
#include <cstdint>
#include <limits>
#include <type_traits>

#ifndef HT_LANE
#define HT_LANE [[gnu::always_inline]] inline
#endif

namespace ht::tape_curve {

using tape_ops::Dual;
using tape_ops::V3;
using namespace tape_ops;

constexpr int kChunk = 16;
static_assert(kBlock % kChunk == 0, "blocks hold whole chunks");

HT_LANE bool in_box(float x, float y, float z, const float* box) {
  return (x >= box[0]) & (x <= box[3]) & (y >= box[1]) & (y <= box[4]) & (z >= box[2]) & (z <= box[5]);
}

// Squared distance from a chunk's box (lo, hi) to a segment group's box (lo(3) hi(3)).
HT_LANE float box_gap2(const float* lo, const float* hi, const float* group) {
  float e2 = 0.0f;
  for (int a = 0; a < 3; ++a) {
    const float e = std::max(std::max(group[a] - hi[a], lo[a] - group[3 + a]), 0.0f);
    e2 += e * e;
  }
  return e2;
}

// The squared distance from each of `padded` gathered lanes (whole chunks) to its nearest
// segment and, for gradients, that segment's index. A chunk runs first the group of segments
// whose box is nearest its own, then only the groups whose box comes nearer than the farthest of
// its lanes' distances so far (capped by R^2, where the falloff ends): a farther group cannot
// hold a lane's nearest segment where the field is nonzero. The slack covers float rounding.
// Where a curve's parts lie among its constants (runtime/tape.hpp).
struct CurveParts {
  int segments, groups;
  const float* boxes;  // 6 a group
  const float* balls;  // 4 a group: centre, reach^2
  const float* seg;    // 7 a segment
};
HT_LANE CurveParts curve_parts(const float* k) {
  CurveParts c{};
  c.segments = static_cast<int>(k[10]);
  c.groups = (c.segments + kCurveGroup - 1) / kCurveGroup;
  c.boxes = k + 11;
  c.balls = c.boxes + 6 * c.groups;
  c.seg = c.balls + 4 * c.groups;
  return c;
}

template <bool kWhich>
HT_LANE void nearest_segments(const float* gx, const float* gy, const float* gz, int padded, const float* k, float* d,
                              int* at) {
  const CurveParts parts = curve_parts(k);
  const int segments = parts.segments, groups = parts.groups;
  const float* boxes = parts.boxes;
  const float* seg = parts.seg;
  for (int c0 = 0; c0 < padded; c0 += kChunk) {
    float lo[3] = {gx[c0], gy[c0], gz[c0]}, hi[3] = {gx[c0], gy[c0], gz[c0]};
    for (int j = c0; j < c0 + kChunk; ++j) {
      lo[0] = std::min(lo[0], gx[j]), hi[0] = std::max(hi[0], gx[j]);
      lo[1] = std::min(lo[1], gy[j]), hi[1] = std::max(hi[1], gy[j]);
      lo[2] = std::min(lo[2], gz[j]), hi[2] = std::max(hi[2], gz[j]);
      d[j] = std::numeric_limits<float>::max();
      if constexpr (kWhich) at[j] = 0;
    }
    auto run = [&](int g) {
      for (int i = g * kCurveGroup; i < std::min(segments, (g + 1) * kCurveGroup); ++i) {
        const float* q = seg + 7 * i;
        for (int j = c0; j < c0 + kChunk; ++j) {  // vectorized in every build
          const float dist = segment2(V3<float>{gx[j], gy[j], gz[j]}, q);
          if constexpr (kWhich) at[j] = dist < d[j] ? i : at[j];
          // min_(d[j], dist) written with its own comparison: sharing the one above makes GCC
          // keep a branch on the 16-byte builds.
          d[j] = d[j] <= dist ? d[j] : dist;
        }
      }
    };
    int first = 0;
    float nearest = std::numeric_limits<float>::infinity();
    for (int g = 0; g < groups; ++g) {
      const float e2 = box_gap2(lo, hi, boxes + 6 * g);
      if (e2 < nearest) nearest = e2, first = g;
    }
    run(first);
    for (int g = 0; g < groups; ++g) {
      if (g == first) continue;
      float far = 0.0f;
      for (int j = c0; j < c0 + kChunk; ++j) far = std::max(far, d[j]);
      if (box_gap2(lo, hi, boxes + 6 * g) > std::min(far, k[0]) * 1.0001f + 1e-12f) continue;
      run(g);
    }
  }
}

// The lanes of a block inside the support box, listed chunk by chunk (a chunk with none inside
// skipped whole), then padded with the first one's index to whole chunks. Returns the count.
template <class T>
HT_LANE int gather_lanes(const T* x, const T* y, const T* z, int n, int count, const float* box, std::uint16_t* lane,
                         int& padded) {
  alignas(64) std::uint8_t inside[kBlock];
  for (int i = 0; i < n; ++i) inside[i] = in_box(val(x[i]), val(y[i]), val(z[i]), box) & (i < count);
  int m = 0;
  for (int c0 = 0; c0 < n; c0 += kChunk) {
    const int c1 = std::min(c0 + kChunk, n);
    std::uint8_t any = 0;
    for (int i = c0; i < c1; ++i) any |= inside[i];
    if (!any) continue;
    for (int i = c0; i < c1; ++i) {
      lane[m] = static_cast<std::uint16_t>(i);
      m += inside[i];
    }
  }
  padded = (m + kChunk - 1) / kChunk * kChunk;
  for (int j = m; j < padded; ++j) lane[j] = lane[0];
  return m;
}

// Of the m gathered lanes, those within some group's ball, moved to the front (their order
// kept) and padded as gather_lanes pads. In the support box of a short curve (the snake's are a
// tenth of their radius long) half the lanes lie outside the ball: they are 0 with no segment
// run. Returns their count.
HT_LANE int keep_within_balls(const CurveParts& parts, float* gx, float* gy, float* gz, int m, std::uint16_t* lane,
                              int& padded) {
  alignas(64) std::uint8_t near[kBlock + kChunk];
  for (int j = 0; j < padded; ++j) near[j] = 0;
  for (int g = 0; g < parts.groups; ++g) {
    const float* ball = parts.balls + 4 * g;
    for (int j = 0; j < padded; ++j) {  // vectorized in every build
      const float dx = gx[j] - ball[0], dy = gy[j] - ball[1], dz = gz[j] - ball[2];
      near[j] |= static_cast<std::uint8_t>(dx * dx + dy * dy + dz * dz < ball[3]);
    }
  }
  int kept = 0;
  for (int j = 0; j < m; ++j) {
    lane[kept] = lane[j];
    gx[kept] = gx[j], gy[kept] = gy[j], gz[kept] = gz[j];
    kept += near[j];
  }
  if (kept == 0) return 0;
  padded = (kept + kChunk - 1) / kChunk * kChunk;
  for (int j = kept; j < padded; ++j) lane[j] = lane[0], gx[j] = gx[0], gy[j] = gy[0], gz[j] = gz[0];
  return kept;
}

/// A Curve instruction over n lanes (count of them holding points) of a block: the frame's
/// coordinates x, y, z, the result in out, k the instruction's constants.
template <class T>
HT_LANE void curve_loop(const T* x, const T* y, const T* z, T* out, int n, int count, const float* k) {
  for (int i = 0; i < n; ++i) out[i] = T(0.0f);
  std::uint16_t lane[kBlock + kChunk];
  int padded = 0;
  int m = gather_lanes(x, y, z, n, count, k + 4, lane, padded);
  if (m == 0) return;
  alignas(64) float gx[kBlock + kChunk], gy[kBlock + kChunk], gz[kBlock + kChunk], d[kBlock + kChunk];
  alignas(64) int at[kBlock + kChunk];
  for (int j = 0; j < padded; ++j) {
    gx[j] = val(x[lane[j]]);
    gy[j] = val(y[lane[j]]);
    gz[j] = val(z[lane[j]]);
  }
  const CurveParts parts = curve_parts(k);
  m = keep_within_balls(parts, gx, gy, gz, m, lane, padded);
  if (m == 0) return;
  const float* seg = parts.seg;
  constexpr bool kGradients = std::is_same_v<T, Dual>;
  if constexpr (kGradients) {
    nearest_segments<true>(gx, gy, gz, padded, k, d, at);
    // The min's derivative is its argument's: the nearest segment differentiated alone.
    for (int j = 0; j < m; ++j) {
      const int i = lane[j];
      out[i] = falloff2(segment2(V3<Dual>{x[i], y[i], z[i]}, seg + 7 * at[j]), k);
    }
  } else {
    // Values: one long vector loop per segment over every gathered lane runs faster than
    // skipping groups chunk by chunk (a brick's chunks rarely lie beyond a group).
    const int segments = parts.segments;
    for (int j = 0; j < padded; ++j) d[j] = std::numeric_limits<float>::max();
    for (int i = 0; i < segments; ++i)
      for (int j = 0; j < padded; ++j) d[j] = min_(d[j], segment2(V3<float>{gx[j], gy[j], gz[j]}, seg + 7 * i));  // vectorized in every build
    for (int j = 0; j < m; ++j) out[lane[j]] = falloff2(d[j], k);
  }
}

}  // namespace ht::tape_curve
