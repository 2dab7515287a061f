#include "parallax/scene/correspondence_graph.h"

#include <algorithm>
#include <numeric>
#include <span>

#include "parallax/math/union_find.h"
#include "parallax/util/check.h"

namespace parallax {

void CorrespondenceGraph::AddImage(image_t image_id, size_t num_points2D) {
  PARALLAX_CHECK(!finalized_);
  PARALLAX_CHECK_MSG(!ExistsImage(image_id), "image " << image_id << " added twice");
  images_[image_id].num_points2D = num_points2D;
}

void CorrespondenceGraph::AddCorrespondences(image_t image_id1, image_t image_id2,
                                             const FeatureMatches& matches) {
  PARALLAX_CHECK(!finalized_);
  PARALLAX_CHECK_NE(image_id1, image_id2);
  PARALLAX_CHECK(ExistsImage(image_id1) && ExistsImage(image_id2));
  const size_t num1 = images_[image_id1].num_points2D;
  const size_t num2 = images_[image_id2].num_points2D;
  FeatureMatches oriented;
  oriented.reserve(matches.size());
  const bool swap = image_id1 > image_id2;
  for (const FeatureMatch& match : matches) {
    PARALLAX_CHECK_MSG(match.point2D_idx1 < num1 && match.point2D_idx2 < num2,
                       "match out of range in pair " << image_id1 << "-" << image_id2);
    oriented.push_back(swap ? FeatureMatch{match.point2D_idx2, match.point2D_idx1} : match);
  }
  if (oriented.empty()) return;
  images_[image_id1].neighbors[image_id2] += oriented.size();
  images_[image_id2].neighbors[image_id1] += oriented.size();
  FeatureMatches& stored = pair_matches_[ImagePairToPairId(image_id1, image_id2)];
  stored.insert(stored.end(), oriented.begin(), oriented.end());
}

void CorrespondenceGraph::Finalize() {
  PARALLAX_CHECK(!finalized_);
  finalized_ = true;
  size_t num_nodes = 0;
  for (auto& [image_id, entry] : images_) {
    entry.node_offset = num_nodes;
    num_nodes += entry.num_points2D;
  }
  std::vector<image_t> node_image(num_nodes);
  for (const auto& [image_id, entry] : images_) {
    std::fill_n(node_image.begin() + entry.node_offset, entry.num_points2D, image_id);
  }

  BuildCorrespondenceLists(num_nodes);

  // Strongest pairs first: their matches are the most reliable, so when a conflict arises
  // the weaker link is the one refused.
  std::vector<const std::pair<const image_pair_t, FeatureMatches>*> pairs;
  for (const auto& entry : pair_matches_) pairs.push_back(&entry);
  std::stable_sort(pairs.begin(), pairs.end(), [](const auto* a, const auto* b) {
    return a->second.size() > b->second.size();
  });

  UnionFind sets(num_nodes);
  // Sorted image ids of every set with more than one element, keyed by root. Read in place
  // (a single node's set is its image): copying both lists for every match made this loop
  // much of the time of loading a large collection for the mapper (docs/performance.md,
  // "Correspondence graph: set lists read in place").
  std::unordered_map<size_t, std::vector<image_t>> set_images;
  const auto images_of = [&](size_t root, image_t* single) -> std::span<const image_t> {
    const auto it = set_images.find(root);
    if (it != set_images.end()) return it->second;
    *single = node_image[root];
    return {single, 1};
  };
  const auto disjoint = [](std::span<const image_t> a, std::span<const image_t> b) {
    for (size_t i = 0, j = 0; i < a.size() && j < b.size();) {
      if (a[i] == b[j]) return false;
      a[i] < b[j] ? ++i : ++j;
    }
    return true;
  };
  std::vector<size_t> conflicting_roots;
  for (const auto* pair : pairs) {
    const auto [image_id1, image_id2] = PairIdToImagePair(pair->first);
    const size_t offset1 = images_[image_id1].node_offset;
    const size_t offset2 = images_[image_id2].node_offset;
    for (const FeatureMatch& match : pair->second) {
      const size_t root1 = sets.Find(offset1 + match.point2D_idx1);
      const size_t root2 = sets.Find(offset2 + match.point2D_idx2);
      if (root1 == root2) continue;
      image_t single1 = 0, single2 = 0;
      const std::span<const image_t> images1 = images_of(root1, &single1);
      const std::span<const image_t> images2 = images_of(root2, &single2);
      if (!disjoint(images1, images2)) {
        ++stats_.num_refused_unions;
        conflicting_roots.push_back(root1);
        continue;
      }
      std::vector<image_t> merged(images1.size() + images2.size());
      std::merge(images1.begin(), images1.end(), images2.begin(), images2.end(), merged.begin());
      sets.Union(root1, root2);
      set_images.erase(root1);
      set_images.erase(root2);
      set_images[sets.Find(root1)] = std::move(merged);
    }
  }

  node_track_.assign(num_nodes, kInvalidTrackId);
  std::vector<track_t> root_track(num_nodes, kInvalidTrackId);
  for (size_t node = 0; node < num_nodes; ++node) {
    const size_t root = sets.Find(node);
    if (sets.SetSize(root) < 2) continue;
    if (root_track[root] == kInvalidTrackId) {
      root_track[root] = static_cast<track_t>(tracks_.size());
      tracks_.emplace_back();
    }
    const track_t track_id = root_track[root];
    node_track_[node] = track_id;
    const image_t image_id = node_image[node];
    tracks_[track_id].push_back(
        {image_id, static_cast<point2D_t>(node - images_[image_id].node_offset)});
  }
  std::sort(conflicting_roots.begin(), conflicting_roots.end());
  conflicting_roots.erase(std::unique(conflicting_roots.begin(), conflicting_roots.end()),
                          conflicting_roots.end());
  stats_.num_split_components = conflicting_roots.size();
  stats_.num_tracks = tracks_.size();
  for (const auto& track : tracks_) stats_.num_observations += track.size();
  stats_.mean_track_length =
      tracks_.empty() ? 0.0 : static_cast<double>(stats_.num_observations) / tracks_.size();
}

void CorrespondenceGraph::BuildCorrespondenceLists(size_t num_nodes) {
  // First node of every image by id, for lookups without the map.
  const image_t max_image_id = images_.empty() ? 0 : images_.rbegin()->first;
  if (IdsFitFlatTable(max_image_id, images_.size())) {
    image_nodes_.assign(max_image_id + 1, {kNoImage, 0});
    for (const auto& [image_id, entry] : images_) {
      image_nodes_[image_id] = {entry.node_offset, entry.num_points2D};
    }
  }
  correspondence_offsets_.assign(num_nodes + 1, 0);
  for (const auto& [pair_id, matches] : pair_matches_) {
    const auto [image_id1, image_id2] = PairIdToImagePair(pair_id);
    const size_t offset1 = images_[image_id1].node_offset;
    const size_t offset2 = images_[image_id2].node_offset;
    for (const FeatureMatch& match : matches) {
      ++correspondence_offsets_[offset1 + match.point2D_idx1 + 1];
      ++correspondence_offsets_[offset2 + match.point2D_idx2 + 1];
    }
  }
  std::partial_sum(correspondence_offsets_.begin(), correspondence_offsets_.end(),
                   correspondence_offsets_.begin());
  correspondences_.resize(correspondence_offsets_.back());
  std::vector<size_t> cursor(correspondence_offsets_.begin(), correspondence_offsets_.end() - 1);
  for (const auto& [pair_id, matches] : pair_matches_) {
    const auto [image_id1, image_id2] = PairIdToImagePair(pair_id);
    const size_t offset1 = images_[image_id1].node_offset;
    const size_t offset2 = images_[image_id2].node_offset;
    for (const FeatureMatch& match : matches) {
      correspondences_[cursor[offset1 + match.point2D_idx1]++] = {image_id2, match.point2D_idx2};
      correspondences_[cursor[offset2 + match.point2D_idx2]++] = {image_id1, match.point2D_idx1};
    }
  }
}

std::span<const TrackElement> CorrespondenceGraph::CorrespondencesOf(image_t image_id,
                                                                     point2D_t point2D_idx) const {
  PARALLAX_CHECK(finalized_);
  size_t node;
  if (image_id < image_nodes_.size() && image_nodes_[image_id].first != kNoImage) {
    PARALLAX_CHECK_LT(point2D_idx, image_nodes_[image_id].second);
    node = image_nodes_[image_id].first + point2D_idx;
  } else {
    const ImageEntry& entry = images_.at(image_id);
    PARALLAX_CHECK_LT(point2D_idx, entry.num_points2D);
    node = entry.node_offset + point2D_idx;
  }
  return {correspondences_.data() + correspondence_offsets_[node],
          correspondences_.data() + correspondence_offsets_[node + 1]};
}

std::vector<image_t> CorrespondenceGraph::ImageIds() const {
  std::vector<image_t> ids;
  for (const auto& [image_id, entry] : images_) ids.push_back(image_id);
  return ids;
}

size_t CorrespondenceGraph::NumObservationsForImage(image_t image_id) const {
  PARALLAX_CHECK(finalized_);
  const ImageEntry& entry = images_.at(image_id);
  size_t count = 0;
  for (size_t i = 0; i < entry.num_points2D; ++i) {
    if (node_track_[entry.node_offset + i] != kInvalidTrackId) ++count;
  }
  return count;
}

track_t CorrespondenceGraph::TrackOf(image_t image_id, point2D_t point2D_idx) const {
  PARALLAX_CHECK(finalized_);
  const ImageEntry& entry = images_.at(image_id);
  PARALLAX_CHECK_LT(point2D_idx, entry.num_points2D);
  return node_track_[entry.node_offset + point2D_idx];
}

bool CorrespondenceGraph::IsTwoViewTrack(track_t track_id) const {
  const std::vector<TrackElement>& elements = tracks_[track_id];
  if (elements.size() != 2) return false;
  for (const TrackElement& element : elements) {
    if (CorrespondencesOf(element.image_id, element.point2D_idx).size() != 1) return false;
  }
  return true;
}

const track_t* CorrespondenceGraph::TracksOfImage(image_t image_id) const {
  PARALLAX_CHECK(finalized_);
  return node_track_.data() + images_.at(image_id).node_offset;
}

size_t CorrespondenceGraph::NumMatchesBetween(image_t image_id1, image_t image_id2) const {
  const auto it = pair_matches_.find(ImagePairToPairId(image_id1, image_id2));
  return it == pair_matches_.end() ? 0 : it->second.size();
}

const std::map<image_t, size_t>& CorrespondenceGraph::NeighborsOf(image_t image_id) const {
  return images_.at(image_id).neighbors;
}

}  // namespace parallax
