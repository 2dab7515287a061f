// The `colmap` drop-in: COLMAP's options of both generations become the same Parallax flags,
// unknown ones fail naming themselves, meaningless ones warn; and the command lines Gaussian
// splatting's convert.py issues (written down from the script) run end to end, leaving
// COLMAP's file layout.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <string>
#include <vector>

#include "parallax/cli/cli_test_process.h"
#include "parallax/cli/colmap_flags.h"
#include "parallax/geometry/gps.h"
#include "parallax/render/synthetic_scene.h"
#include "parallax/report/ground_truth.h"
#include "parallax/scene/colmap_io.h"
#include "parallax/util/check.h"
#include "parallax/util/test_dir.h"

namespace parallax::cli {
namespace {

namespace fs = std::filesystem;

const std::vector<ColmapOption> kTable = {
    {{"database_path"}, ColmapOption::Kind::kValue, "--database", "", nullptr},
    {{"FeatureExtraction.num_threads", "SiftExtraction.num_threads"},
     ColmapOption::Kind::kValue,
     "--threads",
     "",
     nullptr},
    {{"ImageReader.single_camera"}, ColmapOption::Kind::kFlagIfOn, "--single-camera", "", nullptr},
    {{"SiftMatching.cross_check"}, ColmapOption::Kind::kFlagIfOff, "--no-cross-check", "", nullptr},
    {{"FeatureExtraction.use_gpu", "SiftExtraction.use_gpu"},
     ColmapOption::Kind::kIgnored,
     "",
     "has no meaning here",
     nullptr},
};

TEST(ColmapFlags, BothGenerationsAndBothSpellingsGiveTheSameParallaxFlags) {
  const ColmapTranslation three =
      TranslateColmapArgs("feature_extractor",
                          {"--database_path", "db.db", "--SiftExtraction.num_threads", "2",
                           "--ImageReader.single_camera", "1", "--SiftExtraction.use_gpu", "1"},
                          kTable);
  const ColmapTranslation four =
      TranslateColmapArgs("feature_extractor",
                          {"--database_path=db.db", "--FeatureExtraction.num_threads=2",
                           "--ImageReader.single_camera=true", "--FeatureExtraction.use_gpu=0"},
                          kTable);
  const std::vector<std::string> expected = {"--database", "db.db", "--threads", "2",
                                             "--single-camera"};
  EXPECT_EQ(three.parallax_args, expected);
  EXPECT_EQ(four.parallax_args, expected);
  ASSERT_EQ(three.warnings.size(), 1u);
  EXPECT_EQ(three.warnings[0], "--SiftExtraction.use_gpu has no meaning here; ignored");
  EXPECT_FALSE(three.help);
}

TEST(ColmapFlags, BooleansFollowCOLMAPsSpellings) {
  EXPECT_TRUE(ParseColmapBool("x", "TRUE"));
  EXPECT_FALSE(ParseColmapBool("x", "0"));
  EXPECT_THROW(ParseColmapBool("x", "yes"), InputError);
  // A boolean alone is true; cross_check 0 becomes --no-cross-check, 1 nothing.
  EXPECT_EQ(TranslateColmapArgs("m", {"--ImageReader.single_camera"}, kTable).parallax_args,
            std::vector<std::string>{"--single-camera"});
  EXPECT_EQ(TranslateColmapArgs("m", {"--SiftMatching.cross_check", "0"}, kTable).parallax_args,
            std::vector<std::string>{"--no-cross-check"});
  EXPECT_TRUE(
      TranslateColmapArgs("m", {"--SiftMatching.cross_check", "1"}, kTable).parallax_args.empty());
}

TEST(ColmapFlags, AnUnknownOptionFailsNamingIt) {
  try {
    TranslateColmapArgs("feature_extractor", {"--SiftExtraction.no_such_option", "1"}, kTable);
    FAIL() << "no error";
  } catch (const InputError& error) {
    EXPECT_EQ(std::string(error.what()),
              "colmap feature_extractor: unrecognised option '--SiftExtraction.no_such_option'");
  }
  EXPECT_THROW(TranslateColmapArgs("m", {"--database_path"}, kTable), InputError);  // No value.
  EXPECT_THROW(TranslateColmapArgs("m", {"stray"}, kTable), InputError);
  // One option under both its names fails naming both, before the Parallax command sees it.
  try {
    TranslateColmapArgs(
        "m", {"--SiftExtraction.num_threads", "2", "--FeatureExtraction.num_threads", "4"}, kTable);
    FAIL() << "no error";
  } catch (const InputError& error) {
    EXPECT_EQ(std::string(error.what()),
              "colmap m: --SiftExtraction.num_threads and --FeatureExtraction.num_threads set "
              "the same option; give it once");
  }
  // COLMAP's options common to every subcommand are accepted with a warning.
  const ColmapTranslation common = TranslateColmapArgs("m", {"--log_to_stderr", "1"}, kTable);
  EXPECT_TRUE(common.parallax_args.empty());
  EXPECT_EQ(common.warnings.size(), 1u);
}

class ColmapDropInTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (test::ParallaxBinary().empty()) GTEST_SKIP() << "PARALLAX_BINARY not set";
    colmap_ = (fs::path(test::ParallaxBinary()).parent_path() / "colmap").string();
    ASSERT_TRUE(fs::exists(colmap_)) << colmap_;
  }
  test::ProcessResult Colmap(std::vector<std::string> arguments) {
    arguments.insert(arguments.begin(), colmap_);
    test::ChildProcess child(arguments, dir_.path() / "stdout.txt", dir_.path() / "stderr.txt");
    return child.Wait(300);
  }
  // The images in <source>/input, as convert.py expects them; no intrinsics given.
  fs::path RenderSource(int num_views) {
    const fs::path source = dir_.path() / "source";
    test::RenderSyntheticScene(source / "input", num_views, 640, 480, dir_.path());
    for (const char* extra : {"gt", "K.txt", "synth_par.txt"})
      fs::remove_all(source / "input" / extra);
    return source;
  }
  // convert.py's sequence, with the extraction and matching sections of one COLMAP
  // generation.
  void RunConvertSequence(const fs::path& source, const std::string& extraction,
                          const std::string& matching) {
    const std::string db = (source / "distorted" / "database.db").string();
    const std::string input = (source / "input").string();
    const std::string model = (source / "distorted" / "sparse" / "0").string();
    fs::create_directories(source / "distorted" / "sparse");
    test::ProcessResult result =
        Colmap({"feature_extractor", "--database_path", db, "--image_path", input,
                "--ImageReader.single_camera", "1", "--ImageReader.camera_model", "OPENCV",
                "--" + extraction + ".use_gpu", "1"});
    ASSERT_TRUE(result.ExitedWith(0)) << result.err;
    EXPECT_NE(result.err.find("colmap: warning: --" + extraction + ".use_gpu"), std::string::npos);
    result =
        Colmap({"exhaustive_matcher", "--database_path", db, "--" + matching + ".use_gpu", "1"});
    ASSERT_TRUE(result.ExitedWith(0)) << result.err;
    result = Colmap({"mapper", "--database_path", db, "--image_path", input, "--output_path",
                     (source / "distorted" / "sparse").string(),
                     "--Mapper.ba_global_function_tolerance=0.000001"});
    ASSERT_TRUE(result.ExitedWith(0)) << result.err;
    result = Colmap({"model_aligner", "--input_path", model, "--database_path", db,
                     "--alignment_max_error", "0.1", "--alignment_type", "plane", "--output_path",
                     model});
    ASSERT_TRUE(result.ExitedWith(0)) << result.err;
    result = Colmap({"image_undistorter", "--image_path", input, "--input_path",
                     (source / "distorted" / "sparse" / "0").string(), "--output_path",
                     source.string(), "--output_type", "COLMAP"});
    ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  }
  void ExpectColmapLayout(const fs::path& source, size_t num_views) {
    // The mapper's models as COLMAP writes them: <output_path>/<k>/*.bin, nothing else.
    const fs::path model = source / "distorted" / "sparse" / "0";
    for (const char* file : {"cameras.bin", "images.bin", "points3D.bin"}) {
      EXPECT_TRUE(fs::exists(model / file)) << file;
    }
    EXPECT_FALSE(fs::exists(model / "images.txt"));
    for (const fs::directory_entry& entry :
         fs::directory_iterator(source / "distorted" / "sparse")) {
      EXPECT_TRUE(entry.is_directory() && entry.path().filename().string()[0] != '.')
          << entry.path();
    }
    const Reconstruction reconstruction = ReadReconstruction(model);
    EXPECT_EQ(reconstruction.NumRegImages(), num_views);
    // Aligned to its principal plane: the points around the origin, the cameras above.
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (const auto& [point3D_id, point] : reconstruction.Points3D()) {
      centroid += point.xyz / static_cast<double>(reconstruction.NumPoints3D());
    }
    EXPECT_LT(centroid.norm(), 1e-6);
    for (const image_t image_id : reconstruction.RegImageIds()) {
      EXPECT_GT(reconstruction.GetImage(image_id).ProjectionCenter().z(), 0.0) << image_id;
    }
    // The undistorted workspace.
    EXPECT_TRUE(fs::exists(source / "sparse" / "cameras.bin"));
    EXPECT_TRUE(fs::exists(source / "stereo" / "patch-match.cfg"));
    size_t num_images = 0;
    for ([[maybe_unused]] const auto& entry : fs::directory_iterator(source / "images"))
      ++num_images;
    EXPECT_EQ(num_images, num_views);
  }

