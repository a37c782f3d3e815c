// Where points and faces lie against the surface {f = T}, from field values alone (a gradient
// costs five values; a slope along a known direction costs one more): the quality pass's Newton
// steps and its checks that a step beside a crease keeps faces on the surface
// (meshers/quality.cpp). Lengths are world units; `h` is the precision, which sets the probe's
// length (a twentieth of it). Not thread-safe: each pass owns one (it keeps scratch arrays so
// that its calls allocate nothing once grown).
#pragma once

#include "meshers/batch_field.hpp"

#include <glm/vec3.hpp>

#include <array>
#include <span>
#include <vector>

namespace ht {

class OffSurface {
 public:
  /// `field` must outlive this.
  OffSurface(const BatchField& field, double threshold, double h) : field_(field), T_(threshold), h_(h) {}

  /// `steps` Newton steps toward f = T along each point's direction (a unit vector). slope[i],
  /// the derivative along the direction, comes from a difference quotient where it is not known
  /// (not finite) and is reused after: a vertex's slope changes little as it slides along the
  /// surface. A step is at most h long; a point that ends more than 0.2 h from where it started
  /// (the direction missed the surface, or crossed onto another sheet) or whose step failed
  /// becomes NaN.
  void project(std::vector<glm::dvec3>& at, std::span<const glm::dvec3> dir, std::span<double> slope, int steps);

  /// How far off the surface each point is: |f - T| over the slope along its direction (a unit
  /// vector), a difference quotient; infinite where that slope is 0 and f != T. One batch.
  const std::vector<double>& points(std::span<const glm::dvec3> at, std::span<const glm::dvec3> dir);

  /// The same for each face's middle, along the face's normal.
  const std::vector<double>& faces(std::span<const std::array<glm::dvec3, 3>> faces);

 private:
  const BatchField& field_;
  double T_, h_;
  std::vector<glm::dvec3> at_, dir_;
  std::vector<double> values_, off_;
};

}  // namespace ht
