#include "parallax/pipeline/pair_selection.h"

#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <set>

#include "parallax/pipeline/extraction_stage.h"
#include "parallax/render/synthetic_scene.h"
#include "parallax/util/check.h"
#include "parallax/util/test_dir.h"

namespace parallax {
namespace {

namespace fs = std::filesystem;
using ImagePair = std::pair<image_t, image_t>;

std::set<ImagePair> AsSet(const std::vector<ImagePair>& pairs) {
  std::set<ImagePair> set;
  for (auto [a, b] : pairs) set.insert({std::min(a, b), std::max(a, b)});
  return set;
}

TEST(PairSelection, ModeNamesRoundTrip) {
  for (const PairMode mode : {PairMode::kAuto, PairMode::kExhaustive, PairMode::kSequential,
                              PairMode::kRetrieval, PairMode::kSpatial, PairMode::kList}) {
    EXPECT_EQ(PairModeFromName(PairModeName(mode)), mode);
  }
  EXPECT_FALSE(PairModeFromName("vocab_tree").has_value());
}

// COLMAP's matches_importer pair list: names to ids, repeats and self-pairs dropped, and a bad
// line or an unknown name named with its file and line.
TEST(PairSelection, PairListReadsNamesAndNamesItsErrors) {
  const test::ScopedTestDir dir("parallax_pair_list_test");
  Database database(dir.path() / "database.db");
  const camera_t camera_id =
      database.WriteCamera(Camera::Create(1, CameraModelId::kPinhole, 100, 64, 48));
  const image_t a = database.WriteImage("a.png", camera_id);
  const image_t b = database.WriteImage("b.png", camera_id);
  const image_t c = database.WriteImage("c.png", camera_id);
  const fs::path list = dir.path() / "pairs.txt";
  std::ofstream(list) << "# pairs\na.png b.png\r\n\nb.png c.png\nb.png a.png\nc.png c.png\n";
  PairSelectionOptions options;
  options.mode = PairMode::kList;
  options.pair_list_path = list;
  const PairSelection selection = SelectPairs(options, {a, b, c}, database);
  EXPECT_EQ(selection.pairs, (std::vector<ImagePair>{{a, b}, {b, c}}));

  std::ofstream(list) << "a.png b.png\na.png d.png\n";
  try {
    SelectPairs(options, {a, b, c}, database);
    FAIL() << "an unknown name was accepted";
  } catch (const InputError& error) {
    EXPECT_EQ(std::string(error.what()),
              list.string() + ":2: image 'd.png' is not in the database");
  }
  std::ofstream(list) << "a.png b.png c.png\n";
  EXPECT_THROW(SelectPairs(options, {a, b, c}, database), InputError);
  options.pair_list_path.clear();
  EXPECT_THROW(SelectPairs(options, {a, b, c}, database), InputError);
}

TEST(PairSelection, SpatialPairsAreNearestWithinRadius) {
  // A 5 x 4 grid, 10 m apart, and one image 1 km away.
  std::vector<std::pair<image_t, Eigen::Vector3d>> positions;
  for (int y = 0; y < 4; ++y) {
    for (int x = 0; x < 5; ++x)
      positions.emplace_back(1 + x + 5 * y, Eigen::Vector3d(10.0 * x, 10.0 * y, 0));
  }
  positions.emplace_back(99, Eigen::Vector3d(1000, 0, 0));
  SpatialPairOptions options;
  options.num_neighbors = 4;
  options.max_distance = 10.5;
  const std::set<ImagePair> pairs = AsSet(SpatialPairs(positions, options));
  // Within 10.5 m only the 4-neighbourhood: 4 * 4 horizontal + 5 * 3 vertical edges.
  EXPECT_EQ(pairs.size(), 31u);
  for (const auto& [a, b] : pairs) {
    EXPECT_NE(b, 99u);
    const int dx = std::abs(static_cast<int>((a - 1) % 5) - static_cast<int>((b - 1) % 5));
    const int dy = std::abs(static_cast<int>((a - 1) / 5) - static_cast<int>((b - 1) / 5));
    EXPECT_EQ(dx + dy, 1) << a << " " << b;
  }
  // One neighbour each, any distance: every image pairs with a nearest one, 99 included.
  options.num_neighbors = 1;
  options.max_distance = 1e6;
  const std::set<ImagePair> nearest = AsSet(SpatialPairs(positions, options));
  EXPECT_TRUE(nearest.count({5, 99}) > 0);  // Image 5 at (40, 0) is the nearest to 99.
  EXPECT_LE(nearest.size(), positions.size());
}

TEST(PairSelection, LoopClosingPairsJoinImagesWithCommonNeighbours) {
  // A square 1-2-3-4 verified along its sides, a tail 4-5, and 6-7 alone.
  const std::vector<std::pair<image_pair_t, int>> verified = {
      {ImagePairToPairId(1, 2), 100}, {ImagePairToPairId(2, 3), 100},
      {ImagePairToPairId(3, 4), 100}, {ImagePairToPairId(4, 1), 100},
      {ImagePairToPairId(4, 5), 100}, {ImagePairToPairId(6, 7), 100}};
  const std::set<ImagePair> pairs = AsSet(LoopClosingPairs(verified, {1, 2, 3, 4, 5, 6, 7}, 5));
  // The diagonals have two common neighbours; 5 shares only 4 with 1 and 3: not enough.
  EXPECT_EQ(pairs, (std::set<ImagePair>{{1, 3}, {2, 4}}));
  EXPECT_TRUE(LoopClosingPairs(verified, {1, 2, 3, 4, 5, 6, 7}, 0).empty());
}

TEST(PairSelection, RetrievalPairsAreTheNearestWhateverTheThreads) {
  // Images along a line: image k sees words 10k to 10k + 29, so it shares two thirds of its
  // words with each neighbour, a third with the next ones. Image 99 is not indexed.
  constexpr int kNumImages = 40;
  RetrievalIndex index(10 * kNumImages + 30);
  std::vector<image_t> image_ids;
  for (image_t k = 1; k <= kNumImages; ++k) {
    std::vector<visual_word_t> words;
    for (visual_word_t word = 10 * k; word < 10 * k + 30; ++word) words.push_back(word);
    index.AddImage(k, words);
    image_ids.push_back(k);
  }
  index.Finalize();
  image_ids.push_back(99);
  const std::vector<ImagePair> one_thread = RetrievalPairs(index, image_ids, 2, 1);
  EXPECT_EQ(RetrievalPairs(index, image_ids, 2, 3), one_thread);
  std::set<ImagePair> expected;
  for (image_t k = 1; k < kNumImages; ++k) expected.insert({k, k + 1});
  for (const ImagePair& pair : one_thread) {
    EXPECT_NE(pair.first, 99u);
    EXPECT_NE(pair.second, 99u);
  }
  // Every neighbour pair is retrieved; the ends' second choices are two apart.
  const std::set<ImagePair> found = AsSet(one_thread);
  for (const ImagePair& pair : expected) EXPECT_EQ(found.count(pair), 1u) << pair.first;
  EXPECT_EQ(found.size(), expected.size() + 2);
}

TEST(PairSelection, LocalityOrderKeepsEveryPairOnce) {
  const std::vector<ImagePair> pairs = {{5, 9}, {1, 2}, {9, 2}, {3, 4}, {1, 9}};
  const std::vector<ImagePair> ordered = OrderPairsForLocality(pairs, {1, 2, 3, 4, 5, 9});
  EXPECT_EQ(AsSet(ordered), AsSet(pairs));
  EXPECT_EQ(ordered.size(), pairs.size());
  // Breadth-first from image 1: its pairs come first.
  EXPECT_EQ(ordered.front(), (ImagePair{1, 2}));
}

// A small rendered survey: retrieval pairs overlapping views, the trained tree is saved and
// reused, auto picks by size and adds GPS neighbours.
class AerialPairSelectionTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::ScopedTestDir("parallax_pair_selection_test");
    SyntheticSceneOptions scene;
    scene.layout = SyntheticSceneOptions::Layout::kAerial;
    scene.num_views = 24;
    // Quarter-size views keep the suite fast (also under the sanitizers).
    scene.width = 320;
    scene.height = 240;
    scene.num_threads = 2;
    GenerateSyntheticScene(scene, dir_->path() / "images");
    Database database(dir_->path() / "database.db");
    ExtractionStageOptions extraction;
    extraction.num_threads = 2;
    RunExtractionStage(extraction, dir_->path() / "images", &database);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }

