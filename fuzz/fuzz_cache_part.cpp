// fuzz_cache_part: bytes as the payload of a part's cache file (meshers/cache_parts.hpp): the
// first byte picks the kind (even: a brick's extraction, odd: a quality-pass piece), the rest is
// the payload, which the header's checksum has already let through (a forged file). A payload a
// decoder accepts must encode back to the very same bytes; one it refuses must say why.
#include "fuzz/fuzz_support.hpp"
#include "meshers/cache_parts.hpp"

#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string_view payload(reinterpret_cast<const char*>(data) + 1, size - 1);
  std::string why;
  if (data[0] % 2 == 0) {
    ht::brick::KeptBrick brick;
    if (ht::decode_kept(payload, brick, why))
      ht::fuzz::require(ht::encode_kept(brick) == payload, "an accepted brick that does not encode back to its bytes");
    else
      ht::fuzz::require(!why.empty(), "a brick refused without a reason");
  } else {
    ht::QualityPiece piece;
    if (ht::decode_piece(payload, 1000, piece, why))
      ht::fuzz::require(ht::encode_piece(piece) == payload, "an accepted piece that does not encode back to its bytes");
    else
      ht::fuzz::require(!why.empty(), "a piece refused without a reason");
  }
  return 0;
}
