// The four-bar's inverse-dynamics residual blocks (mechanism_residual.h): add_mechanism_terms
// and mechanism_drive_torques instantiated for FourBar, in a unit of its own so that its Jet
// instantiation of the four-bar's dynamics (one width, kMechanismStride) and its double one are
// compiled once.
#include "fivebar/model/four_bar.h"
#include "mechanism_residual.h"
#include "mechanism_stages.h"

namespace fivebar::identification::stages {

namespace {

/// The drive torques of an evaluation of M as its torque sensors read them (plus their offsets,
/// ActuatorParams).
template <typename T>
mech::Vec<1, T> measured_torques(const FourBarParamsT<T>& p, const FourBarEvaluationT<T>& ev) {
  return mech::Vec<1, T>(ev.M1 + p.actuators.offset[0]);
}

/// r = tau - the drive torques of mech::inverse<M> at the sample's motion as the sensors read
/// them, the parameters x[0] laid out by `layout` into the scene (its friction; with the inertia
/// group, its links; with the actuator group, its motors' friction and offsets). Coulomb signs
/// are those of the sample's relative rates: data, so r is smooth in x.
template <class M>
class MechanismResidual {
 public:
  MechanismResidual(const typename M::template Params<double>& scene, const ParameterLayout& layout,
                    const MechanismSample<M>& s, const EvalOptions& eval)
      : scene_(scene), layout_(layout), s_(s), eval_(eval) {}

  template <typename T>
  bool operator()(T const* const* x, T* r) const {
    typename M::template Params<T> p = scene_.template cast<T>();
    layout_.apply(x[0], &p);
    typename M::template Evaluation<T> ev;
    const Status st =
        mech::inverse<M, T>(p, s_.loads.template cast<T>(), s_.q.template cast<T>(),
                            s_.v.template cast<T>(), s_.a.template cast<T>(), nullptr, eval_, &ev);
    if (!st.ok()) return false;  // Ceres rejects the step
    const mech::Vec<M::kDof, T> d = measured_torques(p, ev);
    for (int j = 0; j < M::kDof; ++j) r[j] = T(s_.tau[j]) - d[j];
    return true;
  }

 private:
  const typename M::template Params<double>& scene_;
  ParameterLayout layout_;
  MechanismSample<M> s_;
  EvalOptions eval_;
};

}  // namespace

template <class M>
void add_mechanism_terms(const typename M::template Params<double>& scene,
                         const ParameterLayout& layout,
                         const std::vector<MechanismSample<M>>& samples, const EvalOptions& eval,
                         double* x, ceres::Problem* problem, Loss loss, double loss_scale,
                         double weight) {
  for (const MechanismSample<M>& s : samples) {
    auto* cost = new ceres::DynamicAutoDiffCostFunction<MechanismResidual<M>, kMechanismStride>(
        new MechanismResidual<M>(scene, layout, s, eval));
    cost->AddParameterBlock(layout.size());
    cost->SetNumResiduals(M::kDof);
    problem->AddResidualBlock(cost, make_loss(loss, loss_scale, weight), x);
  }
}

template <class M>
bool mechanism_drive_torques(const typename M::template Params<double>& scene,
                             const ParameterLayout& layout, const double* x,
                             const MechanismSample<M>& s, const EvalOptions& eval,
                             mech::Vec<M::kDof, double>* torques, Eigen::MatrixXd* dx) {
  double r[M::kDof];
  if (dx == nullptr) {
    const MechanismResidual<M> residual(scene, layout, s, eval);
    if (!residual(&x, r)) return false;
  } else {
    ceres::DynamicAutoDiffCostFunction<MechanismResidual<M>, kMechanismStride> cost(
        new MechanismResidual<M>(scene, layout, s, eval));
    cost.AddParameterBlock(layout.size());
    cost.SetNumResiduals(M::kDof);
    Eigen::Matrix<double, M::kDof, Eigen::Dynamic, Eigen::RowMajor> jac(M::kDof, layout.size());
    double* jacobians[] = {jac.data()};
    if (!cost.Evaluate(&x, r, jacobians)) return false;
    *dx = -jac;  // r = tau - torques
  }
  for (int j = 0; j < M::kDof; ++j) (*torques)[j] = s.tau[j] - r[j];
  return true;
}

template void add_mechanism_terms<FourBar>(const FourBarParams&, const ParameterLayout&,
                                           const std::vector<MechanismSample<FourBar>>&,
                                           const EvalOptions&, double*, ceres::Problem*, Loss,
                                           double, double);
template bool mechanism_drive_torques<FourBar>(const FourBarParams&, const ParameterLayout&,
                                               const double*, const MechanismSample<FourBar>&,
                                               const EvalOptions&, mech::Vec<1, double>*,
                                               Eigen::MatrixXd*);

}  // namespace fivebar::identification::stages
