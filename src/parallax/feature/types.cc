#include "parallax/feature/types.h"

#include <cmath>
#include <cstring>

#include "parallax/util/check.h"

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

void GatherDescriptorRows(const FeatureDescriptors& from, const std::vector<int>& rows,
                          FeatureDescriptors* to) {
  to->resize(static_cast<Eigen::Index>(rows.size()), from.cols());
  const auto dim = static_cast<size_t>(from.cols());
  for (size_t k = 0; k < rows.size(); ++k) {
    PARALLAX_CHECK(rows[k] >= 0 && rows[k] < from.rows());
    std::memcpy(to->data() + k * dim, from.data() + static_cast<size_t>(rows[k]) * dim, dim);
  }
}

}  // namespace parallax
