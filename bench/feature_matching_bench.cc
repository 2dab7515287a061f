// Descriptor matching throughput: Parallax's blocked matrix-product matcher against OpenCV's
// brute-force matcher (cv::BFMatcher(NORM_L2).knnMatch, k = 2, plus the same ratio test), on
// the same descriptors (Parallax's integer dot products of the stored bytes, OpenCV's float
// distances of the unit rows).
//
//   build-X/bench/feature_matching_bench [--benchmark_filter=...]
//
// Data sets: real SIFT descriptors of templeRing (templeR0001 vs templeR0002, about 800 each;
// and 8 images stacked against 8 others, about 7000 each, the size of a large photo's
// feature set). Random non-negative unit descriptors, quantised as SIFT's are, of the same sizes
// stand in when the data is missing. Before the timings, the program prints how often both matchers
// agree on the nearest neighbour.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <optional>
#include <string>
#include <vector>

#include "parallax/feature/descriptor_cells.h"
#include "parallax/feature/matcher.h"
#include "parallax/feature/sift.h"
#include "parallax/feature/similarity_kernel.h"
#include "parallax/image/image_reader.h"
#include "parallax/math/random.h"
#include "parallax/util/file.h"
#include "parallax/util/timer.h"

namespace parallax {
namespace {

constexpr double kMaxRatio = 0.8;

struct DescriptorPair {
  std::string name;
  MatchableDescriptors descriptors1;
  MatchableDescriptors descriptors2;
  UnitDescriptorRows unit1, unit2;  // The same descriptors as unit floats, for OpenCV.
  cv::Mat mat1, mat2;               // Views of unit1 and unit2.
};

// Non-negative unit vectors quantised as SIFT descriptors are stored (x 512, at most 255).
FeatureDescriptors RandomDescriptors(int num) {
  FeatureDescriptors descriptors(num, 128);
  for (int i = 0; i < num; ++i) {
    Eigen::VectorXf values(128);
    for (int k = 0; k < 128; ++k) values[k] = static_cast<float>(std::abs(RandomGaussian(0, 1)));
    values.normalize();
    for (int k = 0; k < 128; ++k) {
      descriptors(i, k) = static_cast<uint8_t>(std::min(255.0f, std::round(512.0f * values[k])));
    }
  }
  return descriptors;
}

// SIFT descriptors of the templeRing images with the given 1-based numbers, stacked.
std::optional<FeatureDescriptors> TempleDescriptors(const std::vector<int>& numbers) {
  const std::filesystem::path dir = DataRoot() / "templeRing" / "images";
  if (!std::filesystem::is_directory(dir)) return std::nullopt;
  const auto extractor = CreateSiftExtractor(SiftExtractionOptions());
  std::vector<FeatureDescriptors> parts;
  Eigen::Index total = 0;
  for (const int number : numbers) {
    char name[64];
    std::snprintf(name, sizeof(name), "templeR%04d.png", number);
    FeatureKeypoints keypoints;
    FeatureDescriptors descriptors;
    extractor->Extract(ReadBitmap(dir / name).gray, &keypoints, &descriptors);
    total += descriptors.rows();
    parts.push_back(std::move(descriptors));
  }
  FeatureDescriptors stacked(total, 128);
  Eigen::Index row = 0;
  for (const auto& part : parts) {
    stacked.middleRows(row, part.rows()) = part;
    row += part.rows();
  }
  return stacked;
}

DescriptorPair MakePair(const std::string& name, const std::vector<int>& numbers1,
                        const std::vector<int>& numbers2, int random_size) {
  DescriptorPair pair;
  auto descriptors1 = TempleDescriptors(numbers1);
  auto descriptors2 = TempleDescriptors(numbers2);
  pair.name = name;
  if (!descriptors1 || !descriptors2) {
    pair.name += " (random: no templeRing data)";
    descriptors1 = RandomDescriptors(random_size);
    descriptors2 = RandomDescriptors(random_size);
  }
  pair.descriptors1 = PrepareDescriptors(*descriptors1);
  pair.descriptors2 = PrepareDescriptors(*descriptors2);
  pair.unit1 = ToUnitRows(*descriptors1);
  pair.unit2 = ToUnitRows(*descriptors2);
  return pair;
}

// 0: one image pair; 1: eight images against eight others.
const DescriptorPair& Pair(int which) {
  static const std::vector<DescriptorPair> pairs = [] {
    std::vector<DescriptorPair> result;
    result.push_back(MakePair("templeR0001 vs templeR0002", {1}, {2}, 800));
    result.push_back(MakePair("templeR0001-0008 vs templeR0009-0016", {1, 2, 3, 4, 5, 6, 7, 8},
                              {9, 10, 11, 12, 13, 14, 15, 16}, 7000));
    // The OpenCV views are made once the pairs no longer move (copying a pair would leave
    // them pointing at the old buffers).
    for (DescriptorPair& pair : result) {
      pair.mat1 = cv::Mat(static_cast<int>(pair.unit1.rows()), 128, CV_32F, pair.unit1.data());
      pair.mat2 = cv::Mat(static_cast<int>(pair.unit2.rows()), 128, CV_32F, pair.unit2.data());
    }
    return result;
  }();
  return pairs.at(which);
}

FeatureMatches OpenCvRatioMatch(const DescriptorPair& pair,
                                std::vector<std::vector<cv::DMatch>>* knn) {
  cv::BFMatcher matcher(cv::NORM_L2);
  knn->clear();  // knnMatch appends.
  matcher.knnMatch(pair.mat1, pair.mat2, *knn, 2);
  FeatureMatches matches;
  for (const auto& candidates : *knn) {
    if (candidates.empty()) continue;
    const bool has_second = candidates.size() > 1;
    if (has_second && !(candidates[0].distance < kMaxRatio * candidates[1].distance)) continue;
    matches.push_back({static_cast<point2D_t>(candidates[0].queryIdx),
                       static_cast<point2D_t>(candidates[0].trainIdx)});
  }
  return matches;
}

// CPU seconds of all threads of the process: on a shared, loaded machine the single-thread
// CPU time is the steadier measure of the work done.
double ProcessCpuSeconds() {
  timespec time;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &time);
  return static_cast<double>(time.tv_sec) + 1e-9 * static_cast<double>(time.tv_nsec);
}

void SetCounters(benchmark::State& state, const DescriptorPair& pair, double total_seconds,
                 double total_cpu_seconds, size_t num_matches) {
  const double iterations = static_cast<double>(state.iterations());
  const double flops = 2.0 * pair.descriptors1.NumRows() * pair.descriptors2.NumRows() * 128;
  state.counters["ms_per_pair"] = 1e3 * total_seconds / iterations;
  state.counters["cpu_ms_per_pair"] = 1e3 * total_cpu_seconds / iterations;
  state.counters["GFLOP/s"] = flops * iterations / total_seconds * 1e-9;
  state.counters["matches"] = static_cast<double>(num_matches);
  state.SetLabel(pair.name);
}

// Args: pair, threads, cross-check.
void BM_ParallaxMatch(benchmark::State& state) {
  const DescriptorPair& pair = Pair(static_cast<int>(state.range(0)));
  FeatureMatchingOptions options;
  options.max_ratio = kMaxRatio;
  options.max_distance = 2.0;  // No bound, as in the OpenCV variant.
  options.num_threads = static_cast<int>(state.range(1));
  options.cross_check = state.range(2) != 0;
  double total_seconds = 0.0, total_cpu_seconds = 0.0;
  size_t num_matches = 0;
  for (auto _ : state) {
    Timer timer;
    const double cpu_start = ProcessCpuSeconds();
    const FeatureMatches matches = MatchDescriptors(pair.descriptors1, pair.descriptors2, options);
    total_cpu_seconds += ProcessCpuSeconds() - cpu_start;
    total_seconds += timer.ElapsedSeconds();
    num_matches = matches.size();
    benchmark::DoNotOptimize(matches.data());
  }
  SetCounters(state, pair, total_seconds, total_cpu_seconds, num_matches);
}

// Approximate matching (descriptor_cells.h) on one thread, cross-checked, as the matching
// stage runs it. Args: pair, cells, assignments. Counters: the share of the exact matcher's
// matches it returns too, and the share of descriptor pairs it compares.
void BM_ParallaxMatchInCells(benchmark::State& state) {
  const DescriptorPair& pair = Pair(static_cast<int>(state.range(0)));
  DescriptorCellsOptions cells_options;
  cells_options.num_cells = static_cast<int>(state.range(1));
  cells_options.num_assignments = static_cast<int>(state.range(2));
  FeatureDescriptors both(pair.descriptors1.NumRows() + pair.descriptors2.NumRows(), 128);
  both << pair.descriptors1.bytes, pair.descriptors2.bytes;
  const DescriptorCells cells = DescriptorCells::Train(both, cells_options);
  const CellFiledDescriptors filed1 =
      FileDescriptorsByCell(pair.descriptors1, cells, cells_options.num_assignments);
  const CellFiledDescriptors filed2 =
      FileDescriptorsByCell(pair.descriptors2, cells, cells_options.num_assignments);
  FeatureMatchingOptions options;
  options.max_ratio = kMaxRatio;
  options.num_threads = 1;
  double total_seconds = 0.0, total_cpu_seconds = 0.0;
  FeatureMatches matches;
  for (auto _ : state) {
    Timer timer;
    const double cpu_start = ProcessCpuSeconds();
    matches = MatchDescriptorsInCells(filed1, filed2, pair.descriptors2, options);
    total_cpu_seconds += ProcessCpuSeconds() - cpu_start;
    total_seconds += timer.ElapsedSeconds();
    benchmark::DoNotOptimize(matches.data());
  }
  SetCounters(state, pair, total_seconds, total_cpu_seconds, matches.size());
  const FeatureMatches exact = MatchDescriptors(pair.descriptors1, pair.descriptors2, options);
  size_t same = 0;
  for (const FeatureMatch& match : matches) {
    same += std::any_of(exact.begin(), exact.end(), [&match](const FeatureMatch& other) {
      return other.point2D_idx1 == match.point2D_idx1 && other.point2D_idx2 == match.point2D_idx2;
    });
  }
  double compared = 0;
  for (size_t c = 0; c < filed1.cells.size(); ++c) {
    compared += static_cast<double>(filed1.cells[c].query_rows.size()) *
                static_cast<double>(filed2.cells[c].searched_rows.size());
  }
  state.counters["exact_matches_found"] = static_cast<double>(same) / exact.size();
  state.counters["pairs_compared"] =
      compared / (static_cast<double>(filed1.num_rows) * filed2.num_rows);
}

// Args: pair, threads (cv::setNumThreads).
void BM_OpenCvKnnMatch(benchmark::State& state) {
  const DescriptorPair& pair = Pair(static_cast<int>(state.range(0)));
  const int previous_threads = cv::getNumThreads();
  cv::setNumThreads(static_cast<int>(state.range(1)));
  double total_seconds = 0.0, total_cpu_seconds = 0.0;
  size_t num_matches = 0;
  std::vector<std::vector<cv::DMatch>> knn;
  for (auto _ : state) {
    Timer timer;
    const double cpu_start = ProcessCpuSeconds();
    const FeatureMatches matches = OpenCvRatioMatch(pair, &knn);
    total_cpu_seconds += ProcessCpuSeconds() - cpu_start;
    total_seconds += timer.ElapsedSeconds();
    num_matches = matches.size();
    benchmark::DoNotOptimize(matches.data());
  }
  cv::setNumThreads(previous_threads);
  SetCounters(state, pair, total_seconds, total_cpu_seconds, num_matches);
}

BENCHMARK(BM_ParallaxMatch)
    ->ArgNames({"pair", "threads", "cross_check"})
    ->ArgsProduct({{0, 1}, {1, 2}, {0, 1}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ParallaxMatchInCells)
    ->ArgNames({"pair", "cells", "assignments"})
    ->ArgsProduct({{0, 1}, {32}, {2, 3, 4}})
    ->Args({1, 64, 4})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OpenCvKnnMatch)
    ->ArgNames({"pair", "threads"})
    ->ArgsProduct({{0, 1}, {1, 2}})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

// The similarity kernel alone on the matcher's largest tile: 256 descriptors of image 2
// against a block of 256 of image 1, 128 bytes each (2 x 256 x 256 x 128 operations per call).
// Arg: kernel (0 scalar, 1 AVX2, 2 AVX-512 VNNI); skipped where the CPU lacks it.
void BM_SimilarityKernel(benchmark::State& state) {
  const auto kernel = static_cast<SimilarityKernel>(state.range(0));
  if (!SimilarityKernelAvailable(kernel)) {
    state.SkipWithError("this CPU does not run the kernel");
    return;
  }
  constexpr int kNum = 256;
  const MatchableDescriptors a = PrepareDescriptors(RandomDescriptors(kNum));
  const MatchableDescriptors b = PrepareDescriptors(RandomDescriptors(kNum));
  std::vector<float> out(static_cast<size_t>(kNum) * kNum);
  PackedSimilarityColumns a_packed;
  PackSimilarityColumns(a.bytes.data(), a.scales.data(), kNum, 128, kernel, &a_packed);
  for (auto _ : state) {
    ComputeSimilarities(a_packed, {b.bytes.data(), b.scales.data(), b.sums.data(), kNum},
                        out.data());
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["GFLOP/s"] = benchmark::Counter(2.0 * kNum * kNum * 128 * state.iterations() / 1e9,
                                                 benchmark::Counter::kIsRate);
}
BENCHMARK(BM_SimilarityKernel)->ArgName("kernel")->DenseRange(0, 2)->Unit(benchmark::kMicrosecond);

// Nearest-neighbour agreement between the two matchers, and agreement of the ratio-test
// matches. With the ratio at 1 and no distance bound, Parallax returns every query's nearest
// neighbour except exact ties (which it rejects); a tie counts as agreeing when OpenCV's two
// best distances are equal too.
void PrintAgreement(int which) {
  const DescriptorPair& pair = Pair(which);
  const int num_queries = pair.descriptors1.NumRows();
  std::vector<std::vector<cv::DMatch>> knn;
  const FeatureMatches opencv_matches = OpenCvRatioMatch(pair, &knn);

  FeatureMatchingOptions nearest_options;
  nearest_options.max_ratio = 1.0;
  nearest_options.max_distance = 2.0;
  nearest_options.cross_check = false;
  std::vector<int> nearest(num_queries, -1);
  for (const auto& match :
       MatchDescriptors(pair.descriptors1, pair.descriptors2, nearest_options)) {
    nearest[match.point2D_idx1] = static_cast<int>(match.point2D_idx2);
  }
  int num_agreeing = 0;
  for (int i = 0; i < num_queries; ++i) {
    const auto& candidates = knn[i];
    if (nearest[i] == candidates[0].trainIdx) {
      ++num_agreeing;
    } else if (nearest[i] < 0 && candidates.size() > 1 &&
               candidates[0].distance == candidates[1].distance) {
      ++num_agreeing;
    }
  }

  FeatureMatchingOptions ratio_options = nearest_options;
  ratio_options.max_ratio = kMaxRatio;
  const FeatureMatches parallax_matches =
      MatchDescriptors(pair.descriptors1, pair.descriptors2, ratio_options);
  size_t num_common = 0;
  std::vector<int> opencv_partner(num_queries, -1);
  for (const auto& match : opencv_matches) {
    opencv_partner[match.point2D_idx1] = static_cast<int>(match.point2D_idx2);
  }
  for (const auto& match : parallax_matches) {
    num_common += opencv_partner[match.point2D_idx1] == static_cast<int>(match.point2D_idx2);
  }
  std::printf(
      "%s: %d x %d descriptors; nearest neighbour agrees for %d of %d queries (%.3f %%); "
      "ratio-test matches: Parallax %zu, OpenCV %zu, common %zu\n",
      pair.name.c_str(), num_queries, pair.descriptors2.NumRows(), num_agreeing, num_queries,
      100.0 * num_agreeing / num_queries, parallax_matches.size(), opencv_matches.size(),
      num_common);
  std::fflush(stdout);
}

}  // namespace
}  // namespace parallax

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  parallax::SetPRNGSeed(0);
  parallax::PrintAgreement(0);
  parallax::PrintAgreement(1);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
