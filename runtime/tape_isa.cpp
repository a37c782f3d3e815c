// Which instruction set the tape's value path runs on: the widest this CPU has, or the one the
// environment (HYBRIDTREE_TAPE_ISA) or force_tape_isa names (runtime/tape_eval.hpp).
#include "runtime/tape_eval.hpp"

#include <atomic>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <string_view>

namespace ht {
namespace {

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define HT_X86_BUILDS 1
#endif

TapeIsa widest_supported() {
  for (const TapeIsa isa : {TapeIsa::Avx512, TapeIsa::Avx2, TapeIsa::Sse4})
    if (tape_isa_supported(isa)) return isa;
  return TapeIsa::Baseline;
}

TapeIsa from_environment() {
  const char* want = std::getenv("HYBRIDTREE_TAPE_ISA");
  if (!want || !*want) return widest_supported();
  for (const TapeIsa isa : {TapeIsa::Avx512, TapeIsa::Avx2, TapeIsa::Sse4, TapeIsa::Baseline})
    if (std::string_view(want) == tape_isa_name(isa)) {
      if (!tape_isa_supported(isa))
        throw std::invalid_argument(std::string("HYBRIDTREE_TAPE_ISA=") + want + ": this CPU cannot run it");
      return isa;
    }
  throw std::invalid_argument(std::string("HYBRIDTREE_TAPE_ISA=") + want + ": not one of avx512, avx2, sse4, baseline");
}

std::atomic<int> g_isa{-1};  // the TapeIsa in use, -1 until the first call

}  // namespace

const char* tape_isa_name(TapeIsa isa) {
  switch (isa) {
    case TapeIsa::Avx512: return "avx512";
    case TapeIsa::Avx2: return "avx2";
    case TapeIsa::Sse4: return "sse4";
    case TapeIsa::Baseline: return "baseline";
  }
  return "baseline";
}

bool tape_isa_supported(TapeIsa isa) {
#ifdef HT_X86_BUILDS
  switch (isa) {
    case TapeIsa::Avx512:
      return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
             __builtin_cpu_supports("avx512dq") && __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("fma") &&
             __builtin_cpu_supports("bmi2");
    case TapeIsa::Avx2: return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") && __builtin_cpu_supports("bmi2");
    case TapeIsa::Sse4: return __builtin_cpu_supports("sse4.2") && __builtin_cpu_supports("popcnt");
    case TapeIsa::Baseline: return true;
  }
  return false;
#else
  return isa == TapeIsa::Baseline;
#endif
}

TapeIsa tape_isa() {
  int isa = g_isa.load(std::memory_order_acquire);
  if (isa < 0) {
    int expected = -1;
    g_isa.compare_exchange_strong(expected, static_cast<int>(from_environment()), std::memory_order_acq_rel);
    isa = g_isa.load(std::memory_order_acquire);
  }
  return static_cast<TapeIsa>(isa);
}

void force_tape_isa(TapeIsa isa) {
  if (!tape_isa_supported(isa))
    throw std::invalid_argument(std::string("force_tape_isa: this CPU cannot run ") + tape_isa_name(isa));
  g_isa.store(static_cast<int>(isa), std::memory_order_release);
}

}  // namespace ht
