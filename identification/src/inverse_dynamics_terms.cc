// The inverse-dynamics residual blocks of identify's problems (inverse_dynamics_terms.h): their
// Jet instantiations, one per parameter count, compiled in this unit.
#include "inverse_dynamics_terms.h"

#include "fallback_cost.h"

namespace fivebar::identification::detail {

ceres::LossFunction* make_loss(Loss loss, double scale) {
  switch (loss) {
    case Loss::kNone:
      return nullptr;
    case Loss::kHuber:
      return new ceres::HuberLoss(scale);
    case Loss::kCauchy:
      return new ceres::CauchyLoss(scale);
  }
  return nullptr;
}

template <int P>
void add_inverse_dynamics_terms(const Params<double>& scene, const ParameterLayout& layout,
                                const std::vector<Sample>& samples, const EvalOptions& eval,
                                Loss loss, double loss_scale, double* x, ceres::Problem* problem) {
  for (const Sample& s : samples) {
    SampleStructure st;
    ceres::CostFunction* cost = nullptr;
    if (sample_structure(scene, s, eval, &st)) {
      cost = new ceres::AutoDiffCostFunction<StructuredResidual, 2, P>(
          new StructuredResidual(scene, layout, st, s, eval));
    } else {
      cost = new FallbackCost<P>(InverseDynamicsResidual(scene, layout, s, eval));
    }
    problem->AddResidualBlock(cost, make_loss(loss, loss_scale), x);
  }
}

// the counts of with_size (a count missing here fails to link)
#define FIVEBAR_TERMS(P)                                                                        \
  template void add_inverse_dynamics_terms<P>(const Params<double>&, const ParameterLayout&,    \
                                              const std::vector<Sample>&, const EvalOptions&,   \
                                              Loss, double, double*, ceres::Problem*);
FIVEBAR_TERMS(2)
FIVEBAR_TERMS(4)
FIVEBAR_TERMS(10)
FIVEBAR_TERMS(20)
FIVEBAR_TERMS(18)
FIVEBAR_TERMS(26)
FIVEBAR_TERMS(36)
FIVEBAR_TERMS(8)
FIVEBAR_TERMS(16)
FIVEBAR_TERMS(24)
FIVEBAR_TERMS(32)
#undef FIVEBAR_TERMS

}  // namespace fivebar::identification::detail
