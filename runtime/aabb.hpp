// Axis-aligned boxes, in double: the support of a node's field and the extent of a mesh.
#pragma once

#include <glm/vec3.hpp>
#include <glm/common.hpp>

#include <limits>

namespace ht {

struct Aabb {
  glm::dvec3 lo{std::numeric_limits<double>::infinity()};
  glm::dvec3 hi{-std::numeric_limits<double>::infinity()};

  static Aabb everything() {
    const double inf = std::numeric_limits<double>::infinity();
    return {glm::dvec3(-inf), glm::dvec3(inf)};
  }
  bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
  bool finite() const {
    return !empty() && glm::all(glm::lessThan(glm::abs(lo), glm::dvec3(1e300))) &&
           glm::all(glm::lessThan(glm::abs(hi), glm::dvec3(1e300)));
  }
  bool contains(const glm::dvec3& p) const {
    return p.x >= lo.x && p.y >= lo.y && p.z >= lo.z && p.x <= hi.x && p.y <= hi.y && p.z <= hi.z;
  }
  void grow(const glm::dvec3& p) { lo = glm::min(lo, p); hi = glm::max(hi, p); }
  Aabb expanded(double r) const { return empty() ? *this : Aabb{lo - r, hi + r}; }
  glm::dvec3 center() const { return 0.5 * (lo + hi); }
  glm::dvec3 size() const { return hi - lo; }
};

/// The box's volume: 0 when empty, infinite when unbounded.
inline double volume(const Aabb& box) {
  if (box.empty()) return 0.0;
  if (!box.finite()) return std::numeric_limits<double>::infinity();
  const glm::dvec3 s = box.size();
  return s.x * s.y * s.z;
}

inline Aabb merge(const Aabb& a, const Aabb& b) { return {glm::min(a.lo, b.lo), glm::max(a.hi, b.hi)}; }
inline Aabb intersect(const Aabb& a, const Aabb& b) { return {glm::max(a.lo, b.lo), glm::min(a.hi, b.hi)}; }

}  // namespace ht
