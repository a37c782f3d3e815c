// Mesh files read here instead of by OpenMesh (OFF, OBJ), and checks on PLY before OpenMesh reads
// it: what OpenMesh's readers do badly, found while fuzzing (fuzz/; each case is a test in
// tests/test_mesh_reading.cpp). Used by MeshLeaf::load (nodes/mesh_leaf.cpp).
#pragma once

#include <glm/vec3.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace ht {

/// What is wrong with a PLY file's structure, or "" when it is sound (and for other formats):
/// the header checked line by line, then every record walked (ASCII word by word, binary byte by
/// byte), so each count and list size is known to fit in the file before OpenMesh reads it.
/// OpenMesh's PLY reader trusts the file: its header parser crashed on a property before any
/// element and looped on an unreadable version, a file stating more faces than it holds was read
/// to its end and accepted, a count that is not a number took 65 s to end in bad_alloc, a list
/// size past its items pushed indices until memory ran out. `text` is the whole file.
std::string stated_counts_problem(const std::string& text, const std::string& ext);

/// A mesh file's records as it states them: positions, and faces as lists of indices into them
/// (kNoVertex for an index past the vertices).
struct MeshRecords {
  std::vector<glm::dvec3> positions;
  std::vector<std::vector<std::uint32_t>> faces;
};
inline constexpr std::uint32_t kNoVertex = ~0u;

/// Reads ASCII OFF ([ST][C][N]OFF) as plain_off() leaves it (the keyword alone on its line, no
/// comments): per vertex three coordinates (as floats, as OpenMesh read them) and, for NOFF, a
/// normal, the rest of the line ignored; per face its size, its indices and the rest of the line
/// ignored. Returns "" or what is wrong, with the line. OpenMesh's OFF reader is not used: given
/// a stream it never looks at the keyword (binary OFF and COFF came out as faces of 0 vertices),
/// reserves whatever the counts say (an empty file asked for 6 GB, "4OFF2" for 3.5 GB, 30 million
/// faces stated in 50 bytes took 46 s and 9 GB), and repeats its last face when the text runs
/// out ("BINARYF" kept it adding faces past 10 s). Binary OFF and 4OFF/nOFF are refused.
std::string read_ascii_off(const std::string& text, MeshRecords& out);

/// Reads OBJ geometry: "v x y z" (further numbers ignored) and "f" with 1-based or negative
/// (relative) indices, each corner's texture and normal indices ignored; every other statement
/// (vt, vn, groups, materials, lines) is skipped. Returns "" or what is wrong, with the line.
/// OpenMesh's OBJ reader is not used: it opened the material library a file names wherever the
/// path led ("mtllib ../../dev/zero" never returned, a FIFO blocked), asserted (aborting the
/// process) on a face corner with no vertex index ("f /1/8"), and dropped faces of fewer than
/// three corners silently.
std::string read_obj(const std::string& text, MeshRecords& out);

}  // namespace ht
