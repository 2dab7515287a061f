#include "parallax/feature/types.h"

#include <cmath>

namespace parallax {

FeatureKeypoint::FeatureKeypoint(float x, float y, float scale, float orientation) : x(x), y(y) {
  const float cos_o = std::cos(orientation), sin_o = std::sin(orientation);
  a11 = scale * cos_o;
  a12 = -scale * sin_o;
  a21 = scale * sin_o;
  a22 = scale * cos_o;
}

float FeatureKeypoint::ComputeScale() const {
  return 0.5f * (std::sqrt(a11 * a11 + a21 * a21) + std::sqrt(a12 * a12 + a22 * a22));
}

float FeatureKeypoint::ComputeOrientation() const { return std::atan2(a21, a11); }

}  // namespace parallax
