// A mesh file's bytes, checked and rewritten before OpenMesh's readers see them: what those
// readers do badly, found by the fuzzers of fuzz/ (each case is a test in
// tests/test_mesh_reading.cpp). Used by MeshLeaf::load (nodes/mesh_leaf.cpp).
#pragma once

#include <string>

namespace ht {

/// OBJ text without its "mtllib" lines. OpenMesh's OBJ reader opens the material library a file
/// names wherever the path leads ("../../dev/zero" never ends, a FIFO blocks forever); only the
/// geometry is read, so the library is never needed.
std::string without_material_libraries(std::string text);

/// What is wrong with the element counts a header states, or "" when they fit in the file or
/// the format states none: an OFF header without them, a negative count, or counts the file
/// cannot hold. OpenMesh's readers trust the counts: a 50-byte OFF file stating 30 million faces
/// made the reader add its last face 30 million times (46 s and 9 GB before a wrong message), an
/// ASCII PLY file stating more faces than it holds was read to its end and accepted, an OFF
/// stream without counts made it reserve room for whatever its variables held.
/// `ext` is ".off" (`text` as plain OFF: the keyword alone on the first line, no comments),
/// ".ply" (ASCII or binary) or anything else (no check).
std::string stated_counts_problem(const std::string& text, const std::string& ext);

}  // namespace ht
