#pragma once

#include <ceres/loss_function.h>

#include <memory>

#include "parallax/estimators/bundle_adjustment.h"

namespace parallax {

// Ceres' loss object for a loss type; nullptr means the trivial (squared) loss, which both
// solvers evaluate fastest.
inline std::unique_ptr<ceres::LossFunction> CreateLossFunction(LossFunctionType type,
                                                               double scale) {
  switch (type) {
    case LossFunctionType::kTrivial:
      return nullptr;
    case LossFunctionType::kHuber:
      return std::make_unique<ceres::HuberLoss>(scale);
    case LossFunctionType::kSoftLOne:
      return std::make_unique<ceres::SoftLOneLoss>(scale);
    case LossFunctionType::kCauchy:
      return std::make_unique<ceres::CauchyLoss>(scale);
  }
  return nullptr;
}

}  // namespace parallax
