// Internal to identification: the inverse-dynamics residual blocks of identify's problems, at
// the parameter counts the layouts give. Their Jet instantiations (the structured residual at
// each count, the fallback residual through fallback_cost.h) are compiled in
// inverse_dynamics_terms.cc, apart from the rest of identify.cc.
#pragma once

#include <ceres/ceres.h>

#include <type_traits>
#include <vector>

#include "fivebar/identification/identify.h"
#include "fivebar/identification/residual.h"

namespace fivebar::identification::detail {

/// The robust loss of identify's residual blocks at scale `scale` (nullptr for Loss::kNone).
ceres::LossFunction* make_loss(Loss loss, double scale);

/// Calls f(std::integral_constant<int, P>) for the parameter counts the layouts give (friction
/// 2, 4, 10, 20, each with or without the 16 inertial parameters, and with the 6 actuator terms
/// except after per-joint Stribeck with inertia); false for another count.
template <typename F>
bool with_size(int P, F&& f) {
  switch (P) {
    case 2: f(std::integral_constant<int, 2>()); return true;
    case 4: f(std::integral_constant<int, 4>()); return true;
    case 10: f(std::integral_constant<int, 10>()); return true;
    case 20: f(std::integral_constant<int, 20>()); return true;
    case 18: f(std::integral_constant<int, 18>()); return true;
    case 26: f(std::integral_constant<int, 26>()); return true;
    case 36: f(std::integral_constant<int, 36>()); return true;
    // with the 6 actuator terms
    case 8: f(std::integral_constant<int, 8>()); return true;
    case 16: f(std::integral_constant<int, 16>()); return true;
    case 24: f(std::integral_constant<int, 24>()); return true;
    case 32: f(std::integral_constant<int, 32>()); return true;
    default: return false;
  }
}

/// The inverse-dynamics residual blocks, one per sample: from the sample's structure
/// (residual.h: the Jets carry only the P active parameters through a five-number loop), or the
/// full model where the structure cannot be read off. Defined for each count of with_size
/// (inverse_dynamics_terms.cc).
template <int P>
void add_inverse_dynamics_terms(const Params<double>& scene, const ParameterLayout& layout,
                                const std::vector<Sample>& samples, const EvalOptions& eval,
                                Loss loss, double loss_scale, double* x, ceres::Problem* problem);

}  // namespace fivebar::identification::detail
