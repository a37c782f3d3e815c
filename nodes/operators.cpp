#include "nodes/operators.hpp"

#include <glm/geometric.hpp>

namespace ht {

double crop_reach(const double* b) {
  return 0.5 * std::min({b[3] - b[0], b[4] - b[1], b[5] - b[2]});
}

double crop_box_field(const double* b, double T, const glm::dvec3& p) {
  const glm::dvec3 lo(b[0], b[1], b[2]), hi(b[3], b[4], b[5]);
  const glm::dvec3 center = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
  const glm::dvec3 q = glm::abs(p - center) - half;
  const double outside = glm::length(glm::max(q, glm::dvec3(0.0)));
  const double inside = std::min(std::max(q.x, std::max(q.y, q.z)), 0.0);
  const double s = outside + inside;
  return T * (1.0 - s / crop_reach(b));
}

}  // namespace ht