  // Ground-truth pairs with at least `min_shared` scene points, by image id.
  static std::map<ImagePair, int> TruthPairs(const Database& database) {
    std::map<std::string, image_t> id_of_name;
    for (const Image& image : database.ReadAllImages()) id_of_name[image.name] = image.image_id;
    std::map<ImagePair, int> truth;
    std::ifstream stream(dir_->path() / "images" / "gt" / "overlap_pairs.txt");
    std::string name1, name2;
    int shared = 0;
    while (stream >> name1 >> name2 >> shared) {
      const image_t a = id_of_name.at(name1), b = id_of_name.at(name2);
      truth[{std::min(a, b), std::max(a, b)}] = shared;
    }
    return truth;
  }

  static std::vector<image_t> ImageIds(const Database& database) {
    std::vector<image_t> ids;
    for (const Image& image : database.ReadAllImages()) ids.push_back(image.image_id);
    return ids;
  }

  static test::ScopedTestDir* dir_;
};
test::ScopedTestDir* AerialPairSelectionTest::dir_ = nullptr;

TEST_F(AerialPairSelectionTest, RetrievalFindsOverlappingViewsAndSavesItsTree) {
  const Database database(dir_->path() / "database.db");
  ASSERT_EQ(database.NumImages(), 24u);
  const std::map<ImagePair, int> truth = TruthPairs(database);
  PairSelectionOptions options;
  options.mode = PairMode::kRetrieval;
  options.retrieval.num_neighbors = 5;
  options.retrieval.tree.depth = 3;
  options.num_threads = 2;
  const PairSelection selection = SelectPairs(options, ImageIds(database), database);
  EXPECT_TRUE(selection.trained_vocab_tree);
  EXPECT_EQ(selection.vocab_tree_path, DefaultVocabTreePath(database.Path()));
  EXPECT_TRUE(fs::exists(selection.vocab_tree_path));
  ASSERT_FALSE(selection.pairs.empty());
  EXPECT_LE(selection.pairs.size(), 24u * 5u);
  // Retrieved pairs overlap: most share 100 scene points or more (roofs, streets and fields
  // repeat, so some look alike without overlapping), and nearly every image finds such a partner.
  int overlapping = 0;
  std::set<image_t> with_partner;
  for (const auto& [a, b] : AsSet(selection.pairs)) {
    const auto it = truth.find({a, b});
    if (it == truth.end() || it->second < 100) continue;
    ++overlapping;
    with_partner.insert(a);
    with_partner.insert(b);
  }
  EXPECT_GE(overlapping, 0.75 * selection.pairs.size())
      << overlapping << " of " << selection.pairs.size();
  EXPECT_GE(with_partner.size(), 21u);  // Oblique views at the edge may find none.

  // A second selection reads the saved tree and gives the same pairs.
  const PairSelection again = SelectPairs(options, ImageIds(database), database);
  EXPECT_FALSE(again.trained_vocab_tree);
  EXPECT_EQ(again.pairs, selection.pairs);
}

