#include "meshers/batch_field.hpp"

#include "meshers/surface_field.hpp"
#include "runtime/tape_eval.hpp"

namespace ht {

BatchGradient gradient_of(const TapeEvaluator& tape) {
  return [&tape](std::span<const glm::dvec3> p, std::span<double> v, std::span<glm::dvec3> g) { tape.gradient(p, v, g); };
}

BatchGradient gradient_of(SurfaceField& field) {
  return [&field](std::span<const glm::dvec3> p, std::span<double> v, std::span<glm::dvec3> g) { field.gradient(p, v, g); };
}

}  // namespace ht
