// SIFT extraction time per image with the default (paper) settings, images decoded beforehand:
// templeRing (640x480) and one fountain-P11 photo (3072x2048; below the default
// max_image_size of 3200, so extracted at full size). OpenCV's SIFT runs its pyramid and
// extrema search with cv::parallel_for_, so each case runs with 1 and 2 OpenCV threads.
//
//   build-X/bench/feature_extraction_bench [--benchmark_filter=...]

#include <benchmark/benchmark.h>

#include <ctime>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "parallax/feature/gaussian_blur.h"
#include "parallax/feature/sift.h"
#include "parallax/image/image_codecs.h"
#include "parallax/image/image_reader.h"
#include "parallax/util/file.h"
#include "parallax/util/timer.h"

namespace parallax {
namespace {

// The first `max_images` image files of a data set folder, or none when it is missing.
std::vector<std::filesystem::path> ImagePaths(const std::string& folder, size_t max_images) {
  const std::filesystem::path dir = DataRoot() / folder / "images";
  if (!std::filesystem::is_directory(dir)) return {};
  std::vector<std::filesystem::path> paths = ListImageFiles(dir);
  if (paths.size() > max_images) paths.resize(max_images);
  return paths;
}

// Gray images of a data set folder (the first `max_images`), or empty when it is missing.
std::vector<cv::Mat> LoadGray(const std::string& folder, size_t max_images) {
  std::vector<cv::Mat> images;
  for (const auto& path : ImagePaths(folder, max_images)) images.push_back(ReadBitmap(path).gray);
  return images;
}

// CPU seconds of all threads of the process: on a shared, loaded machine the single-thread
// CPU time is the steadier measure of the work done.
double ProcessCpuSeconds() {
  timespec time;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &time);
  return static_cast<double>(time.tv_sec) + 1e-9 * static_cast<double>(time.tv_nsec);
}

const std::vector<cv::Mat>& Images(int which) {
  static const std::vector<cv::Mat> temple = LoadGray("templeRing", 8);
  static const std::vector<cv::Mat> fountain = LoadGray("fountain-P11", 1);
  return which == 0 ? temple : fountain;
}

// Args: data set (0 templeRing, 1 fountain-P11), OpenCV threads.
void BM_SiftExtraction(benchmark::State& state) {
  const std::vector<cv::Mat>& images = Images(static_cast<int>(state.range(0)));
  if (images.empty()) {
    state.SkipWithError("data set missing");
    return;
  }
  const int previous_threads = cv::getNumThreads();
  cv::setNumThreads(static_cast<int>(state.range(1)));
  const auto extractor = CreateSiftExtractor(SiftExtractionOptions());
  size_t index = 0, total_keypoints = 0;
  double total_seconds = 0.0, total_cpu_seconds = 0.0;
  for (auto _ : state) {
    const cv::Mat& image = images[index++ % images.size()];
    FeatureKeypoints keypoints;
    FeatureDescriptors descriptors;
    Timer timer;
    const double cpu_start = ProcessCpuSeconds();
    extractor->Extract(image, &keypoints, &descriptors);
    total_cpu_seconds += ProcessCpuSeconds() - cpu_start;
    total_seconds += timer.ElapsedSeconds();
    total_keypoints += keypoints.size();
  }
  cv::setNumThreads(previous_threads);
  const double iterations = static_cast<double>(state.iterations());
  state.counters["ms_per_image"] = 1e3 * total_seconds / iterations;
  state.counters["cpu_ms_per_image"] = 1e3 * total_cpu_seconds / iterations;
  state.counters["keypoints"] = total_keypoints / iterations;
  state.SetLabel(std::to_string(images[0].cols) + "x" + std::to_string(images[0].rows));
}

BENCHMARK(BM_SiftExtraction)
    ->ArgNames({"dataset", "threads"})
    ->Args({0, 1})
    ->Args({0, 2})
    ->Iterations(16)  // Each of the 8 images twice.
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SiftExtraction)
    ->ArgNames({"dataset", "threads"})
    ->Args({1, 1})
    ->Args({1, 2})
    ->Iterations(3)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

// One layer of the scale space's blur on templeRing's doubled first octave (1280x960), the
// bulk of extraction's time: args are the sigma in hundredths (1.25: the first layer's
// increment; 3.09: the last's, with the widest kernel) and the image's width (256: a strip
// that stays in cache).
void BM_GaussianBlur(benchmark::State& state) {
  cv::Mat image(960, static_cast<int>(state.range(1)), CV_32F);
  cv::RNG rng(1);
  rng.fill(image, cv::RNG::UNIFORM, 0.0f, 1.0f);
  const double sigma = 0.01 * static_cast<double>(state.range(0));
  cv::Mat blurred;
  for (auto _ : state) {
    GaussianBlur(image, sigma, &blurred);
    benchmark::DoNotOptimize(blurred.data);
  }
  state.counters["ns_per_pixel"] = benchmark::Counter(
      static_cast<double>(image.total()) * static_cast<double>(state.iterations()),
      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

BENCHMARK(BM_GaussianBlur)
    ->ArgNames({"sigma_x100", "width"})
    ->Args({125, 1280})
    ->Args({309, 1280})
    ->Args({309, 256})
    ->Unit(benchmark::kMillisecond);

// Decoding templeRing's photos (640x480 RGB PNG files, read into memory beforehand) as the
// features stage decodes them: arg 0 DecodeImage (libdeflate, image/common_png.h), 1 OpenCV's
// imdecode (libpng and zlib, what DecodeImage used before).
void BM_DecodePng(benchmark::State& state) {
  static const std::vector<std::string> files = [] {
    std::vector<std::string> bytes;
    for (const auto& path : ImagePaths("templeRing", 8)) bytes.push_back(ReadFileToString(path));
    return bytes;
  }();
  if (files.empty()) {
    state.SkipWithError("data set missing");
    return;
  }
  size_t index = 0;
  for (auto _ : state) {
    const std::string& bytes = files[index++ % files.size()];
    const cv::Mat image =
        state.range(0) == 0
            ? DecodeImage(bytes, ImageFormat::kPng)
            : cv::imdecode(std::vector<uchar>(bytes.begin(), bytes.end()), cv::IMREAD_UNCHANGED);
    benchmark::DoNotOptimize(image.data);
  }
  state.SetLabel(state.range(0) == 0 ? "DecodeImage" : "cv::imdecode");
}

BENCHMARK(BM_DecodePng)->ArgName("opencv")->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace parallax

BENCHMARK_MAIN();
