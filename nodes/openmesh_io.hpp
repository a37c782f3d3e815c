// The one lock around OpenMesh's file IO, shared by every part of HybridTree that reads or
// writes meshes through it (nodes/mesh_leaf.cpp, meshers/mesh_io.cpp).
#pragma once

#include <mutex>

namespace ht {

/// Held for the whole of every OpenMesh::IO::read_mesh and write_mesh call, on any thread.
/// OpenMesh keeps one process-wide registry of readers and writers (IOManager), the readers
/// and writers are singletons with state of their own (the OBJ reader keeps materials), and its
/// messages go to process-wide streams (omerr, omlog, omout) that the reader mutes and
/// restores. None of that is thread-safe, so reads and writes must be serialised against each
/// other, not only reads against reads: hence one mutex for both, not one per room.
/// An inline function's static is one object in the whole program, whichever file calls it.
inline std::mutex& openmesh_io_mutex() {
  static std::mutex m;
  return m;
}

}  // namespace ht
