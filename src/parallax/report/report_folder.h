#pragma once

#include <filesystem>
#include <string>

namespace parallax {

// Where the report of a finished run takes its inputs from; empty paths take the defaults of
// a `parallax reconstruct` output folder.
struct ReportFolderOptions {
  std::filesystem::path output_dir;  // Holds summary.json, database.db, sparse/; gets report.html.
  std::filesystem::path model_dir;   // Default OUT/sparse/0.
  std::filesystem::path database_path;  // Default OUT/database.db (optional there).
  // Default: the folder summary.json names, else OUT/images when it exists, else none.
  std::filesystem::path image_dir;
  std::filesystem::path ground_truth_path;  // Evaluated against when given.
  std::string title;                        // Default "Parallax report: <folder name>".
};

// Writes OUT/report.html for a finished run (`parallax report`, the Python
// parallax.write_report) and returns its path. Missing optional inputs (summary, database,
// images) leave their sections empty, with a warning; a named input that does not exist is a
// MissingFileError, an output folder without a model an InputError.
std::filesystem::path WriteReportOfOutputFolder(const ReportFolderOptions& options);

}  // namespace parallax
