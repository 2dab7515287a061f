#pragma once

#include <vector>

#include "parallax/util/types.h"

namespace parallax {

// An edge of the view graph: two images and how strongly they are linked (verified matches).
struct ViewGraphEdge {
  image_t image_id1 = kInvalidImageId;
  image_t image_id2 = kInvalidImageId;
  double weight = 0;
};

struct ViewGraphPartitionOptions {
  // Clusters are split until none has more images than this (before the overlap is added).
  int max_cluster_images = 250;
  // Images each cluster borrows from every neighbouring cluster, the most strongly linked
  // first, so that neighbours share enough images to be merged.
  int overlap_images = 10;
  // A cut leaves at least this share of a cluster's images on each side. Without it the
  // normalised cut would trim weakly linked images off the edge one at a time.
  double min_split_fraction = 0.25;
  // Lanczos steps for the Fiedler vector (capped by the cluster size, where it is exact).
  int max_lanczos_steps = 300;
  void Check() const;
};

// Splits the view graph into overlapping clusters for partitioned mapping: each connected
// component is split recursively by normalised cuts (Shi & Malik 2000: the sweep over the
// Fiedler vector of the normalised Laplacian that minimises cut/vol(A) + cut/vol(B)) until
// every cluster is small enough, then every cluster borrows the images of its neighbours most
// strongly linked to it. Images without edges are left out. The result does not depend on
// the order of the edges; clusters are sorted by their smallest image id, images by id.
std::vector<std::vector<image_t>> PartitionViewGraph(const ViewGraphPartitionOptions& options,
                                                     const std::vector<ViewGraphEdge>& edges);

}  // namespace parallax
