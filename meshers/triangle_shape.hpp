// Shape measures of one triangle, for the meshers that judge collapses and flips by the shapes
// they leave (the quality pass, the remesher). Pure functions; no allocation.
#pragma once

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>

namespace ht {

/// The cosine of the smallest corner angle of triangle abc (the angle opposite the shortest side):
/// 0.5 for an equilateral triangle, 1 for a degenerate one. Cosines order angles the other way
/// round, without atan2 or acos.
inline double thinness(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
  // Law of cosines with the two longer sides.
  const double x = glm::dot(b - c, b - c), y = glm::dot(c - a, c - a), z = glm::dot(a - b, a - b);
  const double shortest = std::min({x, y, z}), longest = std::max({x, y, z});
  const double middle = std::max(std::min(x, y), std::min(std::max(x, y), z));
  const double den = 2.0 * std::sqrt(middle * longest);
  return den > 0 ? (middle + longest - shortest) / den : 1.0;
}

/// The unit normal of abc by the right hand (counter-clockwise seen from its front); zero when
/// the triangle is degenerate.
inline glm::dvec3 unit_normal(const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
  const glm::dvec3 n = glm::cross(b - a, c - a);
  const double l = glm::length(n);
  return l > 0 ? n / l : glm::dvec3(0.0);
}

}  // namespace ht