TEST_F(AerialPairSelectionTest, AutoChoosesBySizeAndAddsGpsNeighbours) {
  const Database database(dir_->path() / "database.db");
  // Every view carries its EXIF GPS position, a few metres off the truth.
  EXPECT_EQ(database.ReadImageGpsPriors().size(), 24u);
  PairSelectionOptions options;
  options.num_threads = 2;
  options.retrieval.tree.depth = 3;
  options.retrieval.vocab_tree_path.clear();
  const PairSelection small = SelectPairs(options, ImageIds(database), database);
  EXPECT_EQ(small.modes, std::vector<PairMode>{PairMode::kExhaustive});
  EXPECT_EQ(small.pairs.size(), 24u * 23u / 2u);
  options.auto_exhaustive_max_images = 10;
  const PairSelection large = SelectPairs(options, ImageIds(database), database);
  EXPECT_EQ(large.modes, (std::vector<PairMode>{PairMode::kRetrieval, PairMode::kSpatial}));
  EXPECT_GT(large.num_spatial_pairs, 0u);
  EXPECT_NE(large.reason.find("GPS"), std::string::npos) << large.reason;
  // Beside GPS neighbours, retrieval takes fewer images per image: the near overlaps are GPS's.
  options.retrieval.num_neighbors = 6;
  options.retrieval.num_neighbors_with_gps = 2;
  const PairSelection with_gps = SelectPairs(options, ImageIds(database), database);
  EXPECT_GT(with_gps.num_retrieval_pairs, 0u);
  EXPECT_LE(with_gps.num_retrieval_pairs, 24u * 2u);
  options.mode = PairMode::kRetrieval;
  const PairSelection without_gps = SelectPairs(options, ImageIds(database), database);
  EXPECT_GT(without_gps.num_retrieval_pairs, 24u * 2u);
  // GPS neighbours within 150 m of a survey flown 60 m up overlap nearly always.
  const std::map<ImagePair, int> truth = TruthPairs(database);
  options.mode = PairMode::kSpatial;
  options.spatial.num_neighbors = 4;
  const PairSelection spatial = SelectPairs(options, ImageIds(database), database);
  int overlapping = 0;
  for (const auto& pair : AsSet(spatial.pairs)) overlapping += truth.count(pair) > 0 ? 1 : 0;
  EXPECT_GE(overlapping, 0.9 * spatial.pairs.size())
      << overlapping << " of " << spatial.pairs.size();
}

TEST_F(AerialPairSelectionTest, BadTreeFileNamesItself) {
  const Database database(dir_->path() / "database.db");
  const fs::path truncated = dir_->path() / "truncated.vocab_tree";
  {
    std::ofstream stream(truncated, std::ios::binary);
    stream << "PLXVOCAB\x01";
  }
  PairSelectionOptions options;
  options.mode = PairMode::kRetrieval;
  options.retrieval.vocab_tree_path = truncated;
  try {
    SelectPairs(options, ImageIds(database), database);
    FAIL() << "a truncated tree was accepted";
  } catch (const InputError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find(truncated.string()), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace parallax
