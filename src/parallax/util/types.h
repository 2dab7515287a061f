#pragma once

#include <cstdint>
#include <limits>
#include <utility>

namespace parallax {

// Typed ids, as in COLMAP's database (32-bit camera/image ids, 64-bit 3D point ids).
using camera_t = uint32_t;
using image_t = uint32_t;
using point2D_t = uint32_t;
using point3D_t = uint64_t;
using image_pair_t = uint64_t;

inline constexpr camera_t kInvalidCameraId = std::numeric_limits<camera_t>::max();
inline constexpr image_t kInvalidImageId = std::numeric_limits<image_t>::max();
inline constexpr point2D_t kInvalidPoint2DIdx = std::numeric_limits<point2D_t>::max();
inline constexpr point3D_t kInvalidPoint3DId = std::numeric_limits<point3D_t>::max();

// COLMAP's pair id encoding: smaller id first, pair_id = 2147483647 * id1 + id2.
inline constexpr uint64_t kMaxNumImages = 2147483647;

inline image_pair_t ImagePairToPairId(image_t image_id1, image_t image_id2) {
  if (image_id1 > image_id2) std::swap(image_id1, image_id2);
  return kMaxNumImages * static_cast<image_pair_t>(image_id1) + image_id2;
}

inline std::pair<image_t, image_t> PairIdToImagePair(image_pair_t pair_id) {
  const image_t image_id2 = static_cast<image_t>(pair_id % kMaxNumImages);
  const image_t image_id1 = static_cast<image_t>((pair_id - image_id2) / kMaxNumImages);
  return {image_id1, image_id2};
}

// Whether objects numbered up to `max_id`, `count` of them, may be looked up in a flat table
// indexed by id. Ids are dense in practice (the database and the mapper number from 1); ids
// sparser than a few times the count would make the table mostly empty, so lookups stay in
// the map that owns the objects.
inline bool IdsFitFlatTable(uint64_t max_id, uint64_t count) { return max_id < 4 * count + 1024; }

// True when the pair must be swapped to follow the (smaller id first) convention.
inline bool SwapImagePair(image_t image_id1, image_t image_id2) { return image_id1 > image_id2; }

}  // namespace parallax
