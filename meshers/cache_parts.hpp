// The parts of global polygonizations as the caches keep them (meshers/piece_cache.hpp) and as
// their files hold them (meshers/disk_cache.hpp): a brick's extraction
// (meshers/polygonize_reuse.hpp KeptBrick) and a piece of the quality pass. Internal to the
// polygonizer and its caches; the decoders are the fuzz targets' too (fuzz/fuzz_cache_part.cpp).
//
// The encoders write field by field, so that two writers of one part write the same bytes; the
// decoders take only what an encoder writes (the same bytes back), and check what later code
// indexes with: counts against the bytes left, indices within the vertices, keys in order,
// positions finite.
#pragma once

#include "meshers/polygonize_reuse.hpp"
#include "meshers/quality.hpp"
#include "meshers/triangle_mesh.hpp"

#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace ht {

/// A slab's or band's result of the quality pass, with the parts of the field its work read
/// and their keys then (meshers/quality.hpp QualityReuse).
struct QualityPiece {
  TriangleMesh mesh;
  std::vector<std::uint32_t> origin;  ///< per vertex: its index in the piece's input, ~0u for a new one
  QualityStats stats;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> parts;  ///< (part, key), by part
};

/// A brick's extraction as a file's payload: the flag and counts, the vertices' keys, bricks and
/// positions, the nonzero normals (crease suspects) by vertex, the triangles as indices into the
/// vertices.
std::string encode_kept(const brick::KeptBrick& k);
/// What encode_kept wrote; false with `why` for anything else (the brick's vertex keys must
/// increase, every index lie within the vertices, normals be listed once, in order, nonzero).
bool decode_kept(std::string_view payload, brick::KeptBrick& k, std::string& why);

/// A piece as a file's payload: its mesh, origins, the parts it read, its statistics.
std::string encode_piece(const QualityPiece& p);
/// What encode_piece wrote, checked against the piece's input (`inputs` vertices): indices
/// within the mesh, origins within the input or new (~0u), positions finite.
bool decode_piece(std::string_view payload, std::size_t inputs, QualityPiece& p, std::string& why);

}  // namespace ht
