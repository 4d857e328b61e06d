// The fit stage of identify(): the loss scale, the problem, the solve (with the Stribeck
// restarts), the data residuals and Jacobian at the fit.
#include "identify_stages.h"

namespace fivebar::identification::stages {

namespace {

/// Stribeck law: further start values of the Stribeck velocity [rad/s] (best_stribeck_start)
constexpr double kStribeckStarts[] = {0.05, 0.5, 2.0};

}  // namespace

bool raw_residuals(ceres::Problem* problem, std::vector<double>* r,
                   ceres::CRSMatrix* jac) {
  ceres::Problem::EvaluateOptions eo;
  eo.apply_loss_function = false;
  double cost = 0;
  return problem->Evaluate(eo, &cost, r, nullptr, jac);
}

void rms_pair(const std::vector<double>& r, double* out2) {
  double s[2] = {0, 0};
  for (size_t i = 0; i < r.size(); ++i) s[i % 2] += r[i] * r[i];
  for (int j = 0; j < kActuators; ++j)
    out2[j] = std::sqrt(s[j] / std::max<size_t>(1, r.size() / 2));
}

namespace {

/// Stribeck law, inverse dynamics: the cost has local minima where the Stribeck velocity
/// collapses onto its bound (a peak narrower than the rates of any sample left in the fit, whose
/// static_coulomb is then undetermined). Measured on 500 Hz logs: from the neutral start (0.2
/// rad/s) 3 of 30 fits ended there although a start at the truth reached a lower cost with a
/// determined peak. The fit is solved from the given start and from kStribeckStarts; the end
/// with the least cost is the start of the final solve. f->x is left at that start.
void best_stribeck_start(Fit* f, ceres::Problem* problem) {
  const int g = f->layout.group_of(Coefficient::kStribeckVelocity);
  if (g < 0 || !f->method->restarts_stribeck()) return;
  const ceres::Solver::Options so = solver_options(*f);
  const std::vector<double> x0 = f->x;
  std::vector<double> best = x0;
  double best_cost = std::numeric_limits<double>::infinity();
  const int per = f->layout.per_group();
  for (int k = -1; k < static_cast<int>(std::size(kStribeckStarts)); ++k) {
    std::copy(x0.begin(), x0.end(), f->x.begin());  // the problem holds f->x.data()
    for (int j = 0; k >= 0 && j < per; ++j) {
      const int i = g * per + j;
      f->x[i] = std::max(kStribeckStarts[k], f->layout.lower_bound(i));
    }
    ceres::Solver::Summary summary;
    ceres::Solve(so, problem, &summary);
    if (summary.IsSolutionUsable() && summary.final_cost < best_cost) {
      best_cost = summary.final_cost;
      best = f->x;
    }
  }
  std::copy(best.begin(), best.end(), f->x.begin());
}

}  // namespace

void solve(Fit* f, ceres::Problem* problem, IdentifyResult* out, ceres::Solver::Summary* summary) {
  ceres::Solve(solver_options(*f), problem, summary);
  out->iterations += static_cast<int>(summary->iterations.size());
  out->converged = summary->termination_type == ceres::CONVERGENCE;
  out->solver_message = unweighted_report(*summary, f->cost_weight);
  for (const ceres::IterationSummary& it : summary->iterations)
    out->iteration_costs.push_back(it.cost / f->cost_weight);
  std::vector<double> r;
  const bool evaluates = raw_residuals(problem, &r);
  bool finite = evaluates;
  for (double v : r) finite = finite && std::isfinite(v);
  if (summary->IsSolutionUsable() && finite) return;
  Status st = f->method->first_failure(*f, f->x, "at the solver's last iterate");
  if (st.ok()) {
    st = Status::Error(StatusCode::kSolverFailed,
                       std::string("Ceres: ") +
                           (finite ? summary->message : "residuals not finite at the solution"));
  }
  out->status = st;
}

void noise_floor(const Fit& f, const std::vector<detail::Sensitivity>& sens, double floor[2],
                 double noise[2], double absolute[2]) {
  const TorqueLog& log = f.cond.log;
  Eigen::Vector2d prop = Eigen::Vector2d::Zero();
  for (const detail::Sensitivity& s : sens) prop += detail::propagated_variance(s);
  prop /= std::max<size_t>(1, sens.size());
  for (int j = 0; j < kActuators; ++j) {
    const std::vector<double>& tau = j == 0 ? log.tau1 : log.tau2;
    double s2 = 0;
    for (int i : f.index) s2 += tau[i] * tau[i] / f.index.size();
    // the torques' per-sample noise (after a delay's shift, smoothed by the interpolation)
    const double t2 = f.noise.torque[j] * f.noise.torque[j] * f.cond.torque_variance_factor;
    const double n = std::sqrt(t2 + prop(j));
    const double a = kAbsoluteFloor * std::sqrt(s2);
    floor[j] = std::max(n, a);
    if (noise != nullptr) noise[j] = n;
    if (absolute != nullptr) absolute[j] = a;
  }
}

double loss_scale_from_level(Loss loss, double level, IdentifyResult* out) {
  const double k = loss == Loss::kHuber ? kLossScaleHuber : kLossScaleCauchy;
  const double scale = level > 0 && std::isfinite(level) ? k * level : 0.1;
  out->notes.push_back(std::string(loss_name(loss)) + " loss at scale " +
                       format_significant(scale) + " N m: " + format_significant(k, 4) +
                       " times the residual's noise level per sample " + format_significant(level) +
                       " N m (--loss-scale sets it)");
  return scale;
}

void choose_loss_scale(Fit* f, IdentifyResult* out) {
  const IdentifyOptions& opt = *f->opt;
  f->loss_scale = opt.loss_scale;
  if (opt.loss != Loss::kNone && !(opt.loss_scale > 0)) {
    f->loss_scale = f->method->default_loss_scale(*f, out);
  }
  out->loss_scale = opt.loss == Loss::kNone ? 0.0 : f->loss_scale;
}

Eigen::MatrixXd dense(const ceres::CRSMatrix& crs, int P) {
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(crs.num_rows, P);
  for (int row = 0; row < crs.num_rows; ++row) {
    for (int a = crs.rows[row]; a < crs.rows[row + 1]; ++a) J(row, crs.cols[a]) = crs.values[a];
  }
  return J;
}

namespace {

/// Data residuals and Jacobian (the prior's rows, added last, left out).
void data_residuals(ceres::Problem* problem, int P, int m, Analysis* an) {
  ceres::CRSMatrix crs;
  raw_residuals(problem, &an->r, &crs);
  an->r.resize(m);
  an->J = dense(crs, P).topRows(m);
}

}  // namespace

bool solve_stage(Fit* f, ceres::Problem* problem, IdentifyResult* out,
                 ceres::Solver::Summary* summary, Analysis* an) {
  f->method->initial_levels(problem, out);
  best_stribeck_start(f, problem);
  solve(f, problem, out, summary);
  if (!out->status.ok() || !f->method->refine(f, problem, out, summary, an)) return false;
  data_residuals(problem, f->layout.size(), out->residuals, an);
  return true;
}

/// Sensor-noise sensitivities of every sample of the fit at the parameters f->x.
std::vector<detail::Sensitivity> noise_sensitivities(const Fit& f) {
  std::vector<detail::Sensitivity> sens;
  sens.reserve(f.samples.size());
  SgTapCache taps(f.cond.log.t, f.sg);  // the filter's taps, the same at every centred sample
  const detail::KinematicJacobians jacobian(f.scene, f.layout, f.x.data());
  for (size_t u = 0; u < f.samples.size(); ++u) {
    Eigen::Matrix<double, 2, 6> D;
    if (!jacobian(f.samples[u], f.eval, &D)) {
      D.setZero();
    }
    sens.push_back(detail::sensitivity(&taps, f.index[u], f.source, f.noise, D));
  }
  return sens;
}

/// The fit's problem: the method's residual blocks on f->x, the parameters' lower bounds.
bool build_problem(Fit* f, IdentifyResult* out, ceres::Problem* problem) {
  if (!f->method->add_residuals(f, out, problem)) return false;
  for (int i = 0; i < f->layout.size(); ++i)
    problem->SetParameterLowerBound(f->x.data(), i, f->layout.lower_bound(i));
  return true;
}

/// The solver's options: dense QR, the iteration limit and threads of the options, the method's
/// tolerances.
ceres::Solver::Options solver_options(const Fit& f) {
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = f.opt->max_iterations;
  so.num_threads = f.opt->num_threads;
  f.method->set_tolerances(&so);
  so.logging_type = ceres::SILENT;
  return so;
}

double torque_cost_weight(const TorqueLog& log) {
  double s = 0;
  int n = 0;
  for (int i = 0; i < log.size(); ++i) {
    for (int j = 0; j < log.dof; ++j) {
      const double t = j == 0 ? log.tau1[i] : log.tau2[i];
      if (std::isfinite(t)) s += t * t, ++n;
    }
  }
  const double ms = s / std::max(1, n);
  if (!(ms > 0) || !std::isfinite(ms)) return 1;
  return std::ldexp(1.0, -2 * static_cast<int>(std::lround(0.5 * std::log2(ms))));
}

std::string unweighted_report(const ceres::Solver::Summary& summary, double weight) {
  ceres::Solver::Summary s = summary;
  s.initial_cost /= weight;
  s.final_cost /= weight;
  return s.BriefReport();
}

}  // namespace fivebar::identification::stages
