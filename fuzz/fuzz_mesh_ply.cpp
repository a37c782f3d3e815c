// fuzz_mesh_ply: bytes as a .ply file through MeshLeaf::load (fuzz/fuzz_support.hpp mesh_input).
#include "fuzz/fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return ht::fuzz::mesh_input(data, size, ".ply");
}
