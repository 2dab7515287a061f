#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>
#include <ostream>
#include <type_traits>

namespace parallax {

// Unsigned integers stored in a given byte order, read from unaligned bytes.
inline uint32_t BigEndian16(const uint8_t* bytes) { return (uint32_t{bytes[0]} << 8) | bytes[1]; }
inline uint32_t BigEndian32(const uint8_t* bytes) {
  return (uint32_t{bytes[0]} << 24) | (uint32_t{bytes[1]} << 16) | (uint32_t{bytes[2]} << 8) |
         bytes[3];
}
inline uint32_t LittleEndian16(const uint8_t* bytes) {
  return (uint32_t{bytes[1]} << 8) | bytes[0];
}
inline uint32_t LittleEndian32(const uint8_t* bytes) {
  return (uint32_t{bytes[3]} << 24) | (uint32_t{bytes[2]} << 16) | (uint32_t{bytes[1]} << 8) |
         bytes[0];
}

// Writes a number as little-endian bytes (COLMAP's binary models, binary PLY).
template <typename T>
void WriteBinary(std::ostream& stream, T value) {
  static_assert(std::is_arithmetic_v<T>);
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) std::reverse(bytes, bytes + sizeof(T));
  stream.write(bytes, sizeof(T));
}

}  // namespace parallax
