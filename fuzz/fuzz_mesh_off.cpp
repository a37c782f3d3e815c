// fuzz_mesh_off: bytes as a .off file through MeshLeaf::load (fuzz/fuzz_support.hpp mesh_input).
#include "fuzz/fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return ht::fuzz::mesh_input(data, size, ".off");
}
