// fuzz_cache_entry: bytes as an on-disk node-cache file (meshers/disk_cache.hpp,
// decode_cache_entry). An input that does not start with the magic's 'H' gets this build's
// header stamped over its first 48 bytes (magic, layout, build, key, the payload's true length,
// a good checksum), so the fuzzer reaches the payload's parser (counts, indices, strategies,
// strings) and the corpus stays valid in every build; inputs starting with 'H' go as they are
// (the header's checks). An entry it accepts must encode back to the very same bytes.
#include "fuzz/fuzz_support.hpp"
#include "meshers/disk_cache.hpp"

#include <cstring>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  constexpr std::uint64_t kKey = 0x0123456789abcdefull;
  std::string bytes(reinterpret_cast<const char*>(data), size);
  if (size >= 48 && data[0] != 'H') {
    bytes.replace(0, 32, ht::encode_cache_entry(kKey, ht::CachedJob{}), 0, 32);
    const std::uint64_t payload = size - 48;
    std::memcpy(bytes.data() + 32, &payload, 8);
    ht::reseal_cache_entry(bytes);
  }
  ht::CacheEntryError error;
  const std::optional<ht::CachedJob> job = ht::decode_cache_entry(bytes, kKey, &error);
  if (job) {
    ht::fuzz::require(job->mesh != nullptr, "an accepted entry without a mesh");
    ht::fuzz::require(ht::encode_cache_entry(kKey, *job) == bytes, "an accepted entry that does not encode back to its bytes");
  } else {
    ht::fuzz::require(!error.detail.empty(), "a refusal without a reason");
  }
  return 0;
}
