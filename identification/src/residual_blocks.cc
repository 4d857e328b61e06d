// The residual blocks of the two methods: the inverse-dynamics blocks of the samples (one
// place chooses the compiled cost for the parameter count) and the output-error windows.
#include "fallback_cost.h"
#include "identify_stages.h"

namespace fivebar::identification::stages {

double interp(const std::vector<double>& ts, const std::vector<double>& y, double t) {
  if (t <= ts.front()) return y.front();
  if (t >= ts.back()) return y.back();
  const size_t i = std::upper_bound(ts.begin(), ts.end(), t) - ts.begin();
  const double s = (t - ts[i - 1]) / (ts[i] - ts[i - 1]);
  return y[i - 1] + s * (y[i] - y[i - 1]);
}

namespace {

ceres::LossFunction* robust_loss(Loss loss, double scale) {
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

}  // namespace

ceres::LossFunction* make_loss(Loss loss, double scale, double weight) {
  ceres::LossFunction* robust = robust_loss(loss, scale);
  if (weight == 1) return robust;
  return new ceres::ScaledLoss(robust, weight, ceres::TAKE_OWNERSHIP);
}

namespace {

/// A sample's structured residual on P parameters, its Jacobian in closed form
/// (StructuredResidual::evaluate). With bounds on the parameters, Ceres's trust-region minimizer
/// evaluates each new point three times: with the gradient in its projected line search, for the
/// cost alone, and with the Jacobian once the step is accepted. The block keeps its last
/// evaluation with the Jacobian and answers a request at the same parameters from it (the
/// residual alone as StructuredResidual evaluates it without derivatives): the same numbers,
/// computed once.
template <int P>
class StructuredCost : public ceres::SizedCostFunction<2, P> {
 public:
  explicit StructuredCost(const StructuredResidual& residual) : residual_(residual) {}
  bool Evaluate(double const* const* x, double* r, double** jacobians) const override {
    double* jac = jacobians != nullptr ? jacobians[0] : nullptr;
    if (!(known_ && std::equal(x[0], x[0] + P, x_.begin()))) {
      if (jac == nullptr) return residual_.evaluate(x[0], r, nullptr);
      known_ = false;
      if (!residual_.evaluate(x[0], r_jacobian_.data(), jacobian_.data(), r_.data())) return false;
      std::copy(x[0], x[0] + P, x_.begin());
      known_ = true;
    }
    std::copy(jac == nullptr ? r_.begin() : r_jacobian_.begin(),
              jac == nullptr ? r_.end() : r_jacobian_.end(), r);
    if (jac != nullptr) std::copy(jacobian_.begin(), jacobian_.end(), jac);
    return true;
  }

 private:
  StructuredResidual residual_;
  mutable bool known_ = false;
  mutable std::array<double, P> x_{};
  mutable std::array<double, 2> r_{}, r_jacobian_{};  // without and with the derivatives
  mutable std::array<double, 2 * P> jacobian_{};
};

/// The inverse-dynamics residual blocks, one per sample, on P parameters: from the sample's
/// structure (residual.h: a five-number loop, its derivatives in closed form), or the full model
/// where the structure cannot be read off (fallback_cost.h).
template <int P>
ceres::CostFunction* sample_cost(const Params<double>& scene, const ParameterLayout& layout,
                                 const Sample& s, const EvalOptions& eval) {
  SampleStructure st;
  if (sample_structure(scene, s, eval, &st)) {
    return new StructuredCost<P>(StructuredResidual(scene, layout, st, s, eval));
  }
  return new FallbackCost<P>(InverseDynamicsResidual(scene, layout, s, eval));
}

template <int P>
void add_sized_terms(const Params<double>& scene, const ParameterLayout& layout,
                     const std::vector<Sample>& samples, const EvalOptions& eval, Loss loss,
                     double loss_scale, double weight, double* x, ceres::Problem* problem) {
  for (const Sample& s : samples) {
    problem->AddResidualBlock(sample_cost<P>(scene, layout, s, eval),
                              make_loss(loss, loss_scale, weight), x);
  }
}

/// Calls f(std::integral_constant<int, P>) for the parameter counts the layouts give (friction
/// 2, 4, 10, 20, each with or without the 16 inertial parameters, and with the 6 actuator terms
/// except after per-joint Stribeck with inertia); false for another count. The one place that
/// maps the run-time count to a compiled Jet width: one Jet<double, P> pass per evaluation
/// (ceres::DynamicAutoDiffCostFunction's passes of a fixed stride measured slower,
/// docs/dev/figures-build.md).
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

/// Output error over one window [i0, i1]: the driven angles of a run from the logged state at i0
/// under the logged torques (`run`, at the parameters x) minus the logged ones at samples
/// i0+1..i1.
class WindowResidual {
 public:
  WindowResidual(const TorqueLog& log, int dof, WindowSimulation run, int i0, int i1,
                 const sim::Options& sim)
      : log_(log), dof_(dof), run_(std::move(run)), i0_(i0), i1_(i1), sim_(sim) {
    sim_.duration = log.t[i1] - log.t[i0];
    sim_.output_step = sim_.duration / (i1 - i0);
  }
  int residuals() const { return dof_ * (i1_ - i0_); }

