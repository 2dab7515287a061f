#include "parallax/sfm/mapper_input.h"

#include "parallax/util/check.h"

namespace parallax {

void MapperInputOptions::Check() const { PARALLAX_CHECK_GE(min_num_matches, 0); }

namespace {
bool IsUsableConfig(int config) {
  return config == TwoViewGeometry::kCalibrated || config == TwoViewGeometry::kUncalibrated ||
         config == TwoViewGeometry::kPlanar || config == TwoViewGeometry::kPanoramic ||
         config == TwoViewGeometry::kPlanarOrPanoramic;
}
}  // namespace

void FinalizeMapperInput(const MapperInputOptions& options, MapperInput* input) {
  options.Check();
  for (const auto& [image_id, image] : input->images) {
    input->correspondence_graph.AddImage(image_id, image.points2D.size());
  }
  for (auto it = input->two_view_geometries.begin(); it != input->two_view_geometries.end();) {
    const TwoViewGeometry& geometry = it->second;
    const auto [image_id1, image_id2] = PairIdToImagePair(it->first);
    if (!IsUsableConfig(geometry.config) ||
        static_cast<int>(geometry.inlier_matches.size()) < options.min_num_matches ||
        !input->images.count(image_id1) || !input->images.count(image_id2)) {
      it = input->two_view_geometries.erase(it);
      continue;
    }
    input->correspondence_graph.AddCorrespondences(image_id1, image_id2, geometry.inlier_matches);
    ++it;
  }
  input->correspondence_graph.Finalize();
}

MapperInput LoadMapperInput(const Database& database, const MapperInputOptions& options) {
  MapperInput input;
  for (Camera& camera : database.ReadAllCameras()) {
    const camera_t camera_id = camera.camera_id;
    input.cameras.emplace(camera_id, std::move(camera));
  }
  for (Image& image : database.ReadAllImages()) {
    const FeatureKeypoints keypoints = database.ReadKeypoints(image.image_id);
    image.points2D.resize(keypoints.size());
    for (size_t i = 0; i < keypoints.size(); ++i) {
      image.points2D[i].xy = Eigen::Vector2d(keypoints[i].x, keypoints[i].y);
    }
    image.registered = false;
    const image_t image_id = image.image_id;
    input.images.emplace(image_id, std::move(image));
  }
  for (auto& [pair_id, geometry] : database.ReadTwoViewGeometries()) {
    input.two_view_geometries.emplace(pair_id, std::move(geometry));
  }
  FinalizeMapperInput(options, &input);
  return input;
}

Reconstruction ModelInInputIds(const Reconstruction& model, const MapperInput& input,
                               std::vector<std::string>* missing) {
  std::map<std::string, image_t> input_ids;
  for (const auto& [image_id, image] : input.images) input_ids[image.name] = image_id;
  Reconstruction seed;
  for (const image_t model_id : model.RegImageIds()) {
    const Image& model_image = model.GetImage(model_id);
    const auto found = input_ids.find(model_image.name);
    if (found == input_ids.end()) {
      if (missing != nullptr) missing->push_back(model_image.name);
      continue;
    }
    const Image& input_image = input.images.at(found->second);
    if (!seed.ExistsCamera(input_image.camera_id)) {
      Camera camera = input.cameras.at(input_image.camera_id);
      const Camera& model_camera = model.GetCamera(model_image.camera_id);
      // The model's intrinsics, when its camera is of the same kind (they were refined).
      if (model_camera.model_id == camera.model_id && model_camera.width == camera.width &&
          model_camera.height == camera.height) {
        camera.params = model_camera.params;
      }
      seed.AddCamera(camera);
    }
    Image image;
    image.image_id = input_image.image_id;
    image.camera_id = input_image.camera_id;
    image.name = input_image.name;
    image.cam_from_world = model_image.cam_from_world;
    seed.AddImage(image);
    seed.RegisterImage(image.image_id);
  }
  return seed;
}

}  // namespace parallax
