#include "parallax/feature/vocabulary_tree.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <sstream>

#include "parallax/util/check.h"
#include "parallax/util/content_hash.h"
#include "parallax/util/file.h"
#include "parallax/util/test_dir.h"

namespace parallax {
namespace {

using RowMatrixXf = VocabularyTree::RowMatrixXf;

RowMatrixXf RandomUnitRows(int num, int dim, std::mt19937_64* rng) {
  std::normal_distribution<float> normal;
  RowMatrixXf rows(num, dim);
  for (int i = 0; i < num; ++i) {
    for (int k = 0; k < dim; ++k) rows(i, k) = normal(*rng);
    rows.row(i).normalize();
  }
  return rows;
}

// `row` plus Gaussian noise of expected norm `noise`, renormalised.
Eigen::RowVectorXf NoisyCopy(const Eigen::RowVectorXf& row, float noise, std::mt19937_64* rng) {
  std::normal_distribution<float> normal(0.0f, noise / std::sqrt(static_cast<float>(row.size())));
  Eigen::RowVectorXf copy = row;
  for (Eigen::Index k = 0; k < copy.size(); ++k) copy(k) += normal(*rng);
  return copy.normalized();
}

std::string TreeBytes(const VocabularyTree& tree) {
  std::ostringstream stream;
  tree.Write(stream);
  return stream.str();
}

VocabularyTreeOptions SmallOptions(int depth) {
  VocabularyTreeOptions options;
  options.depth = depth;
  options.seed = 7;
  return options;
}

TEST(VocabularyTree, NoisySamplesGetTheirCentresWord) {
  std::mt19937_64 rng(1);
  constexpr int kNumCentres = 1000, kSamplesPerCentre = 20;
  const RowMatrixXf centres = RandomUnitRows(kNumCentres, 128, &rng);
  RowMatrixXf samples(kNumCentres * kSamplesPerCentre, 128);
  for (int i = 0; i < samples.rows(); ++i) {
    samples.row(i) = NoisyCopy(centres.row(i / kSamplesPerCentre), 0.1f, &rng);
  }
  // Depth 2: about 10 centres per leaf, so no leaf has to split a centre's samples.
  const VocabularyTree tree = VocabularyTree::Train(samples, SmallOptions(2));
  EXPECT_EQ(tree.DescriptorDimension(), 128);
  EXPECT_EQ(tree.Depth(), 2);
  EXPECT_GT(tree.NumWords(), 90);
  EXPECT_LE(tree.NumWords(), 100);

  const std::vector<visual_word_t> centre_words = tree.Quantize(centres);
  const std::vector<visual_word_t> sample_words = tree.Quantize(samples);
  int num_agreeing = 0;
  for (int i = 0; i < samples.rows(); ++i) {
    ASSERT_LT(sample_words[i], static_cast<visual_word_t>(tree.NumWords()));
    num_agreeing += sample_words[i] == centre_words[i / kSamplesPerCentre];
  }
  EXPECT_GT(num_agreeing, 0.95 * samples.rows());
  // And the words tell centres apart: none holds many more than the 10 of a balanced tree.
  std::map<visual_word_t, int> centres_per_word;
  for (const visual_word_t word : centre_words) ++centres_per_word[word];
  EXPECT_GT(centres_per_word.size(), 90u);
  for (const auto& [word, count] : centres_per_word) EXPECT_LE(count, 40) << "word " << word;
}

TEST(VocabularyTree, SameSeedSameTreeWhateverTheThreadCount) {
  std::mt19937_64 rng(2);
  const RowMatrixXf descriptors = RandomUnitRows(6000, 128, &rng);
  VocabularyTreeOptions options = SmallOptions(3);
  options.max_training_descriptors = 4000;  // Exercises the sampling.
  options.num_threads = 1;
  const VocabularyTree tree1 = VocabularyTree::Train(descriptors, options);
  options.num_threads = 3;
  const VocabularyTree tree3 = VocabularyTree::Train(descriptors, options);
  EXPECT_TRUE(TreeBytes(tree1) == TreeBytes(tree3));  // (Not EXPECT_EQ: it would print them.)
  const std::vector<visual_word_t> words = tree1.Quantize(descriptors, 1);
  EXPECT_EQ(words, tree3.Quantize(descriptors, 4));
  EXPECT_GT(tree1.NumWords(), 500);

  // A descriptor's word does not depend on the rest of its batch.
  const RowMatrixXf reversed = descriptors.colwise().reverse();
  std::vector<visual_word_t> reversed_words = tree1.Quantize(reversed);
  std::reverse(reversed_words.begin(), reversed_words.end());
  EXPECT_EQ(words, reversed_words);
  EXPECT_EQ(tree1.Quantize(descriptors.middleRows(17, 3)),
            std::vector<visual_word_t>(words.begin() + 17, words.begin() + 20));

  options.seed = 8;
  EXPECT_FALSE(TreeBytes(VocabularyTree::Train(descriptors, options)) == TreeBytes(tree1));
}

TEST(VocabularyTree, WideNodesSpanSeveralKernelGroups) {
  // 40 children per node: three groups of the kernel's 16 lanes, the last one partial.
  std::mt19937_64 rng(6);
  const RowMatrixXf centres = RandomUnitRows(40, 128, &rng);
  RowMatrixXf samples(400, 128);
  for (int i = 0; i < 400; ++i) samples.row(i) = NoisyCopy(centres.row(i % 40), 0.1f, &rng);
  VocabularyTreeOptions options = SmallOptions(1);
  options.branching = 40;
  const VocabularyTree tree = VocabularyTree::Train(samples, options);
  EXPECT_GT(tree.NumWords(), 30);
  EXPECT_LE(tree.NumWords(), 40);
  const std::vector<visual_word_t> centre_words = tree.Quantize(centres);
  const std::vector<visual_word_t> sample_words = tree.Quantize(samples);
  int num_agreeing = 0;
  for (int i = 0; i < 400; ++i) num_agreeing += sample_words[i] == centre_words[i % 40];
  EXPECT_GT(num_agreeing, 0.95 * 400);
  EXPECT_GT(std::set<visual_word_t>(centre_words.begin(), centre_words.end()).size(), 30u);

  std::istringstream stream(TreeBytes(tree));
  const VocabularyTree read = VocabularyTree::Read(stream, "memory", 128);
  EXPECT_EQ(read.Quantize(samples), sample_words);
  EXPECT_TRUE(TreeBytes(read) == TreeBytes(tree));
}

TEST(VocabularyTree, SmallOrDegenerateNodesAreLeaves) {
  std::mt19937_64 rng(3);
  const RowMatrixXf few = RandomUnitRows(9, 32, &rng);  // Fewer than `branching`.
  const VocabularyTree tree_few = VocabularyTree::Train(few, SmallOptions(3));
  EXPECT_EQ(tree_few.NumWords(), 1);
  EXPECT_EQ(tree_few.Depth(), 0);
  EXPECT_EQ(tree_few.Quantize(few), std::vector<visual_word_t>(9, 0));
  EXPECT_THROW(tree_few.Quantize(RowMatrixXf(1, 128)), CheckError);  // Another dimension.

  const RowMatrixXf equal = few.row(0).replicate(200, 1);
  const VocabularyTree tree_equal = VocabularyTree::Train(equal, SmallOptions(3));
  EXPECT_EQ(tree_equal.NumWords(), 1);

  // Three distinct rows, many copies each: three leaves under the root, however large k is.
  RowMatrixXf three(300, 32);
  for (int i = 0; i < 300; ++i) three.row(i) = few.row(i % 3);
  const VocabularyTree tree_three = VocabularyTree::Train(three, SmallOptions(3));
  EXPECT_EQ(tree_three.NumWords(), 3);
  EXPECT_EQ(tree_three.Depth(), 1);
  const std::vector<visual_word_t> words = tree_three.Quantize(three);
  EXPECT_EQ(std::set<visual_word_t>(words.begin(), words.end()).size(), 3u);
  for (int i = 3; i < 300; ++i) EXPECT_EQ(words[i], words[i % 3]);
}

TEST(VocabularyTree, OptionsCheck) {
  VocabularyTreeOptions options;
  EXPECT_NO_THROW(options.Check());
  options.branching = 1;
  EXPECT_THROW(options.Check(), CheckError);
  options = VocabularyTreeOptions();
  options.depth = 0;
  EXPECT_THROW(options.Check(), CheckError);
  options = VocabularyTreeOptions();
  options.max_training_descriptors = 0;
  EXPECT_THROW(options.Check(), CheckError);
  options = VocabularyTreeOptions();
  options.num_threads = 0;
  EXPECT_THROW(options.Check(), CheckError);
  EXPECT_THROW(VocabularyTree().Quantize(RowMatrixXf(1, 128)), CheckError);
}

// Expects Read to throw a one-line InputError naming `path` and containing `fragment`.
void ExpectReadError(const std::filesystem::path& path, const std::string& fragment,
                     int expected_dimension = -1) {
  try {
    VocabularyTree::Read(path, expected_dimension);
    ADD_FAILURE() << "expected InputError containing '" << fragment << "'";
  } catch (const InputError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find(path.string()), std::string::npos) << message;
    EXPECT_NE(message.find(fragment), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
}

void WriteBytes(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

TEST(VocabularyTree, WriteReadRoundTripAndBadFiles) {
  test::ScopedTestDir dir("vocabulary_tree");
  std::mt19937_64 rng(4);
  const RowMatrixXf descriptors = RandomUnitRows(3000, 128, &rng);
  const VocabularyTree tree = VocabularyTree::Train(descriptors, SmallOptions(3));
  const std::filesystem::path path = dir.path() / "tree.vocab";
  tree.Write(path);
  const VocabularyTree read = VocabularyTree::Read(path, 128);
  EXPECT_EQ(read.NumWords(), tree.NumWords());
  EXPECT_EQ(read.NumNodes(), tree.NumNodes());
  EXPECT_EQ(read.Depth(), tree.Depth());
  EXPECT_EQ(read.Branching(), 10);
  EXPECT_EQ(read.Quantize(descriptors), tree.Quantize(descriptors));
  const std::string bytes = ReadFileToString(path);
  EXPECT_TRUE(TreeBytes(read) == bytes);

  const std::filesystem::path bad = dir.path() / "bad.vocab";
  ExpectReadError(dir.path() / "missing.vocab", "cannot open");
  WriteBytes(bad, bytes.substr(0, bytes.size() / 2));
  ExpectReadError(bad, "truncated");
  WriteBytes(bad, bytes.substr(0, 20));
  ExpectReadError(bad, "truncated");
  WriteBytes(bad, "PLYVOCAB" + bytes.substr(8));
  ExpectReadError(bad, "not a vocabulary tree");
  WriteBytes(bad, bytes + "garbage");
  ExpectReadError(bad, "7 trailing bytes");
  std::string flipped = bytes;
  flipped[bytes.size() / 2] ^= 1;
  WriteBytes(bad, flipped);
  ExpectReadError(bad, "checksum");
  // A root whose children run past the last node, with a valid checksum: the layout check.
  constexpr size_t kHeaderBytes = 28, kDigestBytes = 32;
  std::string forged = bytes.substr(0, bytes.size() - kDigestBytes);
  const uint32_t num_nodes = static_cast<uint32_t>(tree.NumNodes());
  for (int b = 0; b < 4; ++b) forged[kHeaderBytes + b] = static_cast<char>(num_nodes >> (8 * b));
  WriteBytes(bad, forged + HashBytes(forged));
  ExpectReadError(bad, "out of range");

  const VocabularyTree tree64 =
      VocabularyTree::Train(RandomUnitRows(500, 64, &rng), SmallOptions(2));
  const std::filesystem::path path64 = dir.path() / "tree64.vocab";
  tree64.Write(path64);
  EXPECT_EQ(VocabularyTree::Read(path64).DescriptorDimension(), 64);
  ExpectReadError(path64, "expected 128-D", 128);
}

TEST(RetrievalIndex, ScoresAreTfIdfCosines) {
  RetrievalIndex index(5);
  index.AddImage(10, {0, 0, 1});
  index.AddImage(20, {1, 2});
  index.AddImage(30, {3});
  index.Finalize();
  EXPECT_EQ(index.NumImages(), 3u);
  const double idf0 = std::log(3.0), idf1 = std::log(1.5), idf2 = std::log(3.0);
  // Query {1, 2, 4}: word 4 is in no image, so it carries no weight.
  const std::vector<std::pair<image_t, float>> results = index.Query({1, 2, 4}, 10);
  ASSERT_EQ(results.size(), 2u);  // Image 30 shares no word.
  const double query_norm = std::hypot(idf1, idf2);
  EXPECT_EQ(results[0].first, 20u);
  EXPECT_NEAR(results[0].second, 1.0, 1e-6);
  EXPECT_EQ(results[1].first, 10u);
  EXPECT_NEAR(results[1].second, idf1 * idf1 / (query_norm * std::hypot(2 * idf0, idf1)), 1e-6);
  EXPECT_EQ(index.Query({1, 2}, 1).size(), 1u);
  const auto self = index.QueryImage(30, 10);
  ASSERT_EQ(self.size(), 1u);
  EXPECT_EQ(self[0].first, 30u);
  EXPECT_NEAR(self[0].second, 1.0, 1e-6);
  EXPECT_THROW(index.AddImage(40, {0}), CheckError);  // After Finalize.
}

TEST(RetrievalIndex, ImagesAlongAStripFindTheirNeighbours) {
  std::mt19937_64 rng(5);
  // Image i sees each of scene points [i * kStride, i * kStride + kWindow) with probability 3/4,
  // as a noisy copy, plus unrelated clutter; neighbours along the strip share most points.
  constexpr int kNumImages = 60, kStride = 80, kWindow = 400, kClutter = 30;
  const RowMatrixXf scene = RandomUnitRows(kNumImages * kStride + kWindow, 128, &rng);
  std::bernoulli_distribution seen(0.75);
  std::vector<RowMatrixXf> images(kNumImages);
  RowMatrixXf all(0, 128);
  for (int i = 0; i < kNumImages; ++i) {
    std::vector<Eigen::RowVectorXf> rows;
    for (int p = i * kStride; p < i * kStride + kWindow; ++p) {
      if (seen(rng)) rows.push_back(NoisyCopy(scene.row(p), 0.1f, &rng));
    }
    const RowMatrixXf clutter = RandomUnitRows(kClutter, 128, &rng);
    for (int c = 0; c < kClutter; ++c) rows.push_back(clutter.row(c));
    images[i].resize(rows.size(), 128);
    for (size_t r = 0; r < rows.size(); ++r) images[i].row(r) = rows[r];
    all.conservativeResize(all.rows() + images[i].rows(), Eigen::NoChange);
    all.bottomRows(images[i].rows()) = images[i];
  }
  const VocabularyTree tree = VocabularyTree::Train(all, SmallOptions(3));
  RetrievalIndex index(tree.NumWords());
  std::vector<std::vector<visual_word_t>> words(kNumImages);
  auto image_id = [](int i) { return static_cast<image_t>(100 + 3 * i); };
  for (int i = 0; i < kNumImages; ++i) {
    words[i] = tree.Quantize(images[i]);
    index.AddImage(image_id(i), words[i]);
  }
  index.Finalize();

  int num_neighbours = 0, num_found = 0, num_next_two = 0;
  for (int i = 0; i < kNumImages; ++i) {
    const auto results = index.QueryImage(image_id(i), 5);
    ASSERT_EQ(results.size(), 5u);
    EXPECT_EQ(results[0].first, image_id(i));
    EXPECT_NEAR(results[0].second, 1.0f, 1e-5f);
    for (size_t r = 1; r < results.size(); ++r) EXPECT_LE(results[r].second, results[r - 1].second);
    for (const int j : {i - 1, i + 1}) {
      if (j < 0 || j >= kNumImages) continue;
      ++num_neighbours;
      num_found += std::any_of(results.begin() + 1, results.end(),
                               [&](const auto& result) { return result.first == image_id(j); });
    }
    // The two strip neighbours come right after the image itself (not just somewhere in 5).
    if (i > 0 && i + 1 < kNumImages) {
      const std::set<image_t> next_two = {results[1].first, results[2].first};
      num_next_two += next_two == std::set<image_t>{image_id(i - 1), image_id(i + 1)};
    }
    const auto by_words = index.Query(words[i], 5);
    ASSERT_EQ(by_words.size(), results.size());
    for (size_t r = 0; r < results.size(); ++r) {
      EXPECT_NEAR(by_words[r].second, results[r].second, 1e-5f);
    }
  }
  EXPECT_GT(num_found, 0.9 * num_neighbours);
  EXPECT_GT(num_next_two, 0.9 * (kNumImages - 2));
}

}  // namespace
}  // namespace parallax
