// The two identification methods as strategies (method.h): inverse dynamics (a torque residual
// per sample) and output error (simulated minus logged angles over short windows).
#include "method.h"

#include "identify_stages.h"

namespace fivebar::identification::stages {

namespace {

/// Torque residuals, one pair per sample of the fit.
class InverseDynamicsMethod final : public MethodStrategy {
 public:
  bool add_residuals(Fit* f, IdentifyResult* out, ceres::Problem* problem) const override {
    if (!add_inverse_dynamics_terms(f->scene, f->layout, f->samples, f->eval, f->opt->loss,
                                    f->loss_scale, f->x.data(), problem, f->cost_weight)) {
      return false;
    }
    add_inertial_prior(f, f->x.data(), problem);
    out->residuals = 2 * out->samples_used;
    return true;
  }

  void set_tolerances(ceres::Solver::Options* so) const override {
    so->function_tolerance = 1e-12;
    so->gradient_tolerance = 1e-14;
    so->parameter_tolerance = 1e-10;
  }

  /// torque_cost_weight: the cost of order one per sample at any scale of the mechanism.
  double cost_weight(const TorqueLog& log) const override { return torque_cost_weight(log); }

  Status first_failure(const Fit& f, const std::vector<double>& x,
                       const std::string& at) const override {
    return first_failing_sample(f, x, at);
  }

  /// kLossScaleHuber or kLossScaleCauchy times a sample's expected residual level at the start
  /// values (the two actuators' noise floors in quadrature: the loss sees the block's norm).
  double default_loss_scale(const Fit& f, IdentifyResult* out) const override {
    double floor[2];
    noise_floor(f, noise_sensitivities(f), floor);
    return loss_scale_from_level(f.opt->loss, std::hypot(floor[0], floor[1]), out);
  }

  /// The residual level at the start (the Jacobian is needed only after the solve).
  void initial_levels(ceres::Problem* problem, IdentifyResult* out) const override {
    std::vector<double> r0;
    raw_residuals(problem, &r0);
    r0.resize(out->residuals);
    rms_pair(r0, out->rms_torque_residual_initial);
  }

  /// Group inertia: the prior's weight is set to the residual's noise level (the torque noise
  /// plus the angle noise through the rates) and, if that differs, the fit is solved again.
  bool refine(Fit* f, ceres::Problem* problem, IdentifyResult* out,
              ceres::Solver::Summary* summary, Analysis* an) const override {
    an->sens = noise_sensitivities(*f);
    if (!f->layout.inertia) return true;
    double floor[2];
    noise_floor(*f, an->sens, floor);
    const double s = std::max(floor[0], floor[1]);
    if (s > 1.2 * f->prior_scale || s < f->prior_scale / 1.2) {
      f->prior_scale = s;
      solve(f, problem, out, summary);
      if (!out->status.ok()) return false;
      an->sens = noise_sensitivities(*f);
    }
    return true;
  }

  void residual_levels(const Fit& f, const Analysis& an, IdentifyResult* out) const override {
    torque_residual_levels(f, an.r, an.sens, out);
  }

  Eigen::MatrixXd errors_in_variables(const Fit& f, const FreeSet& fs, const Analysis& an,
                                      IdentifyResult* out) const override {
    return score_sandwich(f, fs, an, out);
  }

  ModelVerdict check_model(const Fit& f, const Analysis& an, IdentifyResult* out) const override {
    bound_and_misfit_warning(f, an, out);
    return model_check(f, an, out);
  }

  void prediction_levels(const Fit&, IdentifyResult*) const override {}

  bool fits_groups() const override { return true; }
  bool chooses_window() const override { return true; }
  bool excludes_reversals() const override { return true; }
  bool restarts_stribeck() const override { return true; }
  bool profiles_intervals() const override { return true; }
  bool checks_readings() const override { return true; }
};

/// Angle residuals of the fitted scene simulated over windows from the logged states.
class OutputErrorMethod final : public MethodStrategy {
 public:
  /// Windows over the used range (the rate threshold does not apply), differentiated by
  /// central differences of relative step IdentifyOptions::relative_step.
  bool add_residuals(Fit* f, IdentifyResult* out, ceres::Problem* problem) const override {
    const IdentifyOptions& opt = *f->opt;
    const sim::Options so = window_sim_options(opt.sim_rtol);
    for (auto [i0, i1] : make_windows(f->cond.log, f->first, f->last, out->window_s)) {
      const int m = add_window_residual(f, out->omega1, out->omega2, i0, i1, so, problem);
      out->residuals += m;
      f->window_sizes.push_back(m);
    }
    return true;
  }

  /// The simulated residual carries integrator noise (~rtol, a relative cost noise ~1e-4), so
  /// less is asked of it.
  void set_tolerances(ceres::Solver::Options* so) const override {
    so->function_tolerance = 1e-3;
    so->gradient_tolerance = 1e-10;
    so->parameter_tolerance = 1e-7;
  }

  /// 1: the residuals are angles [rad], of the same order at any scale of the mechanism.
  double cost_weight(const TorqueLog&) const override { return 1; }

  Status first_failure(const Fit&, const std::vector<double>&, const std::string&) const override {
    return Status::Ok();
  }

  double default_loss_scale(const Fit&, IdentifyResult*) const override {
    return kOutputErrorLossScale;
  }

  void initial_levels(ceres::Problem*, IdentifyResult*) const override {}

  bool refine(Fit*, ceres::Problem*, IdentifyResult*, ceres::Solver::Summary*,
              Analysis*) const override {
    return true;
  }

  void residual_levels(const Fit& f, const Analysis& an, IdentifyResult* out) const override {
    if (!f.opt->errors_in_variables) out->warnings.push_back(kIndependentWindowResiduals);
    rms_pair(an.r, out->rms_angle_residual);
  }

  Eigen::MatrixXd errors_in_variables(const Fit& f, const FreeSet& fs, const Analysis& an,
                                      IdentifyResult* out) const override {
    return window_covariance(f.window_sizes, fs.J, an.r, out);
  }

  ModelVerdict check_model(const Fit&, const Analysis&, IdentifyResult*) const override {
    return {};
  }

  void prediction_levels(const Fit& f, IdentifyResult* out) const override {
    output_error_levels(f.cond.log, f.first, f.last, out);
    output_error_misfit(out);
  }

  bool fits_groups() const override { return false; }
  bool chooses_window() const override { return false; }
  bool excludes_reversals() const override { return false; }
  bool restarts_stribeck() const override { return false; }
  bool profiles_intervals() const override { return false; }
  bool checks_readings() const override { return false; }
};

}  // namespace

const MethodStrategy& method_strategy(Method method) {
  static const InverseDynamicsMethod inverse_dynamics;
  static const OutputErrorMethod output_error;
  return method == Method::kOutputError ? static_cast<const MethodStrategy&>(output_error)
                                        : inverse_dynamics;
}

}  // namespace fivebar::identification::stages
