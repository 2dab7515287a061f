#pragma once

#include <vector>

#include "parallax/scene/reconstruction.h"

namespace parallax {

struct ObservationFilterOptions {
  double max_reprojection_error_px = 4.0;  // Observations reprojecting further are removed.
  double min_triangulation_angle_deg =
      1.5;  // Points seen under a smaller largest angle are removed.
  void Check() const;
};

// Removes observations of the given points that reproject badly or lie behind their camera,
// then points whose track no longer spans enough triangulation angle. Returns the number of
// observations removed (a point removed counts all of its observations).
size_t FilterPoints(const ObservationFilterOptions& options,
                    const std::vector<point3D_t>& point3D_ids, Reconstruction* reconstruction);
size_t FilterAllPoints(const ObservationFilterOptions& options, Reconstruction* reconstruction);

}  // namespace parallax