  test::ScopedTestDir dir_{"parallax_colmap_compat_test"};
  std::string colmap_;
};

TEST_F(ColmapDropInTest, GaussianSplattingsConvertSequenceWithCOLMAP3Flags) {
  const fs::path source = RenderSource(24);
  RunConvertSequence(source, "SiftExtraction", "SiftMatching");
  ExpectColmapLayout(source, 24);
}

TEST_F(ColmapDropInTest, GaussianSplattingsConvertSequenceWithCOLMAP4Flags) {
  const fs::path source = RenderSource(24);
  RunConvertSequence(source, "FeatureExtraction", "FeatureMatching");
  ExpectColmapLayout(source, 24);
}

// Retrieval pairs, the hierarchical mapper and the model tools, as scripts for larger sets
// chain them (COLMAP's vocabulary tree file is not Parallax's: warned, not read).
TEST_F(ColmapDropInTest, VocabTreeMatchingHierarchicalMappingAndTheModelTools) {
  const fs::path source = RenderSource(24);
  const std::string db = (source / "database.db").string();
  const std::string input = (source / "input").string();
  test::ProcessResult result = Colmap({"feature_extractor", "--database_path", db, "--image_path",
                                       input, "--ImageReader.single_camera=1"});
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  result =
      Colmap({"vocab_tree_matcher", "--database_path", db, "--VocabTreeMatching.vocab_tree_path",
              "vocab_tree_flickr100K_words32K.bin", "--VocabTreeMatching.num_images", "20"});
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  EXPECT_NE(result.err.find("--VocabTreeMatching.vocab_tree_path is COLMAP's tree format"),
            std::string::npos);
  const fs::path sparse = source / "sparse";
  result = Colmap({"hierarchical_mapper", "--database_path", db, "--image_path", input,
                   "--output_path", sparse.string(), "--leaf_max_num_images", "12"});
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  EXPECT_EQ(ReadReconstruction(sparse / "0").NumRegImages(), 24u);
  result = Colmap({"model_analyzer", "--path", (sparse / "0").string()});
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  EXPECT_NE(result.out.find("images_registered: 24"), std::string::npos) << result.out;
  result = Colmap({"model_converter", "--input_path", (sparse / "0").string(), "--output_path",
                   (source / "text").string(), "--output_type", "TXT"});
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  EXPECT_TRUE(fs::exists(source / "text" / "images.txt"));
}

