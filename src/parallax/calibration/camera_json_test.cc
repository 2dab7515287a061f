#include "parallax/calibration/camera_json.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>
#include <string>

#include "parallax/util/check.h"
#include "parallax/util/file.h"

namespace parallax {
namespace {

CalibratedCamera MakeCalibratedCamera() {
  CalibratedCamera calibrated;
  calibrated.camera.camera_id = 1;
  calibrated.camera.model_id = CameraModelId::kOpenCV;
  calibrated.camera.width = 1280;
  calibrated.camera.height = 960;
  // Values with long decimal expansions, to check that they round-trip bit for bit.
  calibrated.camera.params = {1038.7332806358771,     1038.794420560791,    635.68673079235231,
                              477.73667428059141,     0.17660360389525871,  -0.45893586348609971,
                              -0.0012298493521576231, -0.002267930587474935};
  calibrated.camera.has_prior_focal_length = true;
  calibrated.k3 = 0;
  calibrated.rms_error = 0.5827301;
  calibrated.num_images = 12;
  return calibrated;
}

std::filesystem::path TempDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// Expects `body` to throw an InputError whose message starts with `source` and contains
// `fragment`.
template <typename Body>
void ExpectInputError(const Body& body, const std::string& source, const std::string& fragment) {
  try {
    body();
    ADD_FAILURE() << "expected InputError containing '" << fragment << "'";
  } catch (const InputError& error) {
    const std::string message = error.what();
    EXPECT_EQ(message.rfind(source, 0), 0u) << message;
    EXPECT_NE(message.find(fragment), std::string::npos) << message;
  }
}

TEST(CameraJson, ColmapLineUsesShortestExactNumbers) {
  Camera camera;
  camera.camera_id = 1;
  camera.model_id = CameraModelId::kOpenCV;
  camera.width = 1280;
  camera.height = 960;
  camera.params = {1037.5, 1037.25, 640, 480, 0.1, -0.25, 0.001, -0.002};
  EXPECT_EQ(CameraToColmapLine(camera),
            "1 OPENCV 1280 960 1037.5 1037.25 640 480 0.1 -0.25 0.001 -0.002");
  camera.camera_id = kInvalidCameraId;
  EXPECT_EQ(CameraToColmapLine(camera).substr(0, 9), "1 OPENCV ");
}

TEST(CameraJson, RoundTripsExactlyInMemory) {
  const CalibratedCamera calibrated = MakeCalibratedCamera();
  std::ostringstream stream;
  WriteCameraJson(calibrated, stream);
  const std::string text = stream.str();
  // The documented field order, and the COLMAP line for copy and paste.
  EXPECT_LT(text.find("\"model\": \"OPENCV\""), text.find("\"width\": 1280"));
  EXPECT_LT(text.find("\"fx\""), text.find("\"p2\""));
  EXPECT_NE(text.find("\"colmap\": \"" + CameraToColmapLine(calibrated.camera) + "\""),
            std::string::npos);

  const CalibratedCamera read = ParseCameraJson(text, "camera.json");
  EXPECT_EQ(read.camera.model_id, CameraModelId::kOpenCV);
  EXPECT_EQ(read.camera.width, 1280u);
  EXPECT_EQ(read.camera.height, 960u);
  EXPECT_EQ(read.camera.params, calibrated.camera.params);
  EXPECT_TRUE(read.camera.has_prior_focal_length);
  EXPECT_EQ(read.k3, 0);
  EXPECT_EQ(read.rms_error, calibrated.rms_error);
  EXPECT_EQ(read.num_images, 12);
}

TEST(CameraJson, WritesAtomicallyAndReadsCamera) {
  const auto dir = TempDir("parallax_camera_json_test");
  const auto path = dir / "camera.json";
  WriteCameraJson(MakeCalibratedCamera(), path);
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    EXPECT_EQ(entry.path().filename(), "camera.json");
  }
  const Camera camera = ReadCameraJson(path);
  EXPECT_EQ(camera.params, MakeCalibratedCamera().camera.params);
  EXPECT_TRUE(camera.VerifyParams());
  EXPECT_TRUE(camera.has_prior_focal_length);
  std::filesystem::remove_all(dir);
}

TEST(CameraJson, OptionalFieldsDefault) {
  const CalibratedCamera read = ParseCameraJson(
      R"({"model": "OPENCV", "width": 640, "height": 480, "fx": 500, "fy": 501, "cx": 320,
          "cy": 240, "k1": 0, "k2": 0, "p1": 0, "p2": 0, "comment": "hand-written"})",
      "hand.json");
  EXPECT_EQ(read.camera.params, (std::vector<double>{500, 501, 320, 240, 0, 0, 0, 0}));
  EXPECT_EQ(read.k3, 0);
  EXPECT_EQ(read.rms_error, 0);
  EXPECT_EQ(read.num_images, 0);
}

