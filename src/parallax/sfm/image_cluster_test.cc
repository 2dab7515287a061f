#include "parallax/sfm/image_cluster.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "parallax/scene/synthetic_dataset.h"
#include "parallax/sfm/testing/synthetic_mapper_input.h"
#include "parallax/util/check.h"
#include "parallax/util/file.h"
#include "parallax/util/test_dir.h"

namespace parallax {
namespace {

using test::ScopedTestDir;
using ::testing::HasSubstr;

MapperInput RingInput() {
  SyntheticDatasetOptions options;
  options.num_images = 8;
  options.num_points3D = 300;
  options.seed = 1;
  Reconstruction truth;
  SynthesizeDataset(options, &truth);
  return InputFromTruth(truth);
}

std::string ErrorOf(const std::function<void()>& action) {
  try {
    action();
  } catch (const InputError& error) {
    return error.what();
  }
  return "";
}

TEST(ImageCluster, FileRoundTripAndClusterInput) {
  const ScopedTestDir dir("image_cluster");
  const MapperInput input = RingInput();
  const ImageCluster cluster = MakeImageCluster(input, {2, 3, 5});
  EXPECT_EQ(cluster.image_names,
            (std::vector<std::string>{"image0002.png", "image0003.png", "image0005.png"}));
  ASSERT_EQ(cluster.pairs.size(), 3u);  // Every pair of the ring's images is verified.
  const auto path = dir.path() / "cluster-0.txt";
  WriteImageCluster(cluster, path);
  const ImageCluster read = ReadImageCluster(path);
  EXPECT_EQ(read.image_names, cluster.image_names);
  EXPECT_EQ(read.pairs, cluster.pairs);

  const MapperInput part = ClusterMapperInput(input, read, path.string());
  EXPECT_EQ(part.images.size(), 3u);
  EXPECT_EQ(part.two_view_geometries.size(), 3u);
  EXPECT_TRUE(part.correspondence_graph.ExistsImage(5));
  EXPECT_FALSE(part.correspondence_graph.ExistsImage(4));
  EXPECT_GT(part.correspondence_graph.NumTracks(), 0u);

  // Only the listed pairs are used: without 2-5 the graph has no 2-5 matches.
  ImageCluster fewer = read;
  fewer.pairs.erase(fewer.pairs.begin() + 1);
  const MapperInput part_fewer = ClusterMapperInput(input, fewer, path.string());
  EXPECT_EQ(part_fewer.two_view_geometries.size(), 2u);
  EXPECT_EQ(part_fewer.correspondence_graph.NumMatchesBetween(2, 5), 0u);
}

TEST(ImageCluster, NamesWithSpacesSurviveTheFile) {
  const ScopedTestDir dir("image_cluster");
  ImageCluster cluster;
  cluster.image_names = {"day 1/a b.jpg", "day 1/c.jpg"};
  cluster.pairs = {{"day 1/a b.jpg", "day 1/c.jpg"}};
  WriteImageCluster(cluster, dir.path() / "c.txt");
  const ImageCluster read = ReadImageCluster(dir.path() / "c.txt");
  EXPECT_EQ(read.image_names, cluster.image_names);
  EXPECT_EQ(read.pairs, cluster.pairs);
}

TEST(ImageCluster, BadFilesGetOneLineErrorsNamingThem) {
  const ScopedTestDir dir("image_cluster");
  const auto path = dir.path() / "cluster.txt";
  const auto error_for = [&](const std::string& content) {
    WriteTextFileAtomically(path, content);
    return ErrorOf([&] { ReadImageCluster(path); });
  };
  EXPECT_THAT(error_for("image a.jpg\nphoto b.jpg\n"),
              HasSubstr(path.string() + ": line 2: expected"));
  EXPECT_THAT(error_for("image a.jpg\nimage a.jpg\n"),
              HasSubstr("line 2: image 'a.jpg' listed twice"));
  EXPECT_THAT(error_for("image a.jpg\nimage b.jpg\npair a.jpg b.jpg\n"),
              HasSubstr("line 3: pair needs two image names"));
  EXPECT_THAT(error_for("image a.jpg\npair a.jpg\tc.jpg\n"),
              HasSubstr("'c.jpg' is not among the cluster's images"));
  EXPECT_THAT(error_for("# nothing\n"), HasSubstr(path.string() + ": no images"));
  EXPECT_THAT(ErrorOf([&] { ReadImageCluster(dir.path() / "missing.txt"); }),
              HasSubstr("missing.txt"));
  EXPECT_EQ(error_for("image a.jpg\nphoto b.jpg\n").find('\n'), std::string::npos);
}

TEST(ImageCluster, ImagesOrPairsTheDatabaseLacksAreInputErrors) {
  const MapperInput input = RingInput();
  ImageCluster unknown;
  unknown.image_names = {"image0001.png", "elsewhere.jpg"};
  EXPECT_EQ(ErrorOf([&] { ClusterMapperInput(input, unknown, "c.txt"); }),
            "c.txt: image 'elsewhere.jpg' is not in the database");

  MapperInput sparse = RingInput();
  sparse.two_view_geometries.erase(ImagePairToPairId(1, 2));
  ImageCluster unverified;
  unverified.image_names = {"image0001.png", "image0002.png"};
  unverified.pairs = {{"image0002.png", "image0001.png"}};
  EXPECT_THAT(ErrorOf([&] { ClusterMapperInput(sparse, unverified, "c.txt"); }),
              HasSubstr("c.txt: pair 'image0002.png' - 'image0001.png' has no verified geometry"));
}

}  // namespace
}  // namespace parallax
