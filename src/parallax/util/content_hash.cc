#include "parallax/util/content_hash.h"

#include <xxhash.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <memory>

#include "parallax/util/check.h"
#include "parallax/util/file.h"

namespace parallax {
namespace {

std::string ToHex(const XXH128_hash_t& digest) {
  XXH128_canonical_t canonical;
  XXH128_canonicalFromHash(&canonical, digest);
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string hex;
  hex.reserve(2 * sizeof(canonical.digest));
  for (const unsigned char byte : canonical.digest) {
    hex.push_back(kDigits[byte >> 4]);
    hex.push_back(kDigits[byte & 15]);
  }
  return hex;
}

struct StateDeleter {
  void operator()(XXH3_state_t* state) const { XXH3_freeState(state); }
};

}  // namespace

std::string HashBytes(std::string_view bytes) {
  return ToHex(XXH3_128bits(bytes.data(), bytes.size()));
}

std::string HashFile(const std::filesystem::path& path) {
  std::ifstream stream(path, std::ios::binary);
  if (!stream) ThrowCannotOpenForReading(path);
  const std::unique_ptr<XXH3_state_t, StateDeleter> state(XXH3_createState());
  PARALLAX_CHECK(state != nullptr);
  XXH3_128bits_reset(state.get());
  std::array<char, 1 << 16> block;
  while (stream) {
    stream.read(block.data(), block.size());
    XXH3_128bits_update(state.get(), block.data(), static_cast<size_t>(stream.gcount()));
  }
  if (stream.bad()) throw InputError(path.string() + ": read failed");
  return ToHex(XXH3_128bits_digest(state.get()));
}

}  // namespace parallax