TEST(CameraJson, MalformedInputNamesFileAndField) {
  const std::string source = "/data/cam.json";
  const std::string valid =
      R"({"model": "OPENCV", "width": 640, "height": 480, "fx": 500, "fy": 501, "cx": 320,
          "cy": 240, "k1": 0, "k2": 0, "p1": 0, "p2": 0})";
  EXPECT_NO_THROW(ParseCameraJson(valid, source));
  const auto replaced = [&](const std::string& from, const std::string& to) {
    std::string text = valid;
    text.replace(text.find(from), from.size(), to);
    return text;
  };
  const auto parse = [&](const std::string& text) {
    return [text, source] { ParseCameraJson(text, source); };
  };
  ExpectInputError(parse("{\"model\": "), source, "not valid JSON");
  ExpectInputError(parse(""), source, "not valid JSON");
  ExpectInputError(parse("[1, 2]"), source, "JSON object");
  ExpectInputError(parse(replaced("\"fx\": 500, ", "")), source, "missing field \"fx\"");
  ExpectInputError(parse(replaced("\"p2\": 0", "\"p3\": 0")), source, "missing field \"p2\"");
  ExpectInputError(parse(replaced("\"cy\": 240", "\"cy\": \"240\"")), source,
                   "\"cy\" is not a number");
  ExpectInputError(parse(replaced("\"OPENCV\"", "\"PINHOLE\"")), source, "PINHOLE");
  ExpectInputError(parse(replaced("\"OPENCV\"", "7")), source, "\"model\" is not a string");
  ExpectInputError(parse(replaced("\"width\": 640", "\"width\": 640.5")), source,
                   "\"width\" is not an integer");
  ExpectInputError(parse(replaced("\"height\": 480", "\"height\": -480")), source, "positive");
  ExpectInputError(parse(replaced("\"fy\": 501", "\"fy\": 0")), source, "positive");
  ExpectInputError(parse(replaced("\"p2\": 0", "\"p2\": 0, \"k3\": null")), source,
                   "\"k3\" is not a number");

  const auto dir = TempDir("parallax_camera_json_test2");
  ExpectInputError([&] { ReadCameraJson(dir / "missing.json"); }, (dir / "missing.json").string(),
                   "cannot open");
  WriteTextFileAtomically(dir / "broken.json", "{\"model\": \"OPENCV\",");
  ExpectInputError([&] { ReadCameraJson(dir / "broken.json"); }, (dir / "broken.json").string(),
                   "not valid JSON");
  std::filesystem::remove_all(dir);
}

// Regression (issue 8): a number beyond double threw nlohmann's out_of_range, which is not a
// parse_error, so the message lost the file name.
TEST(CameraJson, NumbersBeyondDoubleAreMalformedJson) {
  const std::string text =
      R"({"model": "OPENCV", "width": 640, "height": 1e400, "fx": 500, "fy": 501, "cx": 320,
          "cy": 240, "k1": 0, "k2": 0, "p1": 0, "p2": 0})";
  ExpectInputError([&] { ParseCameraJson(text, "cam.json"); }, "cam.json", "not valid JSON");
  ExpectInputError([&] { ParseCameraJson("-1e999", "cam.json"); }, "cam.json", "not valid JSON");
}

TEST(CameraJson, K3ShiftIsMeasuredAtTheFarthestCorner) {
  CalibratedCamera calibrated;
  calibrated.camera.model_id = CameraModelId::kOpenCV;
  calibrated.camera.width = 1000;
  calibrated.camera.height = 1000;
  calibrated.camera.params = {1000, 1000, 500, 500, 0, 0, 0, 0};
  calibrated.k3 = 1e-3;
  // Corner at (707.1 px, r^2 = 0.5): 1e-3 * 0.5^3 * 707.1 px.
  EXPECT_NEAR(K3ShiftPixels(calibrated), 1e-3 * 0.125 * std::sqrt(2.0) * 500, 1e-12);
  calibrated.camera.params[2] = 0;  // Principal point at the left edge: farthest corner moves.
  const double dx = 1000, dy = 500, r2 = (dx * dx + dy * dy) / 1e6;
  EXPECT_NEAR(K3ShiftPixels(calibrated), 1e-3 * r2 * r2 * r2 * std::hypot(dx, dy), 1e-12);
}

TEST(CameraJson, RefusesSignificantK3) {
  const auto dir = TempDir("parallax_camera_json_test3");
  const auto path = dir / "camera.json";
  CalibratedCamera calibrated = MakeCalibratedCamera();
  calibrated.k3 = 0.94;  // What OpenCV fits to the checkerboard set with k3 free.
  WriteCameraJson(calibrated, path);
  ExpectInputError([&] { ReadCameraJson(path); }, path.string(), "no k3");
  // The full record still reads, for tools that understand k3.
  EXPECT_EQ(ReadCalibratedCameraJson(path).k3, 0.94);

  calibrated.k3 = 1e-8;  // Far below a hundredth of a pixel.
  WriteCameraJson(calibrated, path);
  EXPECT_NO_THROW(ReadCameraJson(path));
  std::filesystem::remove_all(dir);
}

TEST(CameraJson, WriterRejectsOtherModels) {
  CalibratedCamera calibrated = MakeCalibratedCamera();
  calibrated.camera.model_id = CameraModelId::kPinhole;
  calibrated.camera.params.resize(4);
  std::ostringstream stream;
  EXPECT_THROW(WriteCameraJson(calibrated, stream), CheckError);
}

}  // namespace
}  // namespace parallax
