#include "parallax/sfm/view_graph_partition.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <random>
#include <set>

namespace parallax {
namespace {

// Images first..first+size-1, all linked to each other with `weight`.
void AddClique(image_t first, int size, double weight, std::vector<ViewGraphEdge>* edges) {
  for (int i = 0; i < size; ++i) {
    for (int j = i + 1; j < size; ++j) edges->push_back({first + i, first + j, weight});
  }
}

// A width x height grid of images (ids from 1), each linked to its right and lower neighbour.
std::vector<ViewGraphEdge> Grid(int width, int height) {
  std::vector<ViewGraphEdge> edges;
  const auto id = [width](int x, int y) { return static_cast<image_t>(1 + y * width + x); };
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      if (x + 1 < width) edges.push_back({id(x, y), id(x + 1, y), 1.0});
      if (y + 1 < height) edges.push_back({id(x, y), id(x, y + 1), 1.0});
    }
  }
  return edges;
}

bool IsConnected(const std::vector<image_t>& cluster, const std::vector<ViewGraphEdge>& edges) {
  const std::set<image_t> members(cluster.begin(), cluster.end());
  std::map<image_t, std::vector<image_t>> neighbors;
  for (const ViewGraphEdge& edge : edges) {
    if (members.count(edge.image_id1) && members.count(edge.image_id2)) {
      neighbors[edge.image_id1].push_back(edge.image_id2);
      neighbors[edge.image_id2].push_back(edge.image_id1);
    }
  }
  std::set<image_t> reached = {cluster.front()};
  std::vector<image_t> queue = {cluster.front()};
  while (!queue.empty()) {
    const image_t image_id = queue.back();
    queue.pop_back();
    for (const image_t next : neighbors[image_id]) {
      if (reached.insert(next).second) queue.push_back(next);
    }
  }
  return reached.size() == members.size();
}

TEST(ViewGraphPartition, TwoCliquesSplitAtTheirWeakLink) {
  std::vector<ViewGraphEdge> edges;
  AddClique(1, 30, 100, &edges);
  AddClique(101, 30, 100, &edges);
  edges.push_back({5, 107, 1});
  ViewGraphPartitionOptions options;
  options.max_cluster_images = 40;
  options.overlap_images = 0;
  const auto clusters = PartitionViewGraph(options, edges);
  ASSERT_EQ(clusters.size(), 2u);
  for (const auto& cluster : clusters) {
    ASSERT_EQ(cluster.size(), 30u);
    // All of one clique: ids 1..30 or 101..130.
    EXPECT_EQ(cluster.back() - cluster.front(), 29u);
  }
}

TEST(ViewGraphPartition, SmallGraphIsOneCluster) {
  std::vector<ViewGraphEdge> edges;
  AddClique(1, 10, 5, &edges);
  const auto clusters = PartitionViewGraph(ViewGraphPartitionOptions(), edges);
  ASSERT_EQ(clusters.size(), 1u);
  EXPECT_EQ(clusters[0].size(), 10u);
}

TEST(ViewGraphPartition, ComponentsAreClustersAndIsolatedImagesAreLeftOut) {
  std::vector<ViewGraphEdge> edges;
  AddClique(1, 8, 5, &edges);
  AddClique(20, 6, 5, &edges);
  edges.push_back({40, 40, 10});  // A self edge links nothing.
  edges.push_back({41, 42, 0});   // Nor does a weightless one.
  ViewGraphPartitionOptions options;
  options.overlap_images = 10;
  const auto clusters = PartitionViewGraph(options, edges);
  ASSERT_EQ(clusters.size(), 2u);
  EXPECT_EQ(clusters[0], (std::vector<image_t>{1, 2, 3, 4, 5, 6, 7, 8}));
  EXPECT_EQ(clusters[1], (std::vector<image_t>{20, 21, 22, 23, 24, 25}));
}

TEST(ViewGraphPartition, GridSplitsIntoBoundedConnectedClustersWithShortCuts) {
  const std::vector<ViewGraphEdge> edges = Grid(30, 20);
  ViewGraphPartitionOptions options;
  options.max_cluster_images = 100;
  options.overlap_images = 0;
  const auto clusters = PartitionViewGraph(options, edges);
  std::map<image_t, int> cluster_of;
  for (size_t c = 0; c < clusters.size(); ++c) {
    EXPECT_LE(clusters[c].size(), 100u);
    EXPECT_GE(clusters[c].size(), 25u);  // Balanced cuts: no slivers.
    EXPECT_TRUE(IsConnected(clusters[c], edges)) << "cluster " << c;
    for (const image_t image_id : clusters[c]) {
      EXPECT_TRUE(cluster_of.emplace(image_id, static_cast<int>(c)).second) << image_id;
    }
  }
  EXPECT_EQ(cluster_of.size(), 600u);
  // Compact blocks cut about 1 edge in 8 here; slicing in strips or at random cuts far more.
  size_t num_cut = 0;
  for (const ViewGraphEdge& edge : edges)
    num_cut += cluster_of[edge.image_id1] != cluster_of[edge.image_id2];
  EXPECT_LT(num_cut, 0.15 * edges.size()) << clusters.size() << " clusters";
}

TEST(ViewGraphPartition, DoesNotDependOnEdgeOrder) {
  std::vector<ViewGraphEdge> edges = Grid(25, 12);
  ViewGraphPartitionOptions options;
  options.max_cluster_images = 60;
  options.overlap_images = 4;
  const auto clusters = PartitionViewGraph(options, edges);
  std::mt19937 generator(7);
  std::shuffle(edges.begin(), edges.end(), generator);
  for (ViewGraphEdge& edge : edges) std::swap(edge.image_id1, edge.image_id2);
  EXPECT_EQ(PartitionViewGraph(options, edges), clusters);
}

TEST(ViewGraphPartition, NeighboursLendTheirMostStronglyLinkedImages) {
  std::vector<ViewGraphEdge> edges;
  AddClique(1, 30, 100, &edges);
  AddClique(101, 30, 100, &edges);
  // Bridges of increasing strength: 103..107 in the second clique, 3..7 in the first.
  for (int i = 0; i < 5; ++i)
    edges.push_back({static_cast<image_t>(3 + i), static_cast<image_t>(103 + i), 1.0 + i});
  ViewGraphPartitionOptions options;
  options.max_cluster_images = 40;
  options.overlap_images = 3;
  const auto clusters = PartitionViewGraph(options, edges);
  ASSERT_EQ(clusters.size(), 2u);
  ASSERT_EQ(clusters[0].size(), 33u);
  ASSERT_EQ(clusters[1].size(), 33u);
  // The first clique borrows the three strongest bridge ends of the second, and vice versa.
  EXPECT_EQ(std::vector<image_t>(clusters[0].end() - 3, clusters[0].end()),
            (std::vector<image_t>{105, 106, 107}));
  EXPECT_EQ(std::vector<image_t>(clusters[1].begin(), clusters[1].begin() + 3),
            (std::vector<image_t>{5, 6, 7}));
}

}  // namespace
}  // namespace parallax
