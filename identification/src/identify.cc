// Ceres problems of the two identification methods, covariance and identifiability analysis.
#include "fivebar/identification/identify.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>

#include "fivebar/identification/residual.h"
#include "fivebar/model/dynamics.h"
#include "fivebar/model/rest.h"

namespace fivebar::identification {

bool parse_method(const std::string& name, Method* out) {
  if (name == "inverse-dynamics")
    *out = Method::kInverseDynamics;
  else if (name == "output-error")
    *out = Method::kOutputError;
  else
    return false;
  return true;
}
const char* method_name(Method m) {
  return m == Method::kOutputError ? "output-error" : "inverse-dynamics";
}
bool parse_loss(const std::string& name, Loss* out) {
  if (name == "none")
    *out = Loss::kNone;
  else if (name == "huber")
    *out = Loss::kHuber;
  else if (name == "cauchy")
    *out = Loss::kCauchy;
  else
    return false;
  return true;
}
const char* loss_name(Loss l) {
  switch (l) {
    case Loss::kNone:
      return "none";
    case Loss::kHuber:
      return "huber";
    case Loss::kCauchy:
      return "cauchy";
  }
  return "none";
}

namespace {

using Clock = std::chrono::steady_clock;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string fmt(double x, int prec = 3) {
  std::ostringstream s;
  s.precision(prec);
  s << x;
  return s.str();
}

/// Linear interpolation of y(t) on the sorted grid ts (clamped at the ends).
double interp(const std::vector<double>& ts, const std::vector<double>& y, double t) {
  if (t <= ts.front()) return y.front();
  if (t >= ts.back()) return y.back();
  const size_t i = std::upper_bound(ts.begin(), ts.end(), t) - ts.begin();
  const double s = (t - ts[i - 1]) / (ts[i] - ts[i - 1]);
  return y[i - 1] + s * (y[i] - y[i - 1]);
}

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

/// Neutral start values, independent of the scene: coulomb 0.1, viscous 0.01, static 0.15,
/// Stribeck velocity 0.2 rad/s.
std::vector<double> default_start(const ParameterLayout& layout) {
  static const double kStart[] = {0.1, 0.01, 0.15, 0.2};
  std::vector<double> x(layout.size());
  for (int i = 0; i < layout.size(); ++i) x[i] = kStart[i / layout.per_group()];
  return x;
}

/// Noise gains of the Savitzky-Golay rate and acceleration at an interior sample (white noise
/// of deviation s on the angles gives s * gain): the root sum of squares of the filter
/// coefficients, read off its response to a unit impulse in the middle of the log.
void sg_noise_gains(const std::vector<double>& t, const SgOptions& sg, double* g1, double* g2) {
  const int n = static_cast<int>(t.size());
  const int hw = sg_half_window(sg, (t.back() - t.front()) / std::max(1, n - 1));
  const int lo = std::max(0, n / 2 - 2 * hw), hi = std::min(n - 1, n / 2 + 2 * hw);
  const std::vector<double> ts(t.begin() + lo, t.begin() + hi + 1);
  std::vector<double> x(ts.size(), 0.0), d1, d2;
  x[n / 2 - lo] = 1.0;
  savitzky_golay(ts, x, sg, &d1, &d2);
  *g1 = *g2 = 0.0;
  for (size_t i = 0; i < ts.size(); ++i) {
    *g1 += d1[i] * d1[i];
    *g2 += d2[i] * d2[i];
  }
  *g1 = std::sqrt(*g1);
  *g2 = std::sqrt(*g2);
}

double larger_noise(const std::vector<double>& a, const std::vector<double>& b) {
  return std::max(series_noise(a), series_noise(b));
}

/// Thresholds of the rest rule for this log (IdentifyOptions::rest_rate_threshold).
RestThresholds rest_rule(const TorqueLog& log, const IdentifyResult& out,
                         const IdentifyOptions& opt) {
  double g1 = 0, g2 = 0;
  if (out.accels_estimated) sg_noise_gains(log.t, opt.sg, &g1, &g2);
  double rate_noise = 0, accel_noise = 0;
  if (out.rates_estimated) {
    const double s = larger_noise(log.theta1, log.theta2);
    rate_noise = g1 * s;
    accel_noise = g2 * s;
  } else {
    // logged series: never below the rounding of the angles over one sample step
    const int n = log.size();
    const double h = n > 1 ? (log.t.back() - log.t.front()) / (n - 1) : 1.0;
    const double rounding = std::max(rounding_noise(log.theta1), rounding_noise(log.theta2));
    rate_noise = std::max(larger_noise(out.omega1, out.omega2), rounding / h);
    accel_noise = out.accels_estimated
                      ? g1 * rate_noise
                      : std::max(larger_noise(out.alpha1, out.alpha2), rounding / (h * h));
  }
  RestThresholds r = rest_thresholds(rate_noise, accel_noise);
  if (opt.rest_rate_threshold >= 0) r.rate = opt.rest_rate_threshold;
  if (opt.rest_acceleration_threshold >= 0) r.acceleration = opt.rest_acceleration_threshold;
  return r;
}

template <int P>
void add_inverse_dynamics_terms(const Params<double>& scene, const ParameterLayout& layout,
                                const std::vector<Sample>& samples, const EvalOptions& eval,
                                Loss loss, double loss_scale, double* x, ceres::Problem* problem) {
  for (const Sample& s : samples) {
    auto* cost = new ceres::AutoDiffCostFunction<InverseDynamicsResidual, 2, P>(
        new InverseDynamicsResidual(scene, layout, s, eval));
    problem->AddResidualBlock(cost, make_loss(loss, loss_scale), x);
  }
}

/// Output error over one window [i0, i1]: simulated minus logged angles at samples i0+1..i1.
class WindowResidual {
 public:
  WindowResidual(const Params<double>& scene, const ParameterLayout& layout, const TorqueLog& log,
                 const sim::LoadFunction& loads, const std::vector<double>& w1,
                 const std::vector<double>& w2, int i0, int i1, const sim::Options& sim)
      : scene_(scene), layout_(layout), log_(log), i0_(i0), i1_(i1), sim_(sim) {
    loads_ = logged_loads(log, loads, log.t[i0]);
    initial_ = {log.theta1[i0], log.theta2[i0], w1[i0], w2[i0]};
    sim_.duration = log.t[i1] - log.t[i0];
    sim_.output_step = sim_.duration / (i1 - i0);
  }
  int residuals() const { return 2 * (i1_ - i0_); }

