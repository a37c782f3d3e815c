// Evaluates a tape over many points: float32, blocks of kBlock points in structure-of-arrays
// registers, each instruction a loop over the block's lanes; TBB spreads blocks over threads.
// Values come from a build for the widest vectors the CPU has (AVX-512, AVX2, SSE4.2 or
// baseline x86-64, chosen at run time; see TapeIsa); gradients come from forward-mode differentiation of the same lane
// code (runtime/tape_ops.hpp).
//
// Thread-safe: one evaluator may serve many threads. Each thread keeps one workspace (the
// register file of a block) for every evaluator, grown to the largest tape it has run, so making
// an evaluator and steady-state calls allocate nothing. Results do not depend on the number of
// threads (every point is computed the same way whatever block it lands in).
#pragma once

#include "runtime/tape.hpp"

#include <glm/vec3.hpp>

#include <cstdint>
#include <memory>
#include <span>

namespace ht {

/// Points per block: registers of this many floats. Measured with bench/tape_bench.cpp on the
/// snake and every-kind scenes: 64 and 256 tie, 128 and 512 are 5-10% slower; 256 halves the
/// per-block overhead of 64.
inline constexpr int kBlock = 256;

/// The instruction sets the value path is built for, widest first. Every build computes the
/// same lanes the same way (no contraction into fused multiply-adds, no reassociation), so
/// values are bit-identical whichever runs; only the speed differs.
enum class TapeIsa : std::uint8_t { Avx512, Avx2, Sse4, Baseline };

/// The instruction set values run on: the one forced (force_tape_isa, or the environment
/// variable HYBRIDTREE_TAPE_ISA = avx512 | avx2 | sse4 | baseline read at first use), else the
/// widest this CPU has. Thread-safe.
TapeIsa tape_isa();
/// "avx512", "avx2", "sse4" or "baseline".
const char* tape_isa_name(TapeIsa isa);
/// Whether this CPU can run `isa`.
bool tape_isa_supported(TapeIsa isa);
/// Makes every evaluator of the process run values on `isa` from now on (tests and benchmarks
/// compare the builds). Throws std::invalid_argument when the CPU cannot run it.
void force_tape_isa(TapeIsa isa);

class TapeEvaluator {
 public:
  explicit TapeEvaluator(std::shared_ptr<const Tape> tape);
  ~TapeEvaluator();
  TapeEvaluator(const TapeEvaluator&) = delete;
  TapeEvaluator& operator=(const TapeEvaluator&) = delete;

  /// n points as coordinate arrays; writes n values. Parallel over blocks.
  void field(const float* x, const float* y, const float* z, std::size_t n, float* values) const;
  /// The same for points as vectors (converted to float).
  void field(std::span<const glm::dvec3> points, std::span<double> values) const;
  /// One point (a block of one lane; prefer the batch forms).
  float field(const glm::dvec3& p) const;
  /// Values and gradients. values may be empty.
  void gradient(std::span<const glm::dvec3> points, std::span<double> values, std::span<glm::dvec3> gradients) const;

  const Tape& tape() const { return *tape_; }
  /// Evaluates one block of at most kBlock points on the calling thread (no TBB): the unit
  /// that meshers and benchmarks drive directly.
  void field_block(const float* x, const float* y, const float* z, int n, float* values) const;

 private:
  std::shared_ptr<const Tape> tape_;
};

}  // namespace ht
