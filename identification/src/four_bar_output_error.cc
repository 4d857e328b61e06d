// The four-bar's output-error fit (identify --method output-error): the crank angle simulated
// over windows of the log, each from its logged angle and rate under the logged torque, against
// the logged angle (the five-bar's windows, add_window_block), and the std from the block
// sandwich over the windows (window_covariance).
#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <cmath>
#include <utility>

#include "covariance.h"
#include "four_bar_fit.h"
#include "mechanism_stages.h"
#include "method.h"

namespace fivebar::identification::four_bar {

namespace {

/// The windows as residual blocks on f->x; the residual counts of each, in order.
std::vector<int> add_windows(FourBarFit* f, IdentifyResult* out, ceres::Problem* problem) {
  const IdentifyOptions& opt = *f->opt;
  const TorqueLog& log = f->cond.log;
  const sim::Options so = stages::window_sim_options(opt.sim_rtol);
  std::vector<int> sizes;
  for (auto [i0, i1] : stages::make_windows(log, f->first, f->last, out->window_s)) {
    sim::Initial initial;
    initial.theta1 = log.theta1[i0];
    initial.omega1 = f->w[i0];
    stages::WindowSimulation run =
        [scene = f->scene, layout = f->layout,
         loads = logged_loads(log, f->loads, log.t[i0], f->scene.actuators.offset[0]),
         initial](const double* x, const sim::Options& o) {
          FourBarParams p = scene;
          layout.apply(x, &p.friction);
          return sim::simulate(p, loads, initial, o);
        };
    sizes.push_back(stages::add_window_block(log, 1, std::move(run), i0, i1, so, opt.relative_step,
                                             stages::make_loss(opt.loss, f->loss_scale), &f->x,
                                             problem));
    out->residuals += sizes.back();
  }
  return sizes;
}

/// The output-error solver settings: the four-bar's with output error's tolerances (the method
/// strategy's: its simulated residual carries the integrator's noise).
ceres::Solver::Options output_error_options(const FourBarFit& f) {
  ceres::Solver::Options so = solver_options(f);
  stages::method_strategy(Method::kOutputError).set_tolerances(&so);
  return so;
}

/// The residuals, their Jacobian's singular values (columns scaled to 1) and the window
/// sandwich at the fit, or with `errors_in_variables` off the residual variance's covariance
/// (out->covariance NaN where it cannot be formed).
void window_analysis(const std::vector<int>& sizes, int P, bool errors_in_variables,
                     ceres::Problem* problem, IdentifyResult* out) {
  out->covariance = Eigen::MatrixXd::Constant(P, P, kNaN);
  std::vector<double> r;
  ceres::CRSMatrix crs;
  if (!stages::raw_residuals(problem, &r, &crs)) return;
  const Eigen::MatrixXd J = stages::dense(crs, P);
  const int m = static_cast<int>(r.size());
  out->rms_angle_residual[0] = rms(r);
  out->residual_sigma = std::sqrt(rms(r) * rms(r) * m / std::max(1, m - P));
  scaled_singular_values(J, out);
  if (!out->converged) return;
  if (!errors_in_variables) {  // --classical-std: the residual variance, the five-bar's warning
    const Eigen::MatrixXd H = J.transpose() * J;
    out->covariance =
        out->residual_sigma * out->residual_sigma * H.ldlt().solve(Eigen::MatrixXd::Identity(P, P));
    out->std_method = "residual-variance";
    out->warnings.push_back(stages::kIndependentWindowResiduals);
    return;
  }
  const Eigen::MatrixXd C = stages::window_covariance(sizes, J, r, out);
  if (C.size() > 0) out->covariance = C;
}

}  // namespace

bool output_error_fit(FourBarFit* f, IdentifyResult* out) {
  const IdentifyOptions& opt = *f->opt;
  if (opt.loss != Loss::kNone) {
    f->loss_scale = opt.loss_scale > 0 ? opt.loss_scale : stages::kOutputErrorLossScale;
    out->loss_scale = f->loss_scale;
  }
  ceres::Problem problem;
  const std::vector<int> sizes = add_windows(f, out, &problem);
  if (sizes.empty()) {
    out->status = Status::Error(StatusCode::kInvalidInput, "no output-error window in the log");
    return false;
  }
  for (int i = 0; i < f->layout.size(); ++i) {
    problem.SetParameterLowerBound(f->x.data(), i, f->layout.lower_bound(i));
  }
  std::vector<double> r;
  if (!stages::raw_residuals(&problem, &r)) {
    out->status =
        Status::Error(StatusCode::kSolverFailed,
                      "the four-bar's simulation over a window fails at the start values");
    return false;
  }
  ceres::Solver::Summary summary;
  ceres::Solve(output_error_options(*f), &problem, &summary);
  if (!record_solve(summary, 1.0, out)) return false;
  window_analysis(sizes, f->layout.size(), opt.errors_in_variables, &problem, out);
  return true;
}

}  // namespace fivebar::identification::four_bar