// instant-ngp's colmap2nerf.py: its extraction options (SIFT variants Parallax warns about),
// guided matching, the mapper, then bundle_adjuster freeing the principal point, and text.
TEST_F(ColmapDropInTest, InstantNgpsColmap2NerfSequence) {
  const fs::path source = RenderSource(16);
  const std::string db = (source / "colmap.db").string();
  const std::string input = (source / "input").string();
  const fs::path sparse = source / "colmap_sparse";
  test::ProcessResult result =
      Colmap({"feature_extractor", "--ImageReader.camera_model", "OPENCV",
              "--ImageReader.camera_params", "", "--SiftExtraction.estimate_affine_shape=true",
              "--SiftExtraction.domain_size_pooling=true", "--ImageReader.single_camera", "1",
              "--database_path", db, "--image_path", input});
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  EXPECT_NE(result.err.find("--SiftExtraction.estimate_affine_shape is a SIFT variant"),
            std::string::npos);
  result =
      Colmap({"exhaustive_matcher", "--SiftMatching.guided_matching=true", "--database_path", db});
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  fs::create_directories(sparse);
  result = Colmap(
      {"mapper", "--database_path", db, "--image_path", input, "--output_path", sparse.string()});
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  const Reconstruction mapped = ReadReconstruction(sparse / "0");
  result = Colmap({"bundle_adjuster", "--input_path", (sparse / "0").string(), "--output_path",
                   (sparse / "0").string(), "--BundleAdjustment.refine_principal_point", "1"});
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  const Reconstruction adjusted = ReadReconstruction(sparse / "0");
  EXPECT_EQ(adjusted.NumRegImages(), 16u);
  EXPECT_EQ(adjusted.NumPoints3D(), mapped.NumPoints3D());
  // The principal point was freed, and stays near the rendered one (the image centre): along
  // one sequence it is weakly observed, so within 2.5 % of the width.
  const Camera& before = mapped.Cameras().begin()->second;
  const Camera& after = adjusted.Cameras().begin()->second;
  EXPECT_NE(after.params[2], before.params[2]);
  EXPECT_NEAR(after.params[2], 320.0, 16.0);
  EXPECT_NEAR(after.params[3], 240.0, 16.0);
  result = Colmap({"model_converter", "--input_path", (sparse / "0").string(), "--output_path",
                   (source / "colmap_text").string(), "--output_type", "TXT"});
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  EXPECT_EQ(ReadReconstruction(source / "colmap_text").NumRegImages(), 16u);
}

