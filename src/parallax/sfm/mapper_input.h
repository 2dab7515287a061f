#pragma once

#include <map>
#include <string>
#include <vector>

#include "parallax/scene/camera.h"
#include "parallax/scene/correspondence_graph.h"
#include "parallax/scene/database.h"
#include "parallax/scene/image.h"
#include "parallax/scene/reconstruction.h"
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

// A finished model restated in the ids of `input`, as IncrementalMapper::Extend takes it: the
// registered images of `model` that `input` holds (matched by name; ids of the two need not
// agree), with their poses, and the intrinsics of their cameras in the model. The names of
// the model's registered images that `input` lacks (photos removed since) go to `missing`.
Reconstruction ModelInInputIds(const Reconstruction& model, const MapperInput& input,
                               std::vector<std::string>* missing);

}  // namespace parallax
