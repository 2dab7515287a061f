#include "parallax/scene/colmap_io.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <set>
#include <sstream>
#include <string>

#include "parallax/math/random.h"
#include "parallax/util/check.h"
#include "parallax/util/file.h"

namespace parallax {
namespace {

using ReadFunction = void (*)(std::istream&, const std::string&, Reconstruction*);

// Two cameras, three registered images and one unregistered, points with tracks, colours,
// errors and coordinates that need all 17 significant digits.
Reconstruction MakeReconstruction() {
  Reconstruction reconstruction;
  reconstruction.AddCamera(Camera::Create(1, CameraModelId::kPinhole, 500.125, 640, 480));
  Camera opencv = Camera::Create(7, CameraModelId::kOpenCV, 1.0 / 3.0 * 2000, 1920, 1080);
  opencv.params[4] = -0.1234567890123456789;
  opencv.params[7] = 1e-17;
  reconstruction.AddCamera(opencv);

  for (image_t image_id : {2u, 5u, 9u, 11u}) {
    Image image;
    image.image_id = image_id;
    image.camera_id = image_id == 5 ? 7 : 1;
    image.name =
        image_id == 9 ? "sub dir/image 9.JPG" : "image" + std::to_string(image_id) + ".png";
    image.cam_from_world.rotation = Eigen::Quaterniond(RandomGaussian(0, 1), RandomGaussian(0, 1),
                                                       RandomGaussian(0, 1), RandomGaussian(0, 1))
                                        .normalized();
    image.cam_from_world.translation =
        Eigen::Vector3d(RandomGaussian(0, 3), RandomGaussian(0, 3), 0.1);
    image.points2D.resize(image_id == 11 ? 0 : 30);
    for (Point2D& point2D : image.points2D) {
      point2D.xy = Eigen::Vector2d(RandomUniformReal(0, 640), RandomUniformReal(0, 480));
    }
    reconstruction.AddImage(image);
    if (image_id != 11) reconstruction.RegisterImage(image_id);
  }
  for (point2D_t idx = 0; idx < 20; ++idx) {
    Track track;
    track.AddElement(9, idx);
    track.AddElement(2, 29 - idx);
    if (idx % 3 == 0) track.AddElement(5, idx + 5);
    const point3D_t id = reconstruction.AddPoint3D(
        Eigen::Vector3d(RandomGaussian(0, 10), RandomGaussian(0, 10), RandomGaussian(0, 10)), track,
        Eigen::Matrix<uint8_t, 3, 1>(idx * 12, 255 - idx, idx % 2 ? 0 : 255));
    reconstruction.GetPoint3D(id).error = idx == 4 ? -1.0 : RandomUniformReal(0, 2);
  }
  reconstruction.DeletePoint3D(3);  // Ids need not be contiguous.
  return reconstruction;
}

// Exact equality of everything a model stores (the registered images of `expected`).
void ExpectSameModel(const Reconstruction& expected, const Reconstruction& actual) {
  ASSERT_EQ(expected.NumCameras(), actual.NumCameras());
  for (const auto& [camera_id, camera] : expected.Cameras()) {
    ASSERT_TRUE(actual.ExistsCamera(camera_id));
    const Camera& other = actual.GetCamera(camera_id);
    EXPECT_EQ(other.model_id, camera.model_id);
    EXPECT_EQ(other.width, camera.width);
    EXPECT_EQ(other.height, camera.height);
    EXPECT_EQ(other.params, camera.params);
  }
  ASSERT_EQ(expected.NumRegImages(), actual.NumImages());
  for (const auto& [image_id, image] : expected.Images()) {
    if (!image.registered) continue;
    ASSERT_TRUE(actual.ExistsImage(image_id));
    const Image& other = actual.GetImage(image_id);
    EXPECT_TRUE(other.registered);
    EXPECT_EQ(other.camera_id, image.camera_id);
    EXPECT_EQ(other.name, image.name);
    EXPECT_EQ(other.cam_from_world.rotation.coeffs(), image.cam_from_world.rotation.coeffs());
    EXPECT_EQ(other.cam_from_world.translation, image.cam_from_world.translation);
    EXPECT_EQ(other.num_points3D, image.num_points3D);
    ASSERT_EQ(other.points2D.size(), image.points2D.size());
    for (size_t idx = 0; idx < image.points2D.size(); ++idx) {
      EXPECT_EQ(other.points2D[idx].xy, image.points2D[idx].xy);
      EXPECT_EQ(other.points2D[idx].point3D_id, image.points2D[idx].point3D_id);
    }
  }
  ASSERT_EQ(expected.NumPoints3D(), actual.NumPoints3D());
  for (const auto& [point3D_id, point] : expected.Points3D()) {
    ASSERT_TRUE(actual.ExistsPoint3D(point3D_id));
    const Point3D& other = actual.GetPoint3D(point3D_id);
    EXPECT_EQ(other.xyz, point.xyz);
    EXPECT_EQ(other.color, point.color);
    EXPECT_EQ(other.error, point.error);
    EXPECT_EQ(other.track.elements, point.track.elements);
  }
}

struct Model {
  std::string cameras, images, points3D;
};

Model WriteText(const Reconstruction& reconstruction) {
  std::ostringstream cameras, images, points3D;
  WriteCamerasText(reconstruction, cameras);
  WriteImagesText(reconstruction, images);
  WritePoints3DText(reconstruction, points3D);
  return {cameras.str(), images.str(), points3D.str()};
}

Model WriteBinary(const Reconstruction& reconstruction) {
  std::ostringstream cameras, images, points3D;
  WriteCamerasBinary(reconstruction, cameras);
  WriteImagesBinary(reconstruction, images);
  WritePoints3DBinary(reconstruction, points3D);
  return {cameras.str(), images.str(), points3D.str()};
}

Reconstruction ReadModel(const Model& model, bool binary) {
  Reconstruction reconstruction;
  std::istringstream cameras(model.cameras), images(model.images), points3D(model.points3D);
  if (binary) {
    ReadCamerasBinary(cameras, "cameras.bin", &reconstruction);
    ReadImagesBinary(images, "images.bin", &reconstruction);
    ReadPoints3DBinary(points3D, "points3D.bin", &reconstruction);
  } else {
    ReadCamerasText(cameras, "cameras.txt", &reconstruction);
    ReadImagesText(images, "images.txt", &reconstruction);
    ReadPoints3DText(points3D, "points3D.txt", &reconstruction);
  }
  return reconstruction;
}

// Runs `read` and expects an InputError whose message starts with "<source>:" and contains
// `reason`.
void ExpectInputError(const std::function<void()>& read, const std::string& source,
                      const std::string& reason) {
  try {
    read();
    ADD_FAILURE() << "no InputError for: " << reason;
  } catch (const InputError& error) {
    const std::string message = error.what();
    EXPECT_EQ(message.rfind(source + ":", 0), 0u) << message;
    EXPECT_NE(message.find(reason), std::string::npos) << message;
  }
}

class TempDir {
 public:
  TempDir() {
    path_ = std::filesystem::temp_directory_path() /
            ("parallax_colmap_io_test_" + std::to_string(getpid()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// Files COLMAP 4.2 wrote with one camera of each of its 18 models (testdata/.../README.md):
// its model ids, names and parameter counts are Parallax's, and Parallax writes the binary
// file back byte for byte.
TEST(ColmapIo, ReadsEveryCameraModelColmap42Writes) {
  const std::filesystem::path dir = std::filesystem::path(PARALLAX_SOURCE_DIR) /
                                    "src/parallax/scene/testdata/colmap42_camera_models";
  std::ifstream binary_file(dir / "cameras.bin", std::ios::binary);
  std::ifstream text_file(dir / "cameras.txt");
  ASSERT_TRUE(binary_file && text_file);
  const std::string binary_bytes((std::istreambuf_iterator<char>(binary_file)),
                                 std::istreambuf_iterator<char>());
  Reconstruction from_binary, from_text;
  std::istringstream binary_stream(binary_bytes);
  ReadCamerasBinary(binary_stream, "cameras.bin", &from_binary);
  ReadCamerasText(text_file, "cameras.txt", &from_text);
  ASSERT_EQ(from_binary.NumCameras(), 18u);
  ASSERT_EQ(from_text.NumCameras(), 18u);
  std::set<CameraModelId> models;
  for (const auto& [camera_id, camera] : from_binary.Cameras()) {
    const Camera& text_camera = from_text.GetCamera(camera_id);
    SCOPED_TRACE(text_camera.ModelName());
    // The binary file holds COLMAP's numeric id, the text file its name.
    EXPECT_EQ(camera.model_id, text_camera.model_id);
    EXPECT_EQ(camera.params, text_camera.params);
    EXPECT_EQ(static_cast<int>(camera.params.size()), CameraModelNumParams(camera.model_id));
    EXPECT_TRUE(camera.VerifyParams());
    models.insert(camera.model_id);
  }
  EXPECT_EQ(models.size(), std::size(kCameraModelIds));
  std::ostringstream written;
  WriteCamerasBinary(from_binary, written);
  EXPECT_TRUE(written.str() == binary_bytes);
  // A camera's parameters in COLMAP's order: OPENCV_FISHEYE is fx, fy, cx, cy, k1..k4.
  const Camera& fisheye = from_text.GetCamera(6);
  EXPECT_EQ(fisheye.model_id, CameraModelId::kOpenCVFisheye);
  EXPECT_EQ(fisheye.params,
            std::vector<double>({300, 310, 320, 240, 0.01, -0.002, 0.0003, -0.0004}));
  EXPECT_EQ(from_text.GetCamera(18).model_id, CameraModelId::kEquirectangular);
  EXPECT_EQ(from_text.GetCamera(18).params, std::vector<double>({2048, 1024}));
}

TEST(ColmapIo, TextRoundTripPreservesEverything) {
  const Reconstruction reconstruction = MakeReconstruction();
  const Model text = WriteText(reconstruction);
  const Reconstruction read = ReadModel(text, false);
  ExpectSameModel(reconstruction, read);
  EXPECT_FALSE(read.ExistsImage(11));  // Only registered images are written.
  // Writing what was read gives the same bytes.
  const Model again = WriteText(read);
  EXPECT_EQ(again.cameras, text.cameras);
  EXPECT_EQ(again.images, text.images);
  EXPECT_EQ(again.points3D, text.points3D);
}

TEST(ColmapIo, BinaryRoundTripPreservesEverything) {
  const Reconstruction reconstruction = MakeReconstruction();
  const Model binary = WriteBinary(reconstruction);
  const Reconstruction read = ReadModel(binary, true);
  ExpectSameModel(reconstruction, read);
  const Model again = WriteBinary(read);
  EXPECT_EQ(again.cameras, binary.cameras);
  EXPECT_EQ(again.images, binary.images);
  EXPECT_EQ(again.points3D, binary.points3D);
}

TEST(ColmapIo, TextLayoutMatchesColmap) {
  Reconstruction reconstruction;
  reconstruction.AddCamera(Camera::Create(1, CameraModelId::kSimpleRadial, 0.1 + 1000, 640, 480));
  Image image;
  image.image_id = 3;
  image.camera_id = 1;
  image.name = "a.jpg";
  image.cam_from_world.translation = Eigen::Vector3d(0.1, -2, 0);
  image.points2D.resize(2);
  image.points2D[0].xy = Eigen::Vector2d(1.5, 2);
  image.points2D[1].xy = Eigen::Vector2d(3, 4.25);
  reconstruction.AddImage(image);
  reconstruction.RegisterImage(3);
  Image image2 = image;
  image2.image_id = 4;
  image2.name = "b.jpg";
  image2.points2D.resize(1);
  reconstruction.AddImage(image2);
  reconstruction.RegisterImage(4);
  Track track;
  track.AddElement(3, 1);
  track.AddElement(4, 0);
  reconstruction.AddPoint3D(Eigen::Vector3d(1, 2, 3), track,
                            Eigen::Matrix<uint8_t, 3, 1>(255, 0, 7));
  reconstruction.GetPoint3D(1).error = 0.5;

  const Model text = WriteText(reconstruction);
  EXPECT_EQ(text.cameras,
            "# Camera list with one line of data per camera:\n"
            "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
            "# Number of cameras: 1\n"
            "1 SIMPLE_RADIAL 640 480 1000.1 320 240 0\n");
  EXPECT_EQ(text.images,
            "# Image list with two lines of data per image:\n"
            "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
            "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
            "# Number of images: 2, mean observations per image: 1\n"
            "3 1 0 0 0 0.10000000000000001 -2 0 1 a.jpg\n"
            "1.5 2 -1 3 4.25 1\n"
            "4 1 0 0 0 0.10000000000000001 -2 0 1 b.jpg\n"
            "1.5 2 1\n");
  EXPECT_EQ(text.points3D,
            "# 3D point list with one line of data per point:\n"
            "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
            "# Number of points: 1, mean track length: 2\n"
            "1 1 2 3 255 0 7 0.5 3 1 4 0\n");
  // 1000.1 is not representable: the text keeps the double it was, bit for bit.
  EXPECT_EQ(ReadModel(text, false).GetCamera(1).params[0], 0.1 + 1000);
}

TEST(ColmapIo, BinaryLayoutMatchesColmap) {
  Reconstruction reconstruction;
  reconstruction.AddCamera(Camera::Create(3, CameraModelId::kPinhole, 100, 64, 48));
  const Model binary = WriteBinary(reconstruction);
  // uint64 count, uint32 id, int32 model, uint64 width, uint64 height, 4 doubles.
  ASSERT_EQ(binary.cameras.size(), 8u + 4 + 4 + 8 + 8 + 4 * 8);
  uint64_t count;
  uint32_t camera_id;
  int32_t model_id;
  uint64_t width;
  double fy;
  std::memcpy(&count, binary.cameras.data(), 8);
  std::memcpy(&camera_id, binary.cameras.data() + 8, 4);
  std::memcpy(&model_id, binary.cameras.data() + 12, 4);
  std::memcpy(&width, binary.cameras.data() + 16, 8);
  std::memcpy(&fy, binary.cameras.data() + 32 + 8, 8);
  EXPECT_EQ(count, 1u);
  EXPECT_EQ(camera_id, 3u);
  EXPECT_EQ(model_id, 1);
  EXPECT_EQ(width, 64u);
  EXPECT_EQ(fy, 100.0);
}

// COLMAP 4's rigs.bin and frames.bin for a model without rigs, in the layout COLMAP 4.2
// writes for one (checked against its model_converter output): a rig per camera, a frame per
// registered image with the image's pose.
TEST(ColmapIo, RigsAndFramesLayoutMatchesColmap4) {
  const Reconstruction reconstruction = MakeReconstruction();
  std::ostringstream rigs, frames;
  WriteRigsBinary(reconstruction, rigs);
  WriteFramesBinary(reconstruction, frames);
  // uint64 count; per rig uint32 id, uint32 sensors, int32 type, uint32 sensor id.
  const std::string rig_bytes = rigs.str();
  ASSERT_EQ(rig_bytes.size(), 8u + 2 * 16);
  uint32_t words[4];
  std::memcpy(words, rig_bytes.data() + 8 + 16, 16);  // The second rig: camera 7.
  EXPECT_EQ(words[0], 7u);
  EXPECT_EQ(words[1], 1u);
  EXPECT_EQ(words[2], 0u);  // CAMERA.
  EXPECT_EQ(words[3], 7u);
  // Per frame: uint32 id, uint32 rig, 7 doubles, uint32 data ids, int32 type, uint32 sensor,
  // uint64 image: 84 bytes; image 11 is not registered.
  const std::string frame_bytes = frames.str();
  ASSERT_EQ(frame_bytes.size(), 8u + 3 * 84);
  const char* second = frame_bytes.data() + 8 + 84;  // Image 5, camera 7.
  uint32_t frame_id, rig_id, num_data, sensor_id;
  double qw, tz;
  uint64_t data_id;
  std::memcpy(&frame_id, second, 4);
  std::memcpy(&rig_id, second + 4, 4);
  std::memcpy(&qw, second + 8, 8);
  std::memcpy(&tz, second + 8 + 6 * 8, 8);
  std::memcpy(&num_data, second + 64, 4);
  std::memcpy(&sensor_id, second + 72, 4);
  std::memcpy(&data_id, second + 76, 8);
  const Image& image = reconstruction.GetImage(5);
  EXPECT_EQ(frame_id, 5u);
  EXPECT_EQ(rig_id, 7u);
  EXPECT_EQ(qw, image.cam_from_world.rotation.w());
  EXPECT_EQ(tz, image.cam_from_world.translation.z());
  EXPECT_EQ(num_data, 1u);
  EXPECT_EQ(sensor_id, 7u);
  EXPECT_EQ(data_id, 5u);
  std::ostringstream frames_text;
  WriteFramesText(reconstruction, frames_text);
  EXPECT_NE(frames_text.str().find("\n5 7 "), std::string::npos);
  EXPECT_NE(frames_text.str().find(" 1 CAMERA 7 5\n"), std::string::npos);
}

TEST(ColmapIo, TextFilesAndBinaryFilesReadTheSame) {
  const Reconstruction reconstruction = MakeReconstruction();
  const TempDir temp;
  WriteReconstructionText(reconstruction, temp.path() / "text");
  WriteReconstructionBinary(reconstruction, temp.path() / "binary");
  for (const char* name : {"cameras.txt", "images.txt", "points3D.txt", "rigs.txt", "frames.txt"}) {
    EXPECT_TRUE(std::filesystem::exists(temp.path() / "text" / name));
  }
  const Reconstruction from_text = ReadReconstruction(temp.path() / "text");
  const Reconstruction from_binary = ReadReconstruction(temp.path() / "binary");
  ExpectSameModel(from_text, from_binary);
  ExpectSameModel(reconstruction, from_binary);
  // No temporary files are left behind.
  size_t num_files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(temp.path() / "binary")) {
    EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos);
    ++num_files;
  }
  EXPECT_EQ(num_files, 5u);  // cameras, images, points3D, rigs, frames.
}

TEST(ColmapIo, ReadReconstructionPrefersBinary) {
  const Reconstruction reconstruction = MakeReconstruction();
  Reconstruction other = reconstruction;
  other.GetPoint3D(1).xyz.x() += 1;
  const TempDir temp;
  WriteReconstructionText(other, temp.path());
  WriteReconstructionBinary(reconstruction, temp.path());
  ExpectSameModel(reconstruction, ReadReconstruction(temp.path()));

  ExpectInputError([&] { ReadReconstruction(temp.path() / "missing"); },
                   (temp.path() / "missing").string(), "model folder does not exist");
  EXPECT_THROW(ReadReconstruction(temp.path() / "missing"), MissingFileError);
  std::filesystem::create_directory(temp.path() / "empty");
  ExpectInputError([&] { ReadReconstruction(temp.path() / "empty"); },
                   (temp.path() / "empty").string(), "no COLMAP model");
  std::filesystem::remove(temp.path() / "images.bin");
  ExpectInputError([&] { ReadReconstruction(temp.path()); }, (temp.path() / "images.bin").string(),
                   "cannot open");
}

TEST(ColmapIo, TextReaderToleratesWindowsLineEndingsAndTrailingSpaces) {
  const Reconstruction reconstruction = MakeReconstruction();
  const Model text = WriteText(reconstruction);
  auto mangle = [](const std::string& content) {
    std::string result;
    for (const char c : content) {
      if (c == '\n')
        result += "  \t\r\n";
      else
        result += c;
    }
    return "\r\n" + result + "\r\n\r\n";
  };
  // Images need their second line even when empty, so only blank lines at the ends are added.
  Model mangled{mangle(text.cameras), text.images, mangle(text.points3D)};
  std::string images;
  for (const char c : text.images) {
    if (c == '\n')
      images += " \r\n";
    else
      images += c;
  }
  mangled.images = images;
  ExpectSameModel(reconstruction, ReadModel(mangled, false));
}

void ReadTextModel(const std::string& cameras, const std::string& images,
                   const std::string& points3D) {
  ReadModel({cameras, images, points3D}, false);
}

TEST(ColmapIo, MalformedTextRaisesInputError) {
  const std::string cameras = "# comment\n1 PINHOLE 640 480 500 500 320 240\n";
  const std::string images = "1 1 0 0 0 0 0 0 1 a.jpg\n10 20 -1 30 40 -1\n";
  const std::string points = "5 1 2 3 10 20 30 0.5 1 0 1 1\n";
  EXPECT_NO_THROW(ReadTextModel(cameras, images, points));
  ExpectInputError([&] { ReadTextModel("1 PINHOLE 640 480 500 5x0 320 240\n", images, points); },
                   "cameras.txt:1", "invalid parameter '5x0'");
  ExpectInputError([&] { ReadTextModel("\n1 PINHOLE 640 480 500 320 240\n", images, points); },
                   "cameras.txt:2", "PINHOLE takes 4 parameters, got 3");
  ExpectInputError([&] { ReadTextModel("1 FISHEYE_42 640 480 500 320 240\n", images, points); },
                   "cameras.txt:1", "unknown camera model 'FISHEYE_42'");
  ExpectInputError([&] { ReadTextModel("1 PINHOLE 640 480 -500 500 320 240\n", images, points); },
                   "cameras.txt:1", "invalid parameters");
  ExpectInputError([&] { ReadTextModel(cameras + cameras, images, points); }, "cameras.txt:4",
                   "duplicate camera id 1");
  ExpectInputError([&] { ReadTextModel(cameras, "1 1 0 0 0 0 0 0 2 a.jpg\n\n", points); },
                   "images.txt:1", "refers to missing camera 2");
  ExpectInputError([&] { ReadTextModel(cameras, "1 1 0 0 0 0 0 0 1\n\n", points); }, "images.txt:1",
                   "missing NAME");
  ExpectInputError([&] { ReadTextModel(cameras, "1 1 0 0 0 0 0 nan 1 a.jpg\n\n", points); },
                   "images.txt:1", "invalid pose");
  ExpectInputError(
      [&] { ReadTextModel(cameras, "1 1 0 0 0 0 0 0 1 a.jpg\n10 20 -1 30\n", points); },
      "images.txt:2", "triplets");
  ExpectInputError([&] { ReadTextModel(cameras, "1 1 0 0 0 0 0 0 1 a.jpg\n10 20 -2\n", points); },
                   "images.txt:2", "invalid POINT3D_ID '-2'");
  ExpectInputError([&] { ReadTextModel(cameras, images, "5 1 2 3 10 20 30 0.5 1 0 2 1\n"); },
                   "points3D.txt:1", "observed in missing image 2");
  ExpectInputError([&] { ReadTextModel(cameras, images, "5 1 2 3 10 20 30 0.5 1 0 1 2\n"); },
                   "points3D.txt:1", "missing keypoint 2 of image 1");
  ExpectInputError([&] { ReadTextModel(cameras, images, points + "6 1 2 3 1 2 3 0 1 1\n"); },
                   "points3D.txt:2", "observes two 3D points");
  ExpectInputError([&] { ReadTextModel(cameras, images, "5 1 2 3 10 20 300 0.5 1 0\n"); },
                   "points3D.txt:1", "out of 0..255");
  ExpectInputError([&] { ReadTextModel(cameras, images, "5 1 2 3 10 20 30 0.5 1 0 1\n"); },
                   "points3D.txt:1", "pairs");
  ExpectInputError([&] { ReadTextModel(cameras, images, "5 1 2\n"); }, "points3D.txt:1",
                   "missing coordinate");
  ExpectInputError([&] { ReadTextModel(cameras, images, "5 1 2 1e999 1 2 3 0\n"); },
                   "points3D.txt:1", "invalid coordinate");
}

// Every proper prefix of a binary file is truncated and must fail cleanly.
TEST(ColmapIo, TruncatedBinaryRaisesInputError) {
  const Reconstruction reconstruction = MakeReconstruction();
  const Model binary = WriteBinary(reconstruction);
  auto check_prefixes = [&](const std::string& content, int which) {
    for (size_t size = 0; size < content.size(); ++size) {
      Model model = binary;
      std::string* file = which == 0   ? &model.cameras
                          : which == 1 ? &model.images
                                       : &model.points3D;
      *file = content.substr(0, size);
      const char* source = which == 0 ? "cameras.bin" : which == 1 ? "images.bin" : "points3D.bin";
      try {
        ReadModel(model, true);
        ADD_FAILURE() << source << " truncated to " << size << " bytes was accepted";
      } catch (const InputError& error) {
        EXPECT_EQ(std::string(error.what()).rfind(source, 0), 0u) << error.what();
      }
    }
  };
  check_prefixes(binary.cameras, 0);
  check_prefixes(binary.images, 1);
  check_prefixes(binary.points3D, 2);
}

// Overwrites `size` bytes at `offset` of a binary file.
template <typename T>
std::string Patch(std::string content, size_t offset, T value) {
  std::memcpy(content.data() + offset, &value, sizeof(T));
  return content;
}

TEST(ColmapIo, CorruptBinaryRaisesInputError) {
  Reconstruction reconstruction;
  reconstruction.AddCamera(Camera::Create(1, CameraModelId::kSimplePinhole, 100, 64, 48));
  Image image;
  image.image_id = 1;
  image.camera_id = 1;
  image.name = "a";
  image.points2D.resize(2);
  reconstruction.AddImage(image);
  image.image_id = 2;
  reconstruction.AddImage(image);
  reconstruction.RegisterImage(1);
  reconstruction.RegisterImage(2);
  Track track;
  track.AddElement(1, 0);
  track.AddElement(2, 1);
  reconstruction.AddPoint3D(Eigen::Vector3d(1, 2, 3), track);
  const Model binary = WriteBinary(reconstruction);
  EXPECT_NO_THROW(ReadModel(binary, true));
  const uint64_t absurd = uint64_t{1} << 62;

  Model model = binary;
  model.cameras = Patch(binary.cameras, 0, absurd);
  ExpectInputError([&] { ReadModel(model, true); }, "cameras.bin", "exceeds");
  model.cameras = Patch(binary.cameras, 12, int32_t{42});
  ExpectInputError([&] { ReadModel(model, true); }, "cameras.bin", "unknown camera model id 42");
  model.cameras = Patch(binary.cameras, 8 + 24, -1.0);
  ExpectInputError([&] { ReadModel(model, true); }, "cameras.bin", "invalid parameters");

  model = binary;
  model.images = Patch(binary.images, 0, absurd);
  ExpectInputError([&] { ReadModel(model, true); }, "images.bin", "exceeds");
  // Image record: id(4) q(32) t(24) camera(4) "a\0"(2) then the keypoint count.
  model.images = Patch(binary.images, 8 + 64 + 2, absurd);
  ExpectInputError([&] { ReadModel(model, true); }, "images.bin", "number of keypoints");
  model.images = Patch(binary.images, 8 + 60, uint32_t{9});
  ExpectInputError([&] { ReadModel(model, true); }, "images.bin", "refers to missing camera 9");

  model = binary;
  model.points3D = Patch(binary.points3D, 0, absurd);
  ExpectInputError([&] { ReadModel(model, true); }, "points3D.bin", "exceeds");
  // Point record: id(8) xyz(24) rgb(3) error(8) then the track length and elements.
  model.points3D = Patch(binary.points3D, 8 + 43, absurd);
  ExpectInputError([&] { ReadModel(model, true); }, "points3D.bin", "track length");
  model.points3D = Patch(binary.points3D, 8 + 51, uint32_t{3});
  ExpectInputError([&] { ReadModel(model, true); }, "points3D.bin", "missing image 3");
  model.points3D = Patch(binary.points3D, 8 + 51 + 4, uint32_t{2});
  ExpectInputError([&] { ReadModel(model, true); }, "points3D.bin", "missing keypoint 2");
}

// A stream that cannot seek: counts cannot be checked up front but must still fail cleanly.
class UnseekableBuffer : public std::stringbuf {
 public:
  explicit UnseekableBuffer(const std::string& content) : std::stringbuf(content) {}

 protected:
  pos_type seekoff(off_type, std::ios::seekdir, std::ios::openmode) override { return -1; }
  pos_type seekpos(pos_type, std::ios::openmode) override { return -1; }
};

TEST(ColmapIo, UnseekableStreamWithAbsurdCount) {
  Reconstruction reconstruction;
  reconstruction.AddCamera(Camera::Create(1, CameraModelId::kSimplePinhole, 100, 64, 48));
  const Model binary = WriteBinary(reconstruction);
  UnseekableBuffer good(binary.cameras);
  std::istream good_stream(&good);
  Reconstruction read;
  ReadCamerasBinary(good_stream, "pipe", &read);
  EXPECT_EQ(read.NumCameras(), 1u);

  UnseekableBuffer buffer(Patch(binary.cameras, 0, uint64_t{1} << 62));
  std::istream stream(&buffer);
  Reconstruction corrupt;
  ExpectInputError([&] { ReadCamerasBinary(stream, "pipe", &corrupt); }, "pipe", "truncated");

  // An absurd keypoint count must not be allocated up front either.
  Image image;
  image.image_id = 1;
  image.camera_id = 1;
  image.name = "a";
  reconstruction.AddImage(image);
  reconstruction.RegisterImage(1);
  UnseekableBuffer images(Patch(WriteBinary(reconstruction).images, 8 + 64 + 2, ~uint64_t{0}));
  std::istream images_stream(&images);
  ExpectInputError([&] { ReadImagesBinary(images_stream, "pipe", &read); }, "pipe", "truncated");
}

TEST(ColmapIo, TextImageWithoutKeypointLineAtEnd) {
  Reconstruction reconstruction;
  std::istringstream cameras("1 SIMPLE_PINHOLE 64 48 100 32 24");
  std::istringstream images("# header\n7 1 0 0 0 1 2 3 1 last image.png");
  ReadCamerasText(cameras, "cameras.txt", &reconstruction);
  ReadImagesText(images, "images.txt", &reconstruction);
  ASSERT_TRUE(reconstruction.ExistsImage(7));
  EXPECT_EQ(reconstruction.GetImage(7).name, "last image.png");
  EXPECT_TRUE(reconstruction.GetImage(7).points2D.empty());
  EXPECT_TRUE(reconstruction.IsImageRegistered(7));
}

TEST(ColmapIo, WritesPly) {
  const Reconstruction reconstruction = MakeReconstruction();
  const TempDir temp;
  const std::filesystem::path path = temp.path() / "points.ply";
  WritePointsPly(reconstruction, path);
  const std::string content = ReadFileToString(path);
  const std::string header =
      "ply\n"
      "format binary_little_endian 1.0\n"
      "element vertex " +
      std::to_string(reconstruction.NumPoints3D()) +
      "\n"
      "property float x\n"
      "property float y\n"
      "property float z\n"
      "property uchar red\n"
      "property uchar green\n"
      "property uchar blue\n"
      "end_header\n";
  ASSERT_EQ(content.size(), header.size() + 15 * reconstruction.NumPoints3D());
  EXPECT_EQ(content.substr(0, header.size()), header);
  const Point3D& first = reconstruction.Points3D().begin()->second;
  float x;
  std::memcpy(&x, content.data() + header.size(), 4);
  EXPECT_EQ(x, static_cast<float>(first.xyz.x()));
  EXPECT_EQ(static_cast<uint8_t>(content[header.size() + 12]), first.color[0]);
  EXPECT_EQ(static_cast<uint8_t>(content[header.size() + 14]), first.color[2]);
}

}  // namespace
}  // namespace parallax