// A workspace from automatic_reconstructor, then the tools that start from poses: images
// registered into a model that lacks them, points triangulated into fixed poses, and two
// models merged.
TEST_F(ColmapDropInTest, AutomaticReconstructionAndTheToolsThatStartFromPoses) {
  const fs::path source = RenderSource(16);
  const fs::path workspace = source / "workspace";
  test::ProcessResult result =
      Colmap({"automatic_reconstructor", "--workspace_path", workspace.string(), "--image_path",
              (source / "input").string(), "--single_camera", "1", "--dense", "1"});
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  EXPECT_NE(result.err.find("--dense is not run"), std::string::npos) << result.err;
  const std::string db = (workspace / "database.db").string();
  const Reconstruction full = ReadReconstruction(workspace / "sparse" / "0");
  ASSERT_EQ(full.NumRegImages(), 16u);

  // Three images taken out: image_registrator puts them back, the others stay where they were.
  Reconstruction partial = full;
  const std::vector<image_t> ids = full.RegImageIds();
  for (const image_t image_id : {ids[3], ids[8], ids[12]}) partial.DeRegisterImage(image_id);
  WriteReconstructionBinary(partial, source / "partial");
  result =
      Colmap({"image_registrator", "--database_path", db, "--input_path",
              (source / "partial").string(), "--output_path", (source / "registered").string()});
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  const Reconstruction registered = ReadReconstruction(source / "registered");
  EXPECT_EQ(registered.NumRegImages(), 16u);

  // point_triangulator: the same poses to the bit, points from the database.
  result = Colmap({"point_triangulator", "--database_path", db, "--image_path",
                   (source / "input").string(), "--input_path", (source / "partial").string(),
                   "--output_path", (source / "triangulated").string(), "--clear_points", "1"});
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  const Reconstruction triangulated = ReadReconstruction(source / "triangulated");
  EXPECT_EQ(triangulated.NumRegImages(), 13u);
  EXPECT_GT(triangulated.NumPoints3D(), full.NumPoints3D() / 2);
  for (const image_t image_id : partial.RegImageIds()) {
    const Rigid3d& given = partial.GetImage(image_id).cam_from_world;
    const Rigid3d& kept = triangulated.GetImage(image_id).cam_from_world;
    EXPECT_EQ(kept.translation, given.translation) << image_id;
    EXPECT_EQ(kept.rotation.coeffs(), given.rotation.coeffs()) << image_id;
  }

  // model_merger: the full model joins the partial one's frame; all 16 images.
  result = Colmap({"model_merger", "--input_path1", (source / "partial").string(), "--input_path2",
                   (workspace / "sparse" / "0").string(), "--output_path",
                   (source / "merged").string()});
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  EXPECT_EQ(ReadReconstruction(source / "merged").NumRegImages(), 16u);
  EXPECT_FALSE(fs::exists(source / "merged" / "images.txt"));

  // database_creator: an empty database that feature_extractor then fills.
  const std::string fresh = (source / "fresh.db").string();
  ASSERT_TRUE(Colmap({"database_creator", "--database_path", fresh}).ExitedWith(0));
  EXPECT_TRUE(fs::exists(fresh));
  result = Colmap(
      {"feature_extractor", "--database_path", fresh, "--image_path", (source / "input").string()});
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;

  // matches_importer: only the listed pairs are matched and verified.
  std::vector<std::string> names;
  for (const image_t image_id : ids) names.push_back(full.GetImage(image_id).name);
  std::sort(names.begin(), names.end());
  const fs::path list = source / "pairs.txt";
  {
    std::ofstream stream(list);
    for (size_t i = 0; i + 1 < names.size(); ++i) stream << names[i] << " " << names[i + 1] << "\n";
  }
  result = Colmap({"matches_importer", "--database_path", fresh, "--match_list_path", list.string(),
                   "--match_type", "pairs", "--SiftMatching.use_gpu", "0"});
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  EXPECT_NE(result.out.find("match: 15 pairs"), std::string::npos) << result.out;
  result = Colmap({"matches_importer", "--database_path", fresh, "--match_list_path", list.string(),
                   "--match_type", "raw"});
  EXPECT_TRUE(result.ExitedWith(1));
  EXPECT_NE(result.err.find("--match_type raw is not supported yet"), std::string::npos);
}

