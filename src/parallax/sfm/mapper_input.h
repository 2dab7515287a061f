#pragma once

#include <map>

#include "parallax/scene/camera.h"
#include "parallax/scene/correspondence_graph.h"
#include "parallax/scene/database.h"
#include "parallax/scene/image.h"
#include "parallax/scene/two_view_geometry.h"

namespace parallax {

// Everything the mapper reads from the database: cameras, images with their keypoints,
// the verified pairs and the tracks built from them.
struct MapperInput {
  std::map<camera_t, Camera> cameras;
  std::map<image_t, Image> images;  // points2D = keypoints; no poses.
  std::map<image_pair_t, TwoViewGeometry> two_view_geometries;
  CorrespondenceGraph correspondence_graph;
};

struct MapperInputOptions {
  int min_num_matches = 15;  // Verified pairs with fewer inliers are ignored.
  void Check() const;
};

// Reads the database. Pairs whose configuration is undefined, degenerate or watermark are
// left out of the graph.
MapperInput LoadMapperInput(const Database& database, const MapperInputOptions& options);

// Builds a MapperInput from parts already in memory (synthetic scenes, tests).
void FinalizeMapperInput(const MapperInputOptions& options, MapperInput* input);

}  // namespace parallax
