#include "parallax/estimators/cost_functions/reprojection_error.h"

namespace parallax {

ceres::CostFunction* CreateReprojectionErrorCostFunction(CameraModelId model_id,
                                                         const Eigen::Vector2d& point2D) {
  return VisitCameraModel(model_id, [&]<typename Model>() -> ceres::CostFunction* {
    return ReprojectionErrorCostFunction<Model>::Create(point2D);
  });
}

}  // namespace parallax