// model_aligner on a GPS-tagged drone survey: ENU metres about the mean position, ECEF
// metres, and custom reference positions; each puts the cameras where the truth has them.
TEST_F(ColmapDropInTest, ModelAlignerPutsASurveyInMetres) {
  const fs::path source = dir_.path() / "survey";
  ASSERT_TRUE(test::RunParallax(
                  {"synth", "--output", (source / "input").string(), "--views", "16", "--layout",
                   "aerial", "--width", "480", "--height", "360", "--gps-noise", "1", "-q"},
                  dir_.path(), 300)
                  .ExitedWith(0));
  const GroundTruth truth = ReadMiddleburyGroundTruth(source / "input" / "synth_par.txt");
  std::map<std::string, Eigen::Vector3d> truth_centers;
  Eigen::Vector3d truth_mean = Eigen::Vector3d::Zero();
  for (const GroundTruthImage& view : truth.images) {
    truth_centers[view.name] = view.cam_from_world.Inverse().translation;
    truth_mean += truth_centers[view.name] / static_cast<double>(truth.images.size());
  }
  const fs::path workspace = source / "workspace";
  ASSERT_TRUE(Colmap({"automatic_reconstructor", "--workspace_path", workspace.string(),
                      "--image_path", (source / "input").string()})
                  .ExitedWith(0));
  const std::string model = (workspace / "sparse" / "0").string();
  const std::string db = (workspace / "database.db").string();
  // The largest distance from `expected` over the model's cameras.
  const auto max_center_error = [](const fs::path& aligned_path, const auto& expected) {
    const Reconstruction aligned = ReadReconstruction(aligned_path);
    EXPECT_EQ(aligned.NumRegImages(), 16u) << aligned_path;
    double worst = 0;
    for (const image_t image_id : aligned.RegImageIds()) {
      const Image& image = aligned.GetImage(image_id);
      worst = std::max(worst, (image.ProjectionCenter() - expected(image.name)).norm());
    }
    return worst;
  };

  // ENU: east, north, up metres about the mean GPS position. The GPS has 1 m of noise per
  // axis: 5 m takes in all honest positions (3.4 sigma holds 99 % of a 3-axis normal), where
  // the 5 % of the survey's spread that reference alignments use would take 6 of the 16.
  test::ProcessResult result =
      Colmap({"model_aligner", "--input_path", model, "--output_path", (source / "enu").string(),
              "--alignment_type", "enu", "--database_path", db, "--alignment_max_error", "5"});
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  EXPECT_LT(max_center_error(source / "enu",
                             [&](const std::string& name) {
                               return Eigen::Vector3d(truth_centers.at(name) - truth_mean);
                             }),
            3.0);
  // ECEF: the same cameras, earth-centred.
  result =
      Colmap({"model_aligner", "--input_path", model, "--output_path", (source / "ecef").string(),
              "--alignment_type", "ecef", "--database_path", db, "--alignment_max_error", "5"});
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  const GeodeticPosition origin = SyntheticSurveyOrigin();
  EXPECT_LT(
      max_center_error(source / "ecef",
                       [&](const std::string& name) {
                         return EcefFromGeodetic(GeodeticFromEnu(truth_centers.at(name), origin));
                       }),
      3.0);
  // Custom: exact reference positions, 1 km away.
  const fs::path reference = source / "reference.txt";
  {
    std::ofstream stream(reference);
    stream << std::setprecision(17) << "# image_name X Y Z\n";
    for (const auto& [name, center] : truth_centers) {
      stream << name << " " << center.x() + 1000 << " " << center.y() << " " << center.z() << "\n";
    }
  }
  result =
      Colmap({"model_aligner", "--input_path", model, "--output_path", (source / "custom").string(),
              "--alignment_type", "custom", "--ref_images_path", reference.string()});
  ASSERT_TRUE(result.ExitedWith(0)) << result.err;
  EXPECT_LT(max_center_error(source / "custom",
                             [&](const std::string& name) {
                               return Eigen::Vector3d(truth_centers.at(name) +
                                                      Eigen::Vector3d(1000, 0, 0));
                             }),
            0.5);
  // Without the database, ENU fails in one line.
  result = Colmap({"model_aligner", "--input_path", model, "--output_path", (source / "x").string(),
                   "--alignment_type", "enu"});
  EXPECT_TRUE(result.ExitedWith(1));
  EXPECT_NE(result.err.find("needs --database_path"), std::string::npos) << result.err;
}

