// The cost function of identify's fallback residual (InverseDynamicsResidual, for the samples
// whose structure cannot be read off), differentiated through the Jet widths jet_dynamics.h
// compiles.
#pragma once

#include <ceres/ceres.h>

#include <algorithm>
#include <array>

#include "fivebar/identification/residual.h"
#include "jet_dynamics.h"

namespace fivebar::identification {

/// InverseDynamicsResidual's cost function on P parameters, differentiated with a Jet width that
/// jet_dynamics.h compiles, W = compiled_jet_width(P): for W > P the derivative parts past P stay
/// zero, for W < P the Jacobian takes ceil(P / W) passes of W columns. Each column's derivative
/// is the one Jet<double, P> gives; the few samples that take this path need no inverse_dynamics
/// of their own width (~7 s of compilation each).
template <int P>
class FallbackCost final : public ceres::SizedCostFunction<2, P> {
 public:
  explicit FallbackCost(const InverseDynamicsResidual& r) : r_(r) {}

  bool Evaluate(double const* const* x, double* residuals, double** jacobians) const override {
    if (jacobians == nullptr || jacobians[0] == nullptr) return r_(x[0], residuals);
    constexpr int W = compiled_jet_width(P);
    using J = ceres::Jet<double, W>;
    std::array<J, P> xj;
    for (int c0 = 0; c0 < P; c0 += W) {
      for (int i = 0; i < P; ++i) xj[i] = i >= c0 && i < c0 + W ? J(x[0][i], i - c0) : J(x[0][i]);
      std::array<J, 2> rj;
      if (!r_(xj.data(), rj.data())) return false;
      for (int k = 0; k < 2; ++k) {
        residuals[k] = rj[k].a;
        for (int i = c0; i < std::min(P, c0 + W); ++i) jacobians[0][k * P + i] = rj[k].v[i - c0];
      }
    }
    return true;
  }

 private:
  InverseDynamicsResidual r_;
};

}  // namespace fivebar::identification
