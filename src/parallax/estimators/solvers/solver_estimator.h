#pragma once

#include <vector>

namespace parallax {

// A stateless solver and its residuals as the estimator RANSAC takes (optim/ransac.h):
// `Solve` returns every model the points give (minimal or least squares), `Residuals` the
// squared residual of every correspondence under a model. Each solver header names its
// estimator as an alias of this, e.g. EssentialMatrixFivePointEstimator.
template <typename X, typename Y, typename M, int MinNumSamples,
          void (*Solve)(const std::vector<X>&, const std::vector<Y>&, std::vector<M>*),
          void (*ComputeResiduals)(const std::vector<X>&, const std::vector<Y>&, const M&,
                                   std::vector<double>*)>
struct SolverEstimator {
  using X_t = X;
  using Y_t = Y;
  using M_t = M;
  static constexpr int kMinNumSamples = MinNumSamples;

  void Estimate(const std::vector<X_t>& x, const std::vector<Y_t>& y,
                std::vector<M_t>* models) const {
    Solve(x, y, models);
  }
  void Residuals(const std::vector<X_t>& x, const std::vector<Y_t>& y, const M_t& model,
                 std::vector<double>* squared_residuals) const {
    ComputeResiduals(x, y, model, squared_residuals);
  }
};

}  // namespace parallax
