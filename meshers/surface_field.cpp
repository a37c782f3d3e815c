#include "meshers/surface_field.hpp"

#include "runtime/aabb.hpp"
#include "runtime/tape.hpp"
#include "runtime/tape_eval.hpp"

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <numeric>
#include <shared_mutex>
#include <vector>

namespace ht {
namespace {

// Brick coordinates packed 21 bits an axis, offset so that negative bricks pack too.
constexpr std::int64_t kOffset = std::int64_t(1) << 20;
constexpr std::uint64_t kMask = (std::uint64_t(1) << 21) - 1;

std::uint64_t pack(glm::i64vec3 b) {
  auto axis = [](std::int64_t c) { return std::uint64_t(std::clamp<std::int64_t>(c + kOffset, 0, std::int64_t(kMask))); };
  return axis(b.x) | axis(b.y) << 21 | axis(b.z) << 42;
}

glm::i64vec3 unpack(std::uint64_t k) {
  return {std::int64_t(k & kMask) - kOffset, std::int64_t((k >> 21) & kMask) - kOffset, std::int64_t(k >> 42) - kOffset};
}

}  // namespace

SurfaceField::SurfaceField(std::shared_ptr<const Graph> graph, NodeId root, double threshold, glm::dvec3 origin,
                           double brick, bool under_blend)
    : graph_(std::move(graph)), root_(root), threshold_(threshold), origin_(origin), brick_(brick), under_blend_(under_blend) {}

SurfaceField::~SurfaceField() = default;

void SurfaceField::adopt(glm::ivec3 b, std::shared_ptr<const Tape> tape) {
  const std::unique_lock lock(mutex_);
  evaluators_[pack(glm::i64vec3(b))] = std::make_unique<TapeEvaluator>(std::move(tape));
}

std::uint64_t SurfaceField::key_of(const glm::dvec3& p) const {
  const glm::dvec3 c = glm::floor((p - origin_) / brick_);
  // A non-finite point lands in a clamped corner brick; its value comes out non-finite anyway.
  const glm::dvec3 lim(double(kOffset - 1));
  return pack(glm::i64vec3(glm::clamp((std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z)) ? c : glm::dvec3(0.0), -lim, lim)));
}

SurfaceField::Bins SurfaceField::bin(std::span<const glm::dvec3> points) {
  const std::size_t n = points.size();
  Bins b;
  b.order.resize(n);
  tbb::parallel_for(std::size_t(0), n, [&](std::size_t i) { b.order[i] = {key_of(points[i]), std::uint32_t(i)}; });
  tbb::parallel_sort(b.order.begin(), b.order.end());  // keys are unique: one order at any thread count
  for (std::size_t i = 0; i < n; ++i)
    if (i == 0 || b.order[i].first != b.order[i - 1].first) b.runs.push_back(i);
  b.runs.push_back(n);
  const std::size_t bins = b.runs.size() - 1;
  // Compile the bricks met for the first time, in parallel, then file them in order. A brick's
  // tape depends only on the brick, so two callers compiling the same one file equal tapes.
  std::vector<std::uint64_t> missing;
  {
    const std::shared_lock lock(mutex_);
    for (std::size_t r = 0; r < bins; ++r)
      if (!evaluators_.count(b.order[b.runs[r]].first)) missing.push_back(b.order[b.runs[r]].first);
  }
  std::vector<std::unique_ptr<TapeEvaluator>> compiled(missing.size());
  tbb::parallel_for(std::size_t(0), missing.size(), [&](std::size_t i) {
    const glm::dvec3 lo = origin_ + glm::dvec3(unpack(missing[i])) * brick_;
    const Aabb box{lo, lo + glm::dvec3(brick_)};
    compiled[i] = std::make_unique<TapeEvaluator>(
        std::make_shared<const Tape>(compile_tape(graph_, root_, threshold_, &box, under_blend_)));
  });
  // Evaluators are never erased and the map's nodes do not move: the pointers outlive the lock.
  b.eval.resize(bins);
  auto resolve = [&] {
    for (std::size_t r = 0; r < bins; ++r) b.eval[r] = evaluators_.at(b.order[b.runs[r]].first).get();
  };
  if (missing.empty()) {
    const std::shared_lock lock(mutex_);
    resolve();
  } else {
    const std::unique_lock lock(mutex_);
    for (std::size_t i = 0; i < missing.size(); ++i) evaluators_.try_emplace(missing[i], std::move(compiled[i]));
    resolve();
  }
  return b;
}

void SurfaceField::values(std::span<const glm::dvec3> points, std::span<double> values) {
  const Bins b = bin(points);
  tbb::parallel_for(std::size_t(0), b.eval.size(), [&](std::size_t r) {
    // Blocks of a run on this thread, in scratch on the stack: nothing allocated per run.
    float xs[kBlock], ys[kBlock], zs[kBlock], fs[kBlock];
    for (std::size_t at = b.runs[r]; at < b.runs[r + 1]; at += kBlock) {
      const int count = int(std::min<std::size_t>(kBlock, b.runs[r + 1] - at));
      for (int i = 0; i < count; ++i) {
        const glm::dvec3& p = points[b.order[at + std::size_t(i)].second];
        xs[i] = float(p.x), ys[i] = float(p.y), zs[i] = float(p.z);
      }
      b.eval[r]->field_block(xs, ys, zs, count, fs);
      for (int i = 0; i < count; ++i) values[b.order[at + std::size_t(i)].second] = fs[i];
    }
  });
}

void SurfaceField::gradient(std::span<const glm::dvec3> points, std::span<double> values,
                            std::span<glm::dvec3> gradients) {
  const Bins b = bin(points);
  tbb::parallel_for(std::size_t(0), b.eval.size(), [&](std::size_t r) {
    // The run's points gathered on this task's own vectors: the evaluator runs parallel inside,
    // and thread-local scratch would be shared with the tasks this thread takes meanwhile.
    const std::size_t first = b.runs[r], n = b.runs[r + 1] - first;
    std::vector<glm::dvec3> p(n), g(n);
    std::vector<double> f(n);
    for (std::size_t i = 0; i < n; ++i) p[i] = points[b.order[first + i].second];
    b.eval[r]->gradient(p, f, g);
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t at = b.order[first + i].second;
      if (!values.empty()) values[at] = f[i];
      gradients[at] = g[i];
    }
  });
}

}  // namespace ht
