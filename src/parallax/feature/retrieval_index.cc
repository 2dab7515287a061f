// The tf-idf inverted-file index over images' visual words (RetrievalIndex).

#include <algorithm>
#include <cmath>
#include <utility>

#include "parallax/feature/vocabulary_tree.h"
#include "parallax/util/check.h"

namespace parallax {
namespace {

// The distinct words, ascending, with their counts.
std::vector<std::pair<visual_word_t, uint32_t>> CountWords(std::vector<visual_word_t> words,
                                                           int num_words) {
  std::sort(words.begin(), words.end());
  std::vector<std::pair<visual_word_t, uint32_t>> counts;
  for (const visual_word_t word : words) {
    PARALLAX_CHECK_LT(word, static_cast<visual_word_t>(num_words));
    if (counts.empty() || counts.back().first != word) counts.emplace_back(word, 0);
    ++counts.back().second;
  }
  return counts;
}

}  // namespace

RetrievalIndex::RetrievalIndex(int num_words) : num_words_(num_words), postings_(num_words) {
  PARALLAX_CHECK_GT(num_words, 0);
}

void RetrievalIndex::AddImage(image_t image_id, const std::vector<visual_word_t>& words) {
  PARALLAX_CHECK(!finalized_);
  PARALLAX_CHECK_MSG(!HasImage(image_id), "image " << image_id << " added twice");
  const uint32_t index = static_cast<uint32_t>(image_ids_.size());
  image_indices_.emplace(image_id, index);
  image_ids_.push_back(image_id);
  for (const auto& [word, count] : CountWords(words, num_words_)) {
    postings_[word].push_back({index, static_cast<float>(count)});
    image_words_.push_back(word);
  }
  image_word_begin_.push_back(image_words_.size());
}

void RetrievalIndex::Finalize() {
  PARALLAX_CHECK(!finalized_);
  finalized_ = true;
  const double num_images = static_cast<double>(image_ids_.size());
  idf_.assign(num_words_, 0.0f);
  std::vector<double> squared_norms(image_ids_.size(), 0.0);
  for (int w = 0; w < num_words_; ++w) {
    if (postings_[w].empty()) continue;
    idf_[w] = static_cast<float>(std::log(num_images / postings_[w].size()));
    for (Posting& posting : postings_[w]) {
      posting.weight *= idf_[w];
      squared_norms[posting.image_index] += double{posting.weight} * posting.weight;
    }
  }
  for (auto& postings : postings_) {
    for (Posting& posting : postings) {
      const double norm = std::sqrt(squared_norms[posting.image_index]);
      posting.weight = norm > 0.0 ? static_cast<float>(posting.weight / norm) : 0.0f;
    }
  }
}

std::vector<std::pair<image_t, float>> RetrievalIndex::Query(
    const std::vector<visual_word_t>& words, int max_results) const {
  PARALLAX_CHECK(finalized_);
  WeightedWords query;
  double squared_norm = 0.0;
  for (const auto& [word, count] : CountWords(words, num_words_)) {
    const float weight = static_cast<float>(count) * idf_[word];
    if (!(weight > 0.0f)) continue;
    query.emplace_back(word, weight);
    squared_norm += double{weight} * weight;
  }
  for (auto& [word, weight] : query) weight = static_cast<float>(weight / std::sqrt(squared_norm));
  return Rank(query, max_results);
}

std::vector<std::pair<image_t, float>> RetrievalIndex::QueryImage(image_t image_id,
                                                                  int max_results) const {
  PARALLAX_CHECK(finalized_);
  const auto found = image_indices_.find(image_id);
  PARALLAX_CHECK_MSG(found != image_indices_.end(), "image " << image_id << " is not indexed");
  const uint32_t index = found->second;
  // The image's own (already normalised) weights, found in the postings by image index.
  WeightedWords query;
  for (size_t i = image_word_begin_[index]; i < image_word_begin_[index + 1]; ++i) {
    const std::vector<Posting>& postings = postings_[image_words_[i]];
    const auto own = std::lower_bound(
        postings.begin(), postings.end(), index,
        [](const Posting& posting, uint32_t value) { return posting.image_index < value; });
    if (own->weight > 0.0f) query.emplace_back(image_words_[i], own->weight);
  }
  return Rank(query, max_results);
}

std::vector<std::pair<image_t, float>> RetrievalIndex::Rank(const WeightedWords& query,
                                                            int max_results) const {
  PARALLAX_CHECK_GE(max_results, 0);
  // Every term is positive, so a score of 0 means "not touched yet".
  std::vector<double> scores(image_ids_.size(), 0.0);
  std::vector<uint32_t> touched;
  for (const auto& [word, weight] : query) {
    for (const Posting& posting : postings_[word]) {
      if (posting.weight <= 0.0f) continue;
      if (scores[posting.image_index] == 0.0) touched.push_back(posting.image_index);
      scores[posting.image_index] += double{weight} * posting.weight;
    }
  }
  std::vector<std::pair<image_t, float>> results;
  results.reserve(touched.size());
  for (const uint32_t index : touched) {
    results.emplace_back(image_ids_[index], static_cast<float>(scores[index]));
  }
  const size_t num_results = std::min(results.size(), static_cast<size_t>(max_results));
  std::partial_sort(results.begin(), results.begin() + num_results, results.end(),
                    [](const auto& a, const auto& b) {
                      return a.second != b.second ? a.second > b.second : a.first < b.first;
                    });
  results.resize(num_results);
  return results;
}

}  // namespace parallax