  bool operator()(double const* const* x, double* r) const {
    const sim::Result res = run_(x[0], sim_);
    if (!res.status.ok() || res.rows.size() < 2) return false;
    std::vector<double> ts, angle[2];
    for (const sim::Row& row : res.rows) {
      ts.push_back(row.t);
      for (int j = 0; j < dof_; ++j) angle[j].push_back(row.theta[j]);
    }
    const std::vector<double>* logged[2] = {&log_.theta1, &log_.theta2};
    for (int i = i0_ + 1, k = 0; i <= i1_; ++i, ++k) {
      const double tt = log_.t[i] - log_.t[i0_];
      if (tt > ts.back() + 1e-9) return false;
      for (int j = 0; j < dof_; ++j) r[dof_ * k + j] = interp(ts, angle[j], tt) - (*logged[j])[i];
    }
    return true;
  }

 private:
  const TorqueLog& log_;
  int dof_;
  WindowSimulation run_;
  int i0_, i1_;
  sim::Options sim_;
};

}  // namespace

std::vector<std::pair<int, int>> make_windows(const TorqueLog& log, int first, int last,
                                              double window_s) {
  std::vector<std::pair<int, int>> out;
  int i0 = first;
  while (i0 < last) {
    int i1 = i0;
    while (i1 < last && log.t[i1 + 1] - log.t[i0] <= window_s * (1 + 1e-9)) ++i1;
    if (i1 == i0) ++i1;
    // fold a short tail into the previous window
    if (!out.empty() && log.t[last] - log.t[i0] < 0.5 * window_s) {
      out.back().second = last;
      break;
    }
    out.push_back({i0, i1});
    i0 = i1;
  }
  return out;
}

int add_window_block(const TorqueLog& log, int dof, WindowSimulation run, int i0, int i1,
                     const sim::Options& so, double relative_step, ceres::LossFunction* loss,
                     std::vector<double>* x, ceres::Problem* problem) {
  auto* w = new WindowResidual(log, dof, std::move(run), i0, i1, so);
  ceres::NumericDiffOptions nd;
  nd.relative_step_size = relative_step;
  auto* cost = new ceres::DynamicNumericDiffCostFunction<WindowResidual, ceres::CENTRAL>(
      w, ceres::TAKE_OWNERSHIP, nd);
  cost->AddParameterBlock(static_cast<int>(x->size()));
  cost->SetNumResiduals(w->residuals());
  problem->AddResidualBlock(cost, loss, x->data());
  return w->residuals();
}

int add_window_residual(Fit* f, const std::vector<double>& w1, const std::vector<double>& w2,
                        int i0, int i1, const sim::Options& so, ceres::Problem* problem) {
  const TorqueLog& log = f->cond.log;
  const sim::LoadFunction loads = logged_loads(log, f->loads, log.t[i0], f->scene.actuators.offset);
  const sim::Initial initial = {log.theta1[i0], log.theta2[i0], w1[i0], w2[i0]};
  WindowSimulation run = [scene = f->scene, layout = f->layout, loads, initial](
                             const double* x, const sim::Options& o) {
    Params<double> p = scene;
    layout.apply(x, &p);
    return sim::simulate(p, loads, initial, o);
  };
  return add_window_block(log, 2, std::move(run), i0, i1, so, f->opt->relative_step,
                          make_loss(f->opt->loss, f->loss_scale, f->cost_weight), &f->x, problem);
}

sim::Options window_sim_options(double rtol) {
  sim::Options o;
  o.rtol = rtol;
  o.atol = rtol;
  o.method = sim::Method::kCvodeAdams;
  return o;
}

/// The inverse-dynamics residual blocks of `samples` on the parameter block x (P =
/// layout.size(), through with_size); false for a parameter count with no compiled cost.
bool add_inverse_dynamics_terms(const Params<double>& scene, const ParameterLayout& layout,
                                const std::vector<Sample>& samples, const EvalOptions& eval,
                                Loss loss, double loss_scale, double* x, ceres::Problem* problem,
                                double weight) {
  return with_size(layout.size(), [&](auto n) {
    add_sized_terms<decltype(n)::value>(scene, layout, samples, eval, loss, loss_scale, weight, x,
                                        problem);
  });
}

bool sample_residual(const Params<double>& scene, const ParameterLayout& layout, const Sample& s,
                     const EvalOptions& eval, const double* x, Eigen::Vector2d* r,
                     Eigen::MatrixXd* J) {
  const int P = layout.size();
  bool ok = false;
  const bool sized = with_size(P, [&](auto n) {
    const std::unique_ptr<ceres::CostFunction> cost(
        sample_cost<decltype(n)::value>(scene, layout, s, eval));
    Eigen::Matrix<double, 2, Eigen::Dynamic, Eigen::RowMajor> jac(2, P);
    double* jacobians[] = {jac.data()};
    ok = cost->Evaluate(&x, r->data(), jacobians);
    *J = jac;
  });
  return sized && ok && r->allFinite() && J->allFinite();
}

void add_inertial_prior(Fit* f, double* x, ceres::Problem* problem) {
  if (!f->layout.inertia) return;
  problem->AddResidualBlock(
      detail::inertial_prior_cost(f->prior, f->layout.size(), f->layout.inertia_offset(),
                                  &f->prior_scale),
      make_loss(Loss::kNone, 0, f->cost_weight), x);
}

}  // namespace fivebar::identification::stages
