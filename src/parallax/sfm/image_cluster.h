#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "parallax/sfm/mapper_input.h"

namespace parallax {

// One cluster of a partitioned run, the unit of work that `parallax mapper --cluster FILE`
// maps (on this machine or on another rank): the images to map together, by name, and the
// verified pairs among them to use.
//
// As a file, one entry per line; names run to the end of the line, pairs are separated by a
// tab (image names may hold spaces), '#' starts a comment:
//   image <NAME>
//   pair <NAME1>\t<NAME2>
struct ImageCluster {
  std::vector<std::string> image_names;
  std::vector<std::pair<std::string, std::string>> pairs;
};

// Written atomically.
void WriteImageCluster(const ImageCluster& cluster, const std::filesystem::path& path);
// Throws InputError "<path>: line N: <problem>" on a malformed file.
ImageCluster ReadImageCluster(const std::filesystem::path& path);

// The cluster of `image_ids` with every verified pair of `input` among them.
ImageCluster MakeImageCluster(const MapperInput& input, const std::vector<image_t>& image_ids);

// The part of `input` a cluster covers: its images and pairs (as `input` filtered them when
// it was loaded), with tracks built from those pairs alone. A name the input does not hold,
// or a pair it has not verified, throws InputError naming `source` (the cluster file).
MapperInput ClusterMapperInput(const MapperInput& input, const ImageCluster& cluster,
                               const std::string& source);

}  // namespace parallax
