// A scalar function over a batch of points, the form in which meshers pass fields around (a
// tape, an operand's field shifted to a cut's zero, a SurfaceField's bricks).
#pragma once

#include <glm/vec3.hpp>

#include <functional>
#include <span>

namespace ht {

class SurfaceField;
class TapeEvaluator;

/// Writes one value per point. It must be deterministic and may be called from any thread.
using BatchField = std::function<void(std::span<const glm::dvec3> points, std::span<double> values)>;

/// Writes one value (when `values` is not empty) and one gradient per point; the same contract.
using BatchGradient =
    std::function<void(std::span<const glm::dvec3> points, std::span<double> values, std::span<glm::dvec3> gradients)>;

/// A tape's gradients (it must outlive the function).
BatchGradient gradient_of(const TapeEvaluator& tape);
/// A SurfaceField's gradients, on its bricks' tapes (it must outlive the function).
BatchGradient gradient_of(SurfaceField& field);

}  // namespace ht
