#pragma once

#include <filesystem>
#include <iosfwd>

#include "parallax/scene/reconstruction.h"

namespace parallax {

// COLMAP's model formats: cameras.txt/images.txt/points3D.txt and the .bin twins, byte
// compatible with COLMAP 3.8, and COLMAP 4's rigs and frames beside them (one rig per camera,
// one frame per registered image; read models' rigs and frames are not used yet). Stream functions
// for in-memory round trips; path functions write atomically (temp file + rename). Readers throw
// InputError "<file>:<line>: <reason>" on malformed input, including dangling ids (an image's
// camera or a track's image missing).

void WriteCamerasText(const Reconstruction& reconstruction, std::ostream& stream);
void WriteImagesText(const Reconstruction& reconstruction, std::ostream& stream);
void WritePoints3DText(const Reconstruction& reconstruction, std::ostream& stream);
void WriteCamerasBinary(const Reconstruction& reconstruction, std::ostream& stream);
void WriteImagesBinary(const Reconstruction& reconstruction, std::ostream& stream);
void WritePoints3DBinary(const Reconstruction& reconstruction, std::ostream& stream);
void WriteRigsText(const Reconstruction& reconstruction, std::ostream& stream);
void WriteFramesText(const Reconstruction& reconstruction, std::ostream& stream);
void WriteRigsBinary(const Reconstruction& reconstruction, std::ostream& stream);
void WriteFramesBinary(const Reconstruction& reconstruction, std::ostream& stream);

// `source` names the stream in error messages.
void ReadCamerasText(std::istream& stream, const std::string& source,
                     Reconstruction* reconstruction);
void ReadImagesText(std::istream& stream, const std::string& source,
                    Reconstruction* reconstruction);
void ReadPoints3DText(std::istream& stream, const std::string& source,
                      Reconstruction* reconstruction);
void ReadCamerasBinary(std::istream& stream, const std::string& source,
                       Reconstruction* reconstruction);
void ReadImagesBinary(std::istream& stream, const std::string& source,
                      Reconstruction* reconstruction);
void ReadPoints3DBinary(std::istream& stream, const std::string& source,
                        Reconstruction* reconstruction);

// Writes the five .txt files or the five .bin files into `dir` (created if missing).
void WriteReconstructionText(const Reconstruction& reconstruction,
                             const std::filesystem::path& dir);
void WriteReconstructionBinary(const Reconstruction& reconstruction,
                               const std::filesystem::path& dir);
// Whether `dir` holds a model (cameras.bin or cameras.txt), without reading it.
bool HasColmapModel(const std::filesystem::path& dir);

// Reads a model folder, binary if cameras.bin exists, else text.
Reconstruction ReadReconstruction(const std::filesystem::path& dir);

// Coloured point cloud as binary little-endian PLY (x, y, z float; red, green, blue uchar).
void WritePointsPly(const Reconstruction& reconstruction, const std::filesystem::path& path);

}  // namespace parallax