TEST_F(ColmapDropInTest, BadOptionsAndCommandsFailInOneLine) {
  test::ProcessResult result = Colmap({"feature_extractor", "--SiftExtraction.bogus", "1"});
  EXPECT_TRUE(result.ExitedWith(1));
  EXPECT_EQ(result.err,
            "error: colmap feature_extractor: unrecognised option '--SiftExtraction.bogus'\n");
  result = Colmap({"no_such_command"});
  EXPECT_TRUE(result.ExitedWith(1));
  EXPECT_NE(result.err.find("unknown command 'no_such_command'"), std::string::npos);
  // An output path that is a file: one line, not a crash.
  const fs::path file = dir_.path() / "a_file";
  std::ofstream(file) << "x";
  const fs::path source = RenderSource(12);
  const std::string db = (source / "database.db").string();
  ASSERT_TRUE(Colmap({"feature_extractor", "--database_path", db, "--image_path",
                      (source / "input").string()})
                  .ExitedWith(0));
  ASSERT_TRUE(Colmap({"exhaustive_matcher", "--database_path", db}).ExitedWith(0));
  result = Colmap({"mapper", "--database_path", db, "--image_path", (source / "input").string(),
                   "--output_path", file.string()});
  EXPECT_TRUE(result.ExitedWith(1)) << result.err;
  EXPECT_NE(result.err.find("error: colmap mapper: "), std::string::npos) << result.err;
  result = Colmap({"image_undistorter", "--output_type", "PMVS"});
  EXPECT_TRUE(result.ExitedWith(1));
  EXPECT_NE(result.err.find("--output_type PMVS is not supported"), std::string::npos);
}

}  // namespace
}  // namespace parallax::cli
