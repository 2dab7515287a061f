#pragma once

#include <filesystem>
#include <string>

#include "parallax/export/model_exports.h"

namespace parallax {

// `parallax export --format F`: nerfstudio (transforms.json and sparse_pc.ply beside it), ply
// (points and camera frustums), bundler (bundle.out and list.txt beside it) or nvm. Throws
// InputError for another name. The file's folder is created when missing.
void ExportModel(const Reconstruction& model, const std::string& format,
                 const std::filesystem::path& path, const NerfstudioExportOptions& nerfstudio = {});

}  // namespace parallax
