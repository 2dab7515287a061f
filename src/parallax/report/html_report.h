#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "parallax/report/evaluation.h"
#include "parallax/scene/database.h"
#include "parallax/scene/reconstruction.h"

namespace parallax {

// What the report shows. Everything but the reconstruction is optional; sections without
// their data say so on the page.
struct HtmlReportInputs {
  // Title shown at the top of the page.
  std::string title = "Parallax reconstruction report";
  const Reconstruction* reconstruction = nullptr;
  // Keypoints, putative matches and verified two-view geometries.
  const Database* database = nullptr;
  // Folder holding the images under their names; empty when not available.
  std::filesystem::path image_dir;
  // The contents of summary.json written by `parallax reconstruct` (null when missing).
  nlohmann::json summary;
  std::optional<EvaluationMetrics> evaluation;
};

struct HtmlReportOptions {
  // Longest side in pixels of the embedded (downscaled) images.
  int max_image_size = 720;
  // JPEG quality (0-100) of the embedded images.
  int jpeg_quality = 85;
  // Keypoints drawn per frame at most (evenly subsampled beyond).
  int max_keypoints_drawn = 3000;
  // Correspondence lines drawn for the best pair at most.
  int max_matches_drawn = 250;
  // 3D points embedded at most (evenly subsampled beyond).
  int max_points3D = 300000;
  void Check() const;
};

// The report as one self-contained HTML document: all data, scripts, styles and images
// (base64 JPEG) inline, so it opens offline from a single file.
std::string BuildHtmlReport(const HtmlReportInputs& inputs, const HtmlReportOptions& options = {});

// Writes BuildHtmlReport atomically to `path`.
void WriteHtmlReport(const HtmlReportInputs& inputs, const std::filesystem::path& path,
                     const HtmlReportOptions& options = {});

}  // namespace parallax