  bool operator()(double const* const* x, double* r) const {
    Params<double> p = scene_;
    layout_.apply(x[0], &p.friction);
    const sim::Result res = sim::simulate(p, loads_, initial_, sim_);
    if (!res.status.ok() || res.rows.size() < 2) return false;
    std::vector<double> ts, a, b;
    for (const sim::Row& row : res.rows) {
      ts.push_back(row.t);
      a.push_back(row.theta[0]);
      b.push_back(row.theta[1]);
    }
    for (int i = i0_ + 1, k = 0; i <= i1_; ++i, ++k) {
      const double tt = log_.t[i] - log_.t[i0_];
      if (tt > ts.back() + 1e-9) return false;
      r[2 * k] = interp(ts, a, tt) - log_.theta1[i];
      r[2 * k + 1] = interp(ts, b, tt) - log_.theta2[i];
    }
    return true;
  }

 private:
  const Params<double>& scene_;
  ParameterLayout layout_;
  const TorqueLog& log_;
  int i0_, i1_;
  sim::Options sim_;
  sim::LoadFunction loads_;
  sim::Initial initial_;
};

/// Consecutive windows [i0, i1] of about window_s over the samples [first, last].
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

sim::Options window_sim_options(double rtol) {
  sim::Options o;
  o.rtol = rtol;
  o.atol = rtol;
  o.method = sim::Method::kCvodeAdams;
  return o;
}

}  // namespace

sim::LoadFunction logged_loads(const TorqueLog& log, const sim::LoadFunction& scene_loads,
                               double t0) {
  // the simulator calls in nearly increasing t: no shared state, just a binary search
  const std::vector<double>* t = &log.t;
  const std::vector<double>* tau1 = &log.tau1;
  const std::vector<double>* tau2 = &log.tau2;
  return [t, tau1, tau2, scene_loads, t0](double s) {
    Loads<double> L = scene_loads(t0 + s);
    L.M1 = interp(*t, *tau1, t0 + s);
    L.M2 = interp(*t, *tau2, t0 + s);
    return L;
  };
}

IdentifyResult identify(const Params<double>& scene_in, const sim::LoadFunction& loads,
                        const TorqueLog& log, const IdentifyOptions& opt) {
  const auto start = Clock::now();
  IdentifyResult out;
  out.layout = opt.layout;
  out.method = opt.method;
  out.samples = log.size();
  const ParameterLayout& layout = opt.layout;
  const int P = layout.size();
  const int n = log.size();

  // the scene with the law to fit and the chosen Coulomb sign form
  Params<double> scene = scene_in;
  scene.friction.law = layout.law;
  if (opt.smoothing_velocity >= 0) scene.friction.smoothing_velocity = opt.smoothing_velocity;
  if (layout.law == FrictionLaw::kStribeck) {
    for (int k = 0; k < kJoints; ++k) {
      if (!(scene.friction.stribeck_exponent[k] > 0)) scene.friction.stribeck_exponent[k] = 2.0;
    }
  }

  // every logged pose must close with this mechanism
  check_poses(log, scene);

  // rates and accelerations: logged, else Savitzky-Golay (edges, where the window is one-sided,
  // are left out of the fit)
  int first = 0, last = n - 1;
  out.omega1 = log.omega1;
  out.omega2 = log.omega2;
  out.alpha1 = log.alpha1;
  out.alpha2 = log.alpha2;
  const double dt = n > 1 ? log.duration() / (n - 1) : 1.0;
  std::vector<double> unused;
  if (!log.has_rates || opt.estimate_rates) {
    out.rates_estimated = out.accels_estimated = true;
    savitzky_golay(log.t, log.theta1, opt.sg, &out.omega1, &out.alpha1);
    savitzky_golay(log.t, log.theta2, opt.sg, &out.omega2, &out.alpha2);
  } else if (!log.has_accels) {
    out.accels_estimated = true;
    savitzky_golay(log.t, log.omega1, opt.sg, &out.alpha1, &unused);
    savitzky_golay(log.t, log.omega2, opt.sg, &out.alpha2, &unused);
  }
  if (out.accels_estimated) {
    out.sg_half_window = sg_half_window(opt.sg, dt);
    first = out.sg_half_window;
    last = n - 1 - out.sg_half_window;
  }
  const int needed = P + 1 + (out.accels_estimated ? 2 * out.sg_half_window : 0);
  require_samples(log, needed,
                  std::to_string(P) + " parameters + 1" +
                      (out.accels_estimated ? " + the Savitzky-Golay window" : std::string()));

  // samples that enter the fit; the rest rule leaves out samples with a stuck joint and gives a
  // joint at rest that accelerates the sign of its acceleration
  const RestThresholds rest = rest_rule(log, out, opt);
  out.rest_rate_threshold = rest.rate;
  out.rest_acceleration_threshold = rest.acceleration;
  EvalOptions eval;
  eval.friction_tol = 1e-12;
  eval.friction_max_iter = 100;
  eval.rest_rate = rest.rate;
  out.used.assign(n, 0);
  std::vector<Sample> samples;
  for (int i = first; i <= last; ++i) {
    Sample s;
    s.t = log.t[i];
    s.th1 = log.theta1[i];
    s.th2 = log.theta2[i];
    s.w1 = out.omega1[i];
    s.w2 = out.omega2[i];
    s.a1 = out.alpha1[i];
    s.a2 = out.alpha2[i];
    s.tau1 = log.tau1[i];
    s.tau2 = log.tau2[i];
    s.loads = loads(s.t);
    if (opt.min_rate > 0) {
      Kinematics<double> k;
      solve_kinematics(scene, s.th1, s.th2, &k);
      Bias<double> b;
      compute_bias(scene, k, s.w1, s.w2, &b);
      const auto w = detail::relative_rates(s.w1, s.w2, b.w3, b.w4);
      bool slow = false;
      for (double wk : w) slow = slow || std::abs(wk) < opt.min_rate;
      if (slow) continue;
    }
    std::array<bool, 5> stuck{};
    if (stuck_joints(scene, s.th1, s.th2, s.w1, s.w2, s.a1, s.a2, rest, &stuck).ok() &&
        std::find(stuck.begin(), stuck.end(), true) != stuck.end()) {
      ++out.samples_at_rest;
      continue;
    }
    out.used[i] = 1;
    samples.push_back(s);
  }
  out.samples_used = static_cast<int>(samples.size());
  if (out.samples_used < P + 1) {
    throw LogError(log.path, "samples",
                   "only " + std::to_string(out.samples_used) +
                       " samples usable (rate threshold "
                       "and filter edges), fewer than the " +
                       std::to_string(P + 1) + " needed for " + std::to_string(P) + " parameters");
  }

  std::vector<double> x = opt.initial.empty() ? default_start(layout) : opt.initial;
  if (static_cast<int>(x.size()) != P) {
    out.status = Status::Error(StatusCode::kInvalidInput,
                               "initial values: expected " + std::to_string(P) + " numbers");
    return out;
  }
  const std::vector<double> x0 = x;

  // the problem
  ceres::Problem::Options popts;
  ceres::Problem problem(popts);
  if (opt.method == Method::kInverseDynamics) {
    switch (P) {
      case 2:
        add_inverse_dynamics_terms<2>(scene, layout, samples, eval, opt.loss, opt.loss_scale,
                                      x.data(), &problem);
        break;
      case 4:
        add_inverse_dynamics_terms<4>(scene, layout, samples, eval, opt.loss, opt.loss_scale,
                                      x.data(), &problem);
        break;
      case 10:
        add_inverse_dynamics_terms<10>(scene, layout, samples, eval, opt.loss, opt.loss_scale,
                                       x.data(), &problem);
        break;
      case 20:
        add_inverse_dynamics_terms<20>(scene, layout, samples, eval, opt.loss, opt.loss_scale,
                                       x.data(), &problem);
        break;
      default:
        out.status = Status::Error(StatusCode::kInvalidInput, "unsupported parameter count");
        return out;
    }
    out.residuals = 2 * out.samples_used;
  } else {
    const sim::Options so = window_sim_options(opt.sim_rtol);
    // output error: windows over the used range (the rate threshold does not apply)
    for (auto [i0, i1] : make_windows(log, first, last, opt.window_s)) {
      auto* f = new WindowResidual(scene, layout, log, loads, out.omega1, out.omega2, i0, i1, so);
      ceres::NumericDiffOptions nd;
      nd.relative_step_size = opt.relative_step;
      auto* cost = new ceres::DynamicNumericDiffCostFunction<WindowResidual, ceres::CENTRAL>(
          f, ceres::TAKE_OWNERSHIP, nd);
      cost->AddParameterBlock(P);
      cost->SetNumResiduals(f->residuals());
      out.residuals += f->residuals();
      problem.AddResidualBlock(cost, make_loss(opt.loss, opt.loss_scale), x.data());
    }
  }
  for (int i = 0; i < P; ++i) problem.SetParameterLowerBound(x.data(), i, layout.lower_bound(i));

  auto raw_residuals = [&](std::vector<double>* r) {
    ceres::Problem::EvaluateOptions eo;
    eo.apply_loss_function = false;
    double cost = 0;
    return problem.Evaluate(eo, &cost, r, nullptr, nullptr);
  };
  auto rms_pair = [](const std::vector<double>& r, double* out2) {
    double s[2] = {0, 0};
    for (size_t i = 0; i < r.size(); ++i) s[i % 2] += r[i] * r[i];
    for (int j = 0; j < 2; ++j) out2[j] = std::sqrt(s[j] / std::max<size_t>(1, r.size() / 2));
  };
  std::vector<double> r;
  if (opt.method == Method::kInverseDynamics && raw_residuals(&r)) {
    rms_pair(r, out.rms_torque_residual_initial);
  }

  // solve: nearly linear least squares in the coefficients, a few LM iterations
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = opt.max_iterations;
  so.num_threads = opt.num_threads;
  // output error: the simulated residual carries integrator noise (~rtol), so ask less of it
  const bool oe = opt.method == Method::kOutputError;
  so.function_tolerance = oe ? 1e-3 : 1e-12;  // OE cost noise ~1e-4 relative
  so.gradient_tolerance = oe ? 1e-10 : 1e-14;
  so.parameter_tolerance = oe ? 1e-7 : 1e-10;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  out.iterations = static_cast<int>(summary.iterations.size());
  out.converged = summary.termination_type == ceres::CONVERGENCE;
  out.solver_message = summary.BriefReport();
  for (const ceres::IterationSummary& it : summary.iterations) {
    out.iteration_costs.push_back(it.cost);
  }
  if (!summary.IsSolutionUsable()) {
    out.status = Status::Error(StatusCode::kSolverFailed, "Ceres: " + summary.message);
  }

  // residual variance s^2 = 2 cost / (m - p) and raw residuals per actuator
  const int m = summary.num_residuals;
  out.residual_sigma = std::sqrt(2.0 * summary.final_cost / std::max(1, m - P));
  if (oe) {
    out.warnings.push_back(
        "output-error standard deviations treat the angle residuals as independent; within a "
        "window they are correlated (they integrate the torque noise), so the reported std "
        "understate the uncertainty");
  }
  if (raw_residuals(&r)) {
    if (opt.method == Method::kInverseDynamics)
      rms_pair(r, out.rms_torque_residual);
    else
      rms_pair(r, out.rms_angle_residual);
    if (opt.method == Method::kInverseDynamics) {
      // the sensor noise alone is white: its level is what sample-to-sample differences see,
      // taken robustly (1.4826 median |r_i - r_i-1| / sqrt 2) so that the few sharp features of a
      // mismatch do not raise it; a residual rms well above that has structure the model misses
      for (int j = 0; j < 2; ++j) {
        std::vector<double> d;
        for (size_t i = 2 + j; i < r.size(); i += 2) d.push_back(std::abs(r[i] - r[i - 2]));
        if (d.empty()) continue;
        std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
        out.residual_noise_floor[j] = 1.4826 * d[d.size() / 2] / std::sqrt(2.0);
        const double ratio = out.rms_torque_residual[j] / out.residual_noise_floor[j];
        if (ratio > 1.1) {
          out.warnings.push_back(
              "tau" + std::to_string(j + 1) + " residual rms " + fmt(out.rms_torque_residual[j]) +
              " N m is " + fmt(ratio) + " times its white-noise floor " +
              fmt(out.residual_noise_floor[j]) + " N m: the residual has structure the fitted " +
              "law (or the estimated rates) cannot explain; see fig_residual_vs_rate.png");
        }
      }
    }
  }

  // covariance scaled by the residual variance
  out.covariance = Eigen::MatrixXd::Constant(P, P, kNaN);
  {
    ceres::Covariance::Options co;
    co.algorithm_type = ceres::DENSE_SVD;
    co.null_space_rank = -1;
    co.min_reciprocal_condition_number = 1e-14;
    co.num_threads = opt.num_threads;
    ceres::Covariance cov(co);
    std::vector<std::pair<const double*, const double*>> blocks = {{x.data(), x.data()}};
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> c(P, P);
    if (cov.Compute(blocks, &problem) && cov.GetCovarianceBlock(x.data(), x.data(), c.data())) {
      out.covariance = c * (out.residual_sigma * out.residual_sigma);
    } else {
      out.warnings.push_back("covariance could not be computed (Jacobian rank deficient)");
    }
  }
  out.correlation = Eigen::MatrixXd::Constant(P, P, kNaN);
  for (int i = 0; i < P; ++i) {
    for (int j = 0; j < P; ++j) {
      out.correlation(i, j) =
          out.covariance(i, j) / std::sqrt(out.covariance(i, i) * out.covariance(j, j));
    }
  }

  // identifiability: singular values of the Jacobian with unit-norm columns
  const std::vector<std::string> names = layout.names();
  {
    ceres::Problem::EvaluateOptions eo;
    eo.apply_loss_function = false;
    ceres::CRSMatrix crs;
    double cost = 0;
    if (problem.Evaluate(eo, &cost, nullptr, nullptr, &crs)) {
      Eigen::MatrixXd JtJ = Eigen::MatrixXd::Zero(P, P);
      for (int row = 0; row < crs.num_rows; ++row) {
        for (int a = crs.rows[row]; a < crs.rows[row + 1]; ++a) {
          for (int b = crs.rows[row]; b < crs.rows[row + 1]; ++b) {
            JtJ(crs.cols[a], crs.cols[b]) += crs.values[a] * crs.values[b];
          }
        }
      }
      Eigen::VectorXd scale(P);
      for (int i = 0; i < P; ++i) {
        scale(i) = std::sqrt(JtJ(i, i));
        if (!(scale(i) > 0)) {
          out.warnings.push_back("parameter " + names[i] +
                                 " has no effect on the residuals: the log does not excite it");
          scale(i) = 1;
        }
      }
      const Eigen::MatrixXd S = scale.asDiagonal().inverse() * JtJ * scale.asDiagonal().inverse();
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(S);
      // eigenvalues of J^T J ascending: singular values are their square roots
      for (int i = P - 1; i >= 0; --i)
        out.singular_values.push_back(std::sqrt(std::max(0.0, es.eigenvalues()(i))));
      const double ratio = out.singular_values.back() / out.singular_values.front();
      if (ratio < 1e-2) {  // condition number above 100 with unit-norm columns
        const Eigen::VectorXd v = es.eigenvectors().col(0);
        std::string who;
        for (int i = 0; i < P; ++i) {
          if (std::abs(v(i)) > 0.3) who += (who.empty() ? "" : ", ") + names[i];
        }
        out.warnings.push_back("the log cannot separate " + who +
                               " (smallest/largest scaled singular value " + fmt(ratio) + ")");
      }
    }
  }
  for (int i = 0; i < P; ++i) {
    for (int j = i + 1; j < P; ++j) {
      if (std::abs(out.correlation(i, j)) > 0.98) {
        out.warnings.push_back("strong correlation " + fmt(out.correlation(i, j)) + " between " +
                               names[i] + " and " + names[j]);
      }
    }
  }

  // estimates
  for (int i = 0; i < P; ++i) {
    ParameterEstimate e;
    e.name = names[i];
    e.value = x[i];
    e.std = std::sqrt(out.covariance(i, i));
    e.initial = x0[i];
    if (x[i] <= layout.lower_bound(i) + 1e-12) {
      out.warnings.push_back(names[i] + " is at its lower bound " + fmt(layout.lower_bound(i)));
    } else if (e.std > std::abs(x[i])) {
      out.warnings.push_back(names[i] + " is poorly determined (std " + fmt(e.std) + " > value " +
                             fmt(x[i]) + ")");
    }
    out.parameters.push_back(e);
  }
  out.fitted = scene_in;
  layout.apply(x.data(), &out.fitted.friction);

  // predicted torques at every sample (the fitted model, same sign convention)
  out.predicted_tau1.assign(n, kNaN);
  out.predicted_tau2.assign(n, kNaN);
  Params<double> fit_eval = scene;
  layout.apply(x.data(), &fit_eval.friction);
  for (int i = 0; i < n; ++i) {
    Evaluation<double> ev;
    const Status st =
        inverse_dynamics(fit_eval, loads(log.t[i]), log.theta1[i], log.theta2[i], out.omega1[i],
                         out.omega2[i], out.alpha1[i], out.alpha2[i], nullptr, eval, &ev);
    if (st.ok()) {
      out.predicted_tau1[i] = ev.M1;
      out.predicted_tau2[i] = ev.M2;
    }
  }
  if (opt.method == Method::kOutputError) {
    double s[2] = {0, 0};
    int c = 0;
    for (int i = first; i <= last; ++i) {
      if (std::isnan(out.predicted_tau1[i])) continue;
      s[0] += std::pow(log.tau1[i] - out.predicted_tau1[i], 2);
      s[1] += std::pow(log.tau2[i] - out.predicted_tau2[i], 2);
      ++c;
    }
    for (int j = 0; j < 2; ++j) out.rms_torque_residual[j] = std::sqrt(s[j] / std::max(1, c));
    // the same robust white-noise floor as for inverse dynamics, on the torque residual
    for (int j = 0; j < 2; ++j) {
      const std::vector<double>& tau = j == 0 ? log.tau1 : log.tau2;
      const std::vector<double>& pred = j == 0 ? out.predicted_tau1 : out.predicted_tau2;
      std::vector<double> d;
      for (int i = first + 1; i <= last; ++i) {
        const double e = (tau[i] - pred[i]) - (tau[i - 1] - pred[i - 1]);
        if (std::isfinite(e)) d.push_back(std::abs(e));
      }
      if (d.empty()) continue;
      std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
      out.residual_noise_floor[j] = 1.4826 * d[d.size() / 2] / std::sqrt(2.0);
    }
  }
  out.wall_time_s = std::chrono::duration<double>(Clock::now() - start).count();
  return out;
}

Validation validate(const Params<double>& params, const sim::LoadFunction& loads,
                    const TorqueLog& log, const std::vector<double>& omega1,
                    const std::vector<double>& omega2, double window_s, double rtol) {
  Validation v;
  v.window_s = window_s;
  const int n = log.size();
  v.full_theta1.assign(n, kNaN);
  v.full_theta2.assign(n, kNaN);
  if (n < 2) return v;
  auto run = [&](int i0, int i1, bool full, double* s2, int* count) {
    sim::Options o = window_sim_options(rtol);
    o.duration = log.t[i1] - log.t[i0];
    o.output_step = o.duration / (i1 - i0);
    const sim::Result res =
        sim::simulate(params, logged_loads(log, loads, log.t[i0]),
                      {log.theta1[i0], log.theta2[i0], omega1[i0], omega2[i0]}, o);
    std::vector<double> ts, a, b;
    for (const sim::Row& row : res.rows) {
      ts.push_back(row.t);
      a.push_back(row.theta[0]);
      b.push_back(row.theta[1]);
    }
    if (full) {
      v.status = res.status;
      v.full_duration_s = ts.empty() ? 0.0 : ts.back();
    }
    if (ts.size() < 2) return;
    for (int i = i0; i <= i1; ++i) {
      const double tt = log.t[i] - log.t[i0];
      if (tt > ts.back() + 1e-9) break;
      const double e1 = interp(ts, a, tt) - log.theta1[i];
      const double e2 = interp(ts, b, tt) - log.theta2[i];
      s2[0] += e1 * e1;
      s2[1] += e2 * e2;
      ++*count;
      if (full) {
        v.full_theta1[i] = interp(ts, a, tt);
        v.full_theta2[i] = interp(ts, b, tt);
        v.full_max[0] = std::max(v.full_max[0], std::abs(e1));
        v.full_max[1] = std::max(v.full_max[1], std::abs(e2));
      }
    }
  };
  double s2[2] = {0, 0};
  int count = 0;
  run(0, n - 1, true, s2, &count);
  for (int j = 0; j < 2; ++j) v.full_rms[j] = std::sqrt(s2[j] / std::max(1, count));
  double w2[2] = {0, 0};
  int wc = 0;
  for (auto [i0, i1] : make_windows(log, 0, n - 1, window_s)) run(i0, i1, false, w2, &wc);
  for (int j = 0; j < 2; ++j) v.window_rms[j] = std::sqrt(w2[j] / std::max(1, wc));
  return v;
}

}  // namespace fivebar::identification
