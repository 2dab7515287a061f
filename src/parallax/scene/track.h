#pragma once

#include <vector>

#include "parallax/util/types.h"

namespace parallax {

// One observation of a 3D point: keypoint `point2D_idx` of image `image_id`.
struct TrackElement {
  image_t image_id = kInvalidImageId;
  point2D_t point2D_idx = kInvalidPoint2DIdx;
  bool operator==(const TrackElement& other) const = default;
};

struct Track {
  std::vector<TrackElement> elements;

  size_t Length() const { return elements.size(); }
  void AddElement(image_t image_id, point2D_t point2D_idx) {
    elements.push_back({image_id, point2D_idx});
  }
  bool ContainsImage(image_t image_id) const {
    for (const TrackElement& element : elements) {
      if (element.image_id == image_id) return true;
    }
    return false;
  }
  // Removes the element at `index` (order not kept).
  void DeleteElement(size_t index) {
    elements[index] = elements.back();
    elements.pop_back();
  }
  // Removes the element of this observation, if present.
  void DeleteElement(image_t image_id, point2D_t point2D_idx);
};

}  // namespace parallax
