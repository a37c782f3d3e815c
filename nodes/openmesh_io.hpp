// The one lock around OpenMesh's file IO, shared by every part of HybridTree that reads or
// writes meshes through it (nodes/mesh_leaf.cpp, meshers/mesh_io.cpp).
#pragma once

#include <OpenMesh/Core/System/omstream.hh>

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

/// Holds openmesh_io_mutex() and mutes OpenMesh's message streams (omerr, omlog, omout) for
/// its lifetime, restoring those that were on: our own messages say what is wrong, with the file
/// name, and a writer's "[OBJWriter] : write file" is no news to a user. Every OpenMesh read or
/// write runs inside one.
class QuietOpenMesh {
 public:
  QuietOpenMesh()
      : lock_(openmesh_io_mutex()),
        err_(::omerr().is_enabled()),
        log_(::omlog().is_enabled()),
        out_(::omout().is_enabled()) {
    ::omerr().disable();
    ::omlog().disable();
    ::omout().disable();
  }
  ~QuietOpenMesh() {
    if (err_) ::omerr().enable();
    if (log_) ::omlog().enable();
    if (out_) ::omout().enable();
  }
  QuietOpenMesh(const QuietOpenMesh&) = delete;
  QuietOpenMesh& operator=(const QuietOpenMesh&) = delete;

 private:
  std::lock_guard<std::mutex> lock_;
  bool err_, log_, out_;
};

}  // namespace ht
