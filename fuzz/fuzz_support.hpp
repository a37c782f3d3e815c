// What the fuzz targets (fuzz/fuzz_*.cpp) share: the verdict on an input, a scratch file for
// readers that only take paths, and the mesh readers' target itself.
//
// A target accepts an input when the code under test either succeeds and its result passes the
// target's checks, or refuses it with the documented error (MeshError, SceneError). Anything
// else is a finding and stops the process through finding(): under libFuzzer that is a crash it
// records with the input, in the replay tests (fuzz/replay_main.cpp) a failed test.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace ht::fuzz {

/// Prints "finding: what" to stderr and aborts.
[[noreturn]] void finding(const std::string& what);

/// Calls finding() when `ok` is false.
inline void require(bool ok, const std::string& what) {
  if (!ok) finding(what);
}

/// A file of this process's own folder (under the system's temporary folder, removed at exit)
/// holding exactly `bytes`; `name` is its file name, so its extension picks the reader. The same
/// name is rewritten by every call.
std::filesystem::path scratch_file(const std::string& name, std::string_view bytes);

/// The folder of small committed meshes the scene target may name (fuzz/meshes/).
std::filesystem::path mesh_dir();

/// The mesh readers' target: `data` as a mesh file with extension `ext` (".off", ".obj", ".ply",
/// ".stl") through MeshLeaf::load, without repair and, when that refuses it, with repair; a
/// loaded leaf is checked, queried at a few points and written and read back.
int mesh_input(const std::uint8_t* data, std::size_t size, const std::string& ext);

/// Inputs larger than this are skipped (returns 0 at once): one input must run in well under a
/// second under the sanitizers, and the bugs worth finding fit in a few kilobytes.
inline constexpr std::size_t kMaxInputBytes = 64 * 1024;

}  // namespace ht::fuzz

/// libFuzzer's entry point, defined by each fuzz/fuzz_*.cpp.
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);
