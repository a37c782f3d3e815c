#include "meshers/off_surface.hpp"

#include "meshers/triangle_shape.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace ht {

namespace {
constexpr double kProbeCells = 0.05;  // a slope's difference quotient spans this many cells
}  // namespace

void OffSurface::project(std::vector<glm::dvec3>& at, std::span<const glm::dvec3> dir, std::span<double> slope,
                         int steps) {
  const std::size_t n = at.size();
  if (n == 0) return;
  const double delta = kProbeCells * h_;
  std::vector<std::uint32_t> unknown;
  for (std::size_t i = 0; i < n; ++i)
    if (!std::isfinite(slope[i])) unknown.push_back(std::uint32_t(i));
  std::vector<glm::dvec3> probe(at);
  for (const std::uint32_t i : unknown) probe.push_back(at[i] + delta * dir[i]);
  std::vector<double> value(probe.size());
  const std::vector<glm::dvec3> start = at;
  for (int s = 0; s < steps; ++s) {
    if (s == 0) {
      field_(probe, value);
      for (std::size_t k = 0; k < unknown.size(); ++k) slope[unknown[k]] = (value[n + k] - value[unknown[k]]) / delta;
    } else {
      field_(at, std::span(value).first(n));
    }
    for (std::size_t i = 0; i < n; ++i) {
      const double step = (T_ - value[i]) / slope[i];
      at[i] += std::clamp(step, -h_, h_) * dir[i];  // NaN stays NaN: a failure
    }
  }
  for (std::size_t i = 0; i < n; ++i)
    if (!(glm::length(at[i] - start[i]) <= 0.2 * h_)) at[i] = glm::dvec3(std::nan(""));
}

const std::vector<double>& OffSurface::points(std::span<const glm::dvec3> at, std::span<const glm::dvec3> dir) {
  const std::size_t n = at.size();
  const double delta = kProbeCells * h_;
  at_.assign(at.begin(), at.end());
  for (std::size_t i = 0; i < n; ++i) at_.push_back(at[i] + delta * dir[i]);
  values_.resize(at_.size());
  off_.resize(n);
  if (n == 0) return off_;
  field_(at_, values_);
  for (std::size_t i = 0; i < n; ++i) {
    const double slope = std::abs(values_[n + i] - values_[i]) / delta;
    off_[i] = slope > 0 ? std::abs(values_[i] - T_) / slope : (values_[i] == T_ ? 0.0 : HUGE_VAL);
  }
  return off_;
}

const std::vector<double>& OffSurface::faces(std::span<const std::array<glm::dvec3, 3>> faces) {
  std::vector<glm::dvec3> middles(faces.size());
  dir_.resize(faces.size());
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const auto& q = faces[i];
    middles[i] = (q[0] + q[1] + q[2]) / 3.0;
    dir_[i] = unit_normal(q[0], q[1], q[2]);
  }
  return points(middles, dir_);
}

}  // namespace ht
