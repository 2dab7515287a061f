#include "parallax/report/ground_truth.h"

#include <gtest/gtest.h>

#include "parallax/util/eigen_matchers.h"

#include <filesystem>
#include <sstream>

#include "parallax/util/check.h"
#include "parallax/util/file.h"

namespace parallax {
namespace {

using test::EigenMatrixNear;

// Expects an InputError whose message starts with `prefix` and contains `reason`.
template <typename Function>
void ExpectInputError(Function function, const std::string& prefix, const std::string& reason) {
  try {
    function();
    FAIL() << "no InputError";
  } catch (const InputError& error) {
    const std::string message = error.what();
    EXPECT_EQ(message.rfind(prefix, 0), 0u) << message;
    EXPECT_NE(message.find(reason), std::string::npos) << message;
  }
}

// A rotation about z by 90 degrees and its matrix rows, for handcrafted files.
constexpr const char* kRotationRows = "0 -1 0 1 0 0 0 0 1";

TEST(MiddleburyGroundTruth, ParsesWindowsLineEndingsAndTrailingSpaces) {
  std::istringstream stream(
      "2\r\n"
      "a.png 100 0 50 0 110 40 0 0 1 1 0 0 0 1 0 0 0 1 1 2 3 \r\n"
      "b.png 100 0 50 0 110 40 0 0 1 " +
      std::string(kRotationRows) + " -1 0 0.5  \r\n\r\n");
  const GroundTruth truth = ReadMiddleburyGroundTruth(stream, "par.txt");
  ASSERT_EQ(truth.images.size(), 2u);
  EXPECT_EQ(truth.images[0].name, "a.png");
  EXPECT_EQ(truth.images[0].camera.model_id, CameraModelId::kPinhole);
  EXPECT_EQ(truth.images[0].camera.params, (std::vector<double>{100, 110, 50, 40}));
  EXPECT_TRUE(truth.images[0].cam_from_world.translation.isApprox(Eigen::Vector3d(1, 2, 3)));
  const Eigen::Matrix3d R = truth.images[1].cam_from_world.rotation.toRotationMatrix();
  Eigen::Matrix3d expected;
  expected << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  EXPECT_THAT(R, EigenMatrixNear(expected, 1e-12));
  // K [R | t] maps the camera centre to 0.
  const Eigen::Vector3d center = ProjectionCenter(truth.images[1].cam_from_world);
  EXPECT_LT((truth.images[1].cam_from_world * center).norm(), 1e-12);
}

TEST(MiddleburyGroundTruth, RejectsMalformedLines) {
  const std::string good = "a.png 100 0 50 0 110 40 0 0 1 1 0 0 0 1 0 0 0 1 1 2 3\n";
  auto read = [](const std::string& text) {
    return [text] {
      std::istringstream stream(text);
      ReadMiddleburyGroundTruth(stream, "bad_par.txt");
    };
  };
  ExpectInputError(read(""), "bad_par.txt:1: ", "empty");
  ExpectInputError(read("x\n" + good), "bad_par.txt:1: ", "not a finite number");
  ExpectInputError(read("2\n" + good), "bad_par.txt:2: ", "expected 2 views, found 1");
  ExpectInputError(read("1\n" + good + good), "bad_par.txt:3: ", "more views");
  ExpectInputError(read("1\na.png 100 0 50\n"), "bad_par.txt:2: ", "expected 22 fields");
  ExpectInputError(read("1\na.png 100 0 50 0 110 40 0 0 1 1 0 0 0 1 0 0 0 1 1 2 nan\n"),
                   "bad_par.txt:2: ", "not a finite number: 'nan'");
  ExpectInputError(read("1\na.png 100 0 50 0 110 40 0 0 1 2 0 0 0 1 0 0 0 1 1 2 3\n"),
                   "bad_par.txt:2: ", "not a rotation");
  ExpectInputError(read("1\na.png 100 0 50 0 110 40 0 0 1 -1 0 0 0 1 0 0 0 1 1 2 3\n"),
                   "bad_par.txt:2: ", "not a rotation");
  ExpectInputError(read("1\na.png 0 0 50 0 110 40 0 0 1 1 0 0 0 1 0 0 0 1 1 2 3\n"),
                   "bad_par.txt:2: ", "positive focal");
}

TEST(StrechaGroundTruth, ParsesOneCamera) {
  // Camera axes in world: x_cam = -y_world ... given as the columns of R.
  Eigen::Matrix3d world_from_cam;
  world_from_cam << 0, 1, 0, -1, 0, 0, 0, 0, 1;
  const Eigen::Vector3d center(1.5, -2, 0.25);
  std::ostringstream text;
  text << "2000 0 1000 \r\n0 2001 700 \r\n0 0 1 \r\n0 0 0\r\n";
  for (int r = 0; r < 3; ++r) {
    text << world_from_cam(r, 0) << " " << world_from_cam(r, 1) << " " << world_from_cam(r, 2)
         << " \r\n";
  }
  text << center.x() << " " << center.y() << " " << center.z() << " \r\n2000 1400\r\n";
  std::istringstream stream(text.str());
  const GroundTruthImage image = ReadStrechaCamera(stream, "x.jpg.camera", "x.jpg");
  EXPECT_EQ(image.name, "x.jpg");
  EXPECT_EQ(image.camera.width, 2000u);
  EXPECT_EQ(image.camera.height, 1400u);
  EXPECT_EQ(image.camera.params, (std::vector<double>{2000, 2001, 1000, 700}));
  EXPECT_THAT(ProjectionCenter(image.cam_from_world), EigenMatrixNear(center, 1e-12));
  EXPECT_THAT(image.cam_from_world.rotation.toRotationMatrix(),
              EigenMatrixNear(world_from_cam.transpose(), 1e-12));
}

TEST(StrechaGroundTruth, RejectsMalformedFiles) {
  auto read = [](const std::string& text) {
    return [text] {
      std::istringstream stream(text);
      ReadStrechaCamera(stream, "bad.camera", "bad");
    };
  };
  const std::string head = "2000 0 1000\n0 2000 700\n0 0 1\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
  ExpectInputError(read(head), "bad.camera:8: ", "unexpected end of file");
  ExpectInputError(read(head + "1 2\n3 4\n"), "bad.camera:8: ", "expected 3 numbers, found 2");
  ExpectInputError(read(head + "1 2 3\n3 -4\n"), "bad.camera:9: ", "positive integers");
  ExpectInputError(read(head + "1 2 3\n30 40\n1\n"), "bad.camera:10: ", "trailing data");
  ExpectInputError(read("2000 0 1000\n0 2000 700\n0 0 1\n0 0 0\n1 0 0\n1 1 0\n0 0 1\n1 2 3\n3 4\n"),
                   "bad.camera:5: ", "not a rotation");
}

// Regressions from fuzzing (issue 8): numbers too large for the integers they become were
// cast anyway (undefined behaviour: 1e300 views read as 0, a width of 1e300 accepted), and a
// matrix with huge entries gave NaN checks that passed.
TEST(MiddleburyGroundTruth, RejectsHugeCountsAndEntries) {
  std::istringstream huge_count("1e300\na.png 100 0 50 0 110 40 0 0 1 1 0 0 0 1 0 0 0 1 1 2 3\n");
  ExpectInputError([&] { ReadMiddleburyGroundTruth(huge_count, "par.txt"); },
                   "par.txt:1: ", "the number of views 1e300 is too large");
  std::istringstream huge_rotation(
      "1\na.png 100 0 50 0 110 40 0 0 1 1e200 1e200 0 1e200 1e200 0 0 0 1 1 2 3\n");
  ExpectInputError([&] { ReadMiddleburyGroundTruth(huge_rotation, "par.txt"); },
                   "par.txt:2: ", "R is not a rotation matrix");
  std::istringstream mixed_signs(
      "1\na.png 100 0 50 0 110 40 0 0 1 1e300 -1e300 0 1e300 1e300 0 0 0 1 1 2 3\n");
  ExpectInputError([&] { ReadMiddleburyGroundTruth(mixed_signs, "par.txt"); },
                   "par.txt:2: ", "R is not a rotation matrix");
}

TEST(StrechaGroundTruth, RejectsHugeImageSizes) {
  for (const char* size : {"1e300 48", "64 1e19", "2000000 48"}) {
    std::istringstream stream(std::string("300 0 32\n0 300 24\n0 0 1\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
                                          "0 0 -5\n") +
                              size + "\n");
    ExpectInputError([&] { ReadStrechaCamera(stream, "a.camera", "a"); },
                     "a.camera:9: ", "image size must be two positive integers up to 1000000");
  }
}

TEST(GroundTruth, DetectsFormatAndRejectsUnknownFolders) {
  const auto dir = std::filesystem::temp_directory_path() / "parallax_ground_truth_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir / "strecha");
  std::filesystem::create_directories(dir / "empty");
  WriteTextFileAtomically(dir / "strecha" / "b.jpg.camera",
                          "10 0 5\n0 10 5\n0 0 1\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n0 0 0\n10 10\n");
  WriteTextFileAtomically(dir / "strecha" / "a.jpg.camera",
                          "10 0 5\n0 10 5\n0 0 1\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 0 0\n10 10\n");
  WriteTextFileAtomically(dir / "par.txt", "0\n");
  const GroundTruth strecha = ReadGroundTruth(dir / "strecha");
  ASSERT_EQ(strecha.images.size(), 2u);
  EXPECT_EQ(strecha.images[0].name, "a.jpg");
  EXPECT_EQ(strecha.images[1].name, "b.jpg");
  EXPECT_TRUE(ReadGroundTruth(dir / "par.txt").images.empty());
  ExpectInputError([&] { ReadGroundTruth(dir / "empty"); }, (dir / "empty").string(),
                   "not a ground truth");
  ExpectInputError([&] { ReadGroundTruth(dir / "missing"); }, (dir / "missing").string(),
                   "no such");
  std::filesystem::remove_all(dir);
}

TEST(GroundTruth, ReadsTempleRing) {
  const auto path = DataRoot() / "templeRing" / "templeR_par.txt";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " missing";
  const GroundTruth truth = ReadGroundTruth(path);
  ASSERT_EQ(truth.images.size(), 47u);
  EXPECT_EQ(truth.images[0].name, "templeR0001.png");
  EXPECT_NEAR(truth.images[0].camera.FocalLengthX(), 1520.4, 1e-9);
  EXPECT_NEAR(truth.images[0].camera.PrincipalPointY(), 246.87, 1e-9);
  // The cameras sit on a ring about 0.5 m around the temple, whose bounding box centre is
  // given in the data set's README.txt; each looks towards it.
  const Eigen::Vector3d temple(0.0277525, 0.0418135, -0.0546675);
  for (const GroundTruthImage& image : truth.images) {
    const Eigen::Vector3d in_cam = image.cam_from_world * temple;
    EXPECT_GT(in_cam.z(), 0.3) << image.name;
    EXPECT_LT(in_cam.z(), 0.8) << image.name;
    const Eigen::Vector2d pixel = image.camera.ImgFromCam(in_cam);
    EXPECT_GT(pixel.x(), 0);
    EXPECT_LT(pixel.x(), 640);
    EXPECT_GT(pixel.y(), 0);
    EXPECT_LT(pixel.y(), 480);
  }
}

TEST(GroundTruth, ReadsFountain) {
  const auto dir = DataRoot() / "fountain-P11" / "gt";
  if (!std::filesystem::exists(dir)) GTEST_SKIP() << dir << " missing";
  const GroundTruth truth = ReadGroundTruth(dir);
  ASSERT_EQ(truth.images.size(), 11u);
  EXPECT_EQ(truth.images[0].name, "0000.jpg");
  EXPECT_EQ(truth.images[10].name, "0010.jpg");
  EXPECT_EQ(truth.images[0].camera.width, 3072u);
  EXPECT_NEAR(truth.images[0].camera.FocalLengthX(), 2759.48, 1e-9);
  EXPECT_LT((ProjectionCenter(truth.images[0].cam_from_world) -
             Eigen::Vector3d(-7.28137, -7.57667, 0.204446))
                .norm(),
            1e-9);
  // Neighbouring views are a few metres apart at most and look roughly the same way.
  for (size_t i = 1; i < truth.images.size(); ++i) {
    const double baseline = (ProjectionCenter(truth.images[i].cam_from_world) -
                             ProjectionCenter(truth.images[i - 1].cam_from_world))
                                .norm();
    EXPECT_GT(baseline, 0.1);
    EXPECT_LT(baseline, 3.0);
    EXPECT_LT(RotationAngleDegrees(truth.images[i].cam_from_world.rotation,
                                   truth.images[i - 1].cam_from_world.rotation),
              30.0);
  }
}

}  // namespace
}  // namespace parallax
