#pragma once

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

namespace parallax {

// 128-bit XXH3 digests (libxxhash) as 32 lower-case hex digits. Fast enough to hash every input
// photo of a run (several GB/s), not a cryptographic hash: it tells content apart, it does not
// authenticate it.
std::string HashBytes(std::string_view bytes);

// Digest of a whole file, read in blocks. Throws InputError naming the path when it cannot be
// read.
std::string HashFile(const std::filesystem::path& path);

}  // namespace parallax
