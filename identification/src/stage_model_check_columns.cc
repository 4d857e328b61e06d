// Model check of identify(), its Jacobian: the columns of the causes it frees (inertia, angle
// offsets, torque readings), the acceleration-bias scores, and the fit they are taken on.
#include "identify_stages.h"
#include "model_check_causes.h"

namespace fivebar::identification::stages {

namespace {

// ---- model checks (misfit.h) ----

/// The fit's residual blocks under `layout2` on the parameter vector *x2 (kept alive by the
/// caller, who may change it between evaluations); false for an unsupported size.
bool check_problem(const Fit& f, const ParameterLayout& layout2, std::vector<double>* x2,
                   ceres::Problem* problem) {
  return add_inverse_dynamics_terms(f.scene, layout2, f.samples, f.eval, Loss::kNone, 1, x2->data(),
                                    problem);
}

/// The Jacobian J0 and residual r0, rows whitened by the noise floors `fl`; false if not finite.
bool whitened(const Eigen::MatrixXd& J0, const std::vector<double>& r0, const double fl[2],
              Eigen::MatrixXd* J, Eigen::VectorXd* r) {
  *J = J0;
  *r = Eigen::Map<const Eigen::VectorXd>(r0.data(), r0.size());
  for (Eigen::Index row = 0; row < J->rows(); ++row) {
    J->row(row) /= fl[row % 2];
    (*r)(row) /= fl[row % 2];
  }
  return J->allFinite() && r->allFinite();
}

/// The Jacobian of `problem`'s residuals (P parameters) at its current values, rows whitened by
/// the noise floors `fl`, and the whitened residual; false if an evaluation fails.
bool whitened_jacobian(ceres::Problem* problem, int P, const double fl[2], Eigen::MatrixXd* J,
                       Eigen::VectorXd* r) {
  std::vector<double> rv;
  ceres::CRSMatrix crs;
  if (!raw_residuals(problem, &rv, &crs)) return false;
  return whitened(dense(crs, P), rv, fl, J, r);
}

/// The fit's vector under `layout2`, which differs from f.layout in its friction part or by the
/// inertial group: `friction` then the scene's inertial parameters (or the fitted ones), then
/// the fitted actuator terms.
std::vector<double> with_layout(const Fit& f, const ParameterLayout& layout2,
                                std::vector<double> friction) {
  const auto mid = f.x.begin() + f.layout.friction_size();
  if (f.layout.inertia) {
    friction.insert(friction.end(), mid, mid + kInertialParams);
  } else if (layout2.inertia) {
    const detail::InertialPrior prior = detail::inertial_prior(f.scene, f.opt->inertia_prior);
    friction.insert(friction.end(), prior.centre.begin(), prior.centre.end());
  }
  if (f.layout.actuator) friction.insert(friction.end(), f.x.end() - kActuatorTerms, f.x.end());
  return friction;
}

/// The check's step on the logged angles [rad] (offset_columns) and on the accelerations
/// [rad/s^2] (accel_derivatives)
constexpr double kOffsetStep = 1e-6;
constexpr double kAccelStep = 1e-2;

/// Columns of the residual's Jacobian on offsets d of the logged angles (theta1, theta2 read d
/// more than the scene's angles: the model is evaluated at theta - d), by central differences at
/// the fit, rows whitened by the floors `fl`; false if an evaluation fails. The residual of each
/// shifted sample is the full model's (InverseDynamicsResidual, equal to the fit's residual to
/// the friction loop's tolerance): a sample's structure costs 17 more evaluations and is not
/// needed for a residual alone.
bool offset_columns(const Fit& f, const double fl[2], Eigen::MatrixXd* Jo) {
  constexpr double h = kOffsetStep;
  const int m = 2 * static_cast<int>(f.samples.size());
  Jo->setZero(m, 2);
  for (int c = 0; c < 2; ++c) {
    for (double sgn : {1.0, -1.0}) {
      for (size_t u = 0; u < f.samples.size(); ++u) {
        Sample s = f.samples[u];
        (c == 0 ? s.th1 : s.th2) -= sgn * h;
        double r[2];
        if (!InverseDynamicsResidual(f.scene, f.layout, s, f.eval)(f.x.data(), r)) return false;
        for (int k = 0; k < 2; ++k) (*Jo)(2 * u + k, c) += sgn * r[k] / (2 * h * fl[k]);
      }
    }
  }
  return Jo->allFinite();
}

/// The columns (r: the whitened residual at the fit, fl: the noise floors) on errors of the
/// torque readings, tau_c = (1 + g_c) M_c + o_c: the offsets o1, o2 (left out when the fit has
/// them, --estimate actuator) then the gains g1, g2 (unless nearly an offset: unlike_an_offset),
/// with M_c the fitted model's
/// torque (tau_c - o_c - r_c).
TorqueColumns torque_columns(const Fit& f, const Eigen::VectorXd& r, const double fl[2]) {
  const double* o = f.layout.actuator ? &f.x[f.layout.actuator_offset()] : nullptr;
  const Eigen::Index n = static_cast<Eigen::Index>(f.samples.size());
  Eigen::MatrixXd model(n, kDof);
  for (Eigen::Index u = 0; u < n; ++u) {
    for (int c = 0; c < kDof; ++c) {
      const double tau = c == 0 ? f.samples[u].tau1 : f.samples[u].tau2;
      model(u, c) = tau - (o ? o[c] : 0.0) - r(2 * u + c) * fl[c];
    }
  }
  TorqueColumns tc;
  int k = 0;
  for (int c = 0; c < kDof && !o; ++c) tc.offset[c] = k++;
  for (int c = 0; c < kDof; ++c) {
    if (unlike_an_offset(model.col(c))) tc.gain[c] = k++;
  }
  tc.J = Eigen::MatrixXd::Zero(r.size(), k);
  for (Eigen::Index u = 0; u < n; ++u) {
    for (int c = 0; c < kDof; ++c) {
      if (tc.offset[c] >= 0) tc.J(2 * u + c, tc.offset[c]) = -1.0 / fl[c];
      if (tc.gain[c] >= 0) tc.J(2 * u + c, tc.gain[c]) = -model(u, c) / fl[c];
    }
  }
  return tc;
}

/// The columns on the motors' friction coefficients, when the fit leaves them out (--estimate
/// actuator fits them; no columns then): of actuator_coulomb_1, _2, actuator_viscous_1, _2 of the
/// drives' residuals (motor_friction_columns), those unlike an offset (motor_terms: not a crank
/// that never reverses, or turns at a steady rate, which the torque readings' offsets cover),
/// rows whitened by the floors `fl`; `terms`: their actuator terms.
Eigen::MatrixXd motor_columns(const Fit& f, const double fl[2], std::vector<int>* terms) {
  const Eigen::Index n = static_cast<Eigen::Index>(f.samples.size());
  terms->clear();
  if (f.layout.actuator) return Eigen::MatrixXd(2 * n, 0);
  Eigen::MatrixXd D(n, 2 * kActuators);  // per sample: coulomb_1, _2, viscous_1, _2 of its drive
  for (Eigen::Index u = 0; u < n; ++u) {
    const Sample& s = f.samples[u];
    const double w[kActuators] = {s.w1, s.w2}, a[kActuators] = {s.a1, s.a2};
    for (int c = 0; c < kActuators; ++c) {
      const Eigen::Vector2d d = motor_friction_columns(f.scene.friction, f.eval, w[c], a[c]);
      D(u, c) = d(0);
      D(u, kActuators + c) = d(1);
    }
  }
  *terms = motor_terms(D, kActuators);
  Eigen::MatrixXd Jm = Eigen::MatrixXd::Zero(2 * n, static_cast<Eigen::Index>(terms->size()));
  for (size_t k = 0; k < terms->size(); ++k) {
    const int col = (*terms)[k] - kActuators, c = col % kActuators;  // c: the drive's channel
    for (Eigen::Index u = 0; u < n; ++u) Jm(2 * u + c, k) = D(u, col) / fl[c];
  }
  return Jm;
}

}  // namespace

bool check_jacobian(const Fit& f, const double fl[2], Eigen::MatrixXd* J, Eigen::VectorXd* r,
                    CauseColumns& idx, Eigen::VectorXd* info, TorqueColumns* tc,
                    const Analysis* at_fit) {
  const int nf = f.layout.friction_size();
  ParameterLayout l2 = f.layout;
  l2.inertia = true;
  Eigen::MatrixXd Ji, Jo;
  if (f.layout.inertia && at_fit != nullptr && at_fit->J.cols() == l2.size()) {
    // the fit's own columns already hold the inertial ones, at the same parameters
    if (!whitened(at_fit->J, at_fit->r, fl, &Ji, r)) return false;
  } else {
    std::vector<double> x2 = with_layout(f, l2, std::vector<double>(f.x.begin(), f.x.begin() + nf));
    ceres::Problem problem;
    if (!check_problem(f, l2, &x2, &problem) ||
        !whitened_jacobian(&problem, l2.size(), fl, &Ji, r)) {
      return false;
    }
  }
  if (!offset_columns(f, fl, &Jo) || Jo.rows() != Ji.rows()) return false;
  *tc = torque_columns(f, *r, fl);
  const Eigen::MatrixXd Jm = motor_columns(f, fl, &tc->motor_terms);
  const Eigen::MatrixXd& Jt = tc->J;  // (last: score_bias)
  J->resize(Ji.rows(), Ji.cols() + 2 + Jm.cols() + Jt.cols());
  *J << Ji, Jo, Jm, Jt;
  for (int i = 0; i < l2.size(); ++i) {
    const bool candidate = l2.is_inertial(i) && !f.layout.inertia;
    // a fitted parameter without effect on the residual (a crank's mass without gravity: its
    // column is exactly 0) cannot be refitted, and would make every refit singular
    if (!candidate && !(J->col(i).squaredNorm() > 0)) continue;
    idx[candidate ? 1 : 0].push_back(i);
  }
  idx[kCauseAngles + 1] = {l2.size(), l2.size() + 1};
  int c = l2.size() + 2;
  for (Eigen::Index k = 0; k < Jm.cols(); ++k) idx[kCauseMotors + 1].push_back(c++);
  for (Eigen::Index k = 0; k < Jt.cols(); ++k) idx[kCauseTorque + 1].push_back(c++);
  const detail::InertialPrior prior = detail::inertial_prior(f.scene, f.opt->inertia_prior);
  info->resize(kInertialParams);
  for (int k = 0; k < kInertialParams; ++k) (*info)(k) = 1.0 / std::pow(prior.sigma[k], 2);
  return true;
}

namespace {

/// The sum of the squared taps through which a noise channel (an angle, or a logged rate) reaches
/// the estimated acceleration at log sample i (noise of std s on the channel: s^2 times it on the
/// acceleration): the Savitzky-Golay d2 of the angles, or d1 of logged rates (the filter's taps
/// from `taps`, over the log's t and f.sg); 0 when the accelerations are logged (their own noise
/// is not modelled).
double accel_tap_power(const Fit& f, SgTapCache* taps, int i) {
  if (f.source == detail::RateSource::kLogged) return 0.0;
  int lo = i;
  const std::vector<double>*d1 = nullptr, *d2 = nullptr;
  taps->taps(i, &lo, &d1, &d2);
  const std::vector<double>& d = f.source == detail::RateSource::kFromAngles ? *d2 : *d1;
  double power = 0;
  for (double w : d) power += w * w;
  return power;
}

/// d J / d alpha_c and d r / d alpha_c (c: crank 1, 2; each moved at every sample at once) of
/// the whitened Jacobian on the fitted and inertial parameters and the angle offsets
/// (check_jacobian's columns but the torque readings') and of the whitened residual, by forward
/// differences from J, r at the fit (the residual is nearly linear in the accelerations: only the
/// load-dependent friction is not); false if an evaluation fails.
bool accel_derivatives(const Fit& f, const double fl[2], const Eigen::MatrixXd& J,
                       const Eigen::VectorXd& r, Eigen::MatrixXd dJ[2], Eigen::VectorXd dr[2]) {
  constexpr double h = kAccelStep;
  ParameterLayout l2 = f.layout;
  l2.inertia = true;
  Fit g = f;
  for (int c = 0; c < kDof; ++c) {
    for (size_t u = 0; u < f.samples.size(); ++u) {
      g.samples[u].a1 = f.samples[u].a1 + (c == 0 ? h : 0.0);
      g.samples[u].a2 = f.samples[u].a2 + (c == 1 ? h : 0.0);
    }
    const auto friction_end = f.x.begin() + f.layout.friction_size();
    std::vector<double> x2 = with_layout(g, l2, std::vector<double>(f.x.begin(), friction_end));
    ceres::Problem problem;
    Eigen::MatrixXd Jh, Jo;
    Eigen::VectorXd rh;
    if (!check_problem(g, l2, &x2, &problem) ||
        !whitened_jacobian(&problem, l2.size(), fl, &Jh, &rh) || !offset_columns(g, fl, &Jo) ||
        Jh.rows() != J.rows() || Jo.rows() != J.rows() || Jh.cols() + Jo.cols() > J.cols()) {
      return false;
    }
    dJ[c].resize(J.rows(), Jh.cols() + Jo.cols());
    dJ[c] << Jh, Jo;
    dJ[c] = (dJ[c] - J.leftCols(dJ[c].cols())) / h;
    dr[c] = (rh - r) / h;
  }
  return true;
}

}  // namespace

bool score_bias(const Fit& f, const double fl[2], const Eigen::MatrixXd& J,
                const Eigen::VectorXd& r, const TorqueColumns& tc, Eigen::VectorXd* b) {
  b->setZero(J.cols());
  // the std of each crank's noise channel
  const double* sigma = f.source == detail::RateSource::kFromAngles ? f.noise.angle : f.noise.rate;
  if (f.source == detail::RateSource::kLogged || !(sigma[0] > 0 || sigma[1] > 0)) return true;
  Eigen::MatrixXd dJ[2];
  Eigen::VectorXd dr[2];
  if (!accel_derivatives(f, fl, J, r, dJ, dr)) return false;
  // the torque gains' columns (the last of J, torque_columns) hold minus the model's torque,
  // whose derivative in the accelerations is the residual's: dr_c on their crank's rows
  const Eigen::Index first = J.cols() - tc.J.cols();
  SgTapCache taps(f.cond.log.t, f.sg);
  for (size_t u = 0; u < f.samples.size(); ++u) {
    const Eigen::Index row = 2 * static_cast<Eigen::Index>(u);
    const double m = accel_tap_power(f, &taps, f.index[u]);
    for (int c = 0; c < kDof; ++c) {
      const double v = sigma[c] * sigma[c] * m;
      b->head(dJ[c].cols()) += v * dJ[c].middleRows(row, 2).transpose() * dr[c].segment(row, 2);
      for (int k = 0; k < kDof; ++k) {
        if (tc.gain[k] >= 0) (*b)(first + tc.gain[k]) += v * std::pow(dr[c](row + k), 2);
      }
    }
  }
  return b->allFinite();
}

namespace {

/// Marks in `fails` the samples whose residual block, under `layout` at x, does not evaluate
/// (the friction loop does not converge there), with each sample changed by `change` first.
template <typename Change>
void mark_failures(const Fit& f, const ParameterLayout& layout, std::vector<double> x,
                   Change change, std::vector<bool>* fails) {
  std::vector<Sample> s = f.samples;
  for (Sample& e : s) change(&e);
  ceres::Problem problem;
  if (!add_inverse_dynamics_terms(f.scene, layout, s, f.eval, Loss::kNone, 1, x.data(), &problem)) {
    return;
  }
  std::vector<ceres::ResidualBlockId> blocks;
  problem.GetResidualBlocks(&blocks);
  for (size_t u = 0; u < blocks.size() && u < fails->size(); ++u) {
    double cost = 0, r[2];
    if (!problem.EvaluateResidualBlock(blocks[u], false, &cost, r, nullptr) ||
        !std::isfinite(r[0]) || !std::isfinite(r[1])) {
      (*fails)[u] = true;
    }
  }
}

}  // namespace

std::vector<int> check_failures(const Fit& f) {
  ParameterLayout l2 = f.layout;
  l2.inertia = true;
  const std::vector<double> x2 =
      with_layout(f, l2, std::vector<double>(f.x.begin(), f.x.begin() + f.layout.friction_size()));
  std::vector<bool> fails(f.samples.size(), false);
  mark_failures(
      f, l2, x2, [](Sample*) {}, &fails);
  for (double h : {kOffsetStep, -kOffsetStep}) {
    mark_failures(
        f, f.layout, f.x, [h](Sample* e) { e->th1 -= h; }, &fails);
    mark_failures(
        f, f.layout, f.x, [h](Sample* e) { e->th2 -= h; }, &fails);
  }
  mark_failures(
      f, l2, x2, [](Sample* e) { e->a1 += kAccelStep; }, &fails);
  mark_failures(
      f, l2, x2, [](Sample* e) { e->a2 += kAccelStep; }, &fails);
  std::vector<int> out;
  for (size_t u = 0; u < fails.size(); ++u) {
    if (fails[u]) out.push_back(static_cast<int>(u));
  }
  return out;
}

/// The check's Jacobian, residual and score bias (check_jacobian, score_bias) on fit, or on
/// *spare: fit without the samples where the check's changes do not evaluate (check_failures;
/// a heavy mechanism driven a hair from its stretched singular pose: one sample's friction loop
/// did not converge with an encoder's zero moved by 1e-6 rad), noted. The fit the check runs on,
/// or nullptr with verdict->unchecked (and short_log) saying why it cannot run.
const Fit* check_inputs(const Fit& fit, const double fl[2], const Analysis* an, Fit* spare,
                        IdentifyResult* out, Eigen::MatrixXd* J, Eigen::VectorXd* r,
                        CauseColumns& idx, Eigen::VectorXd* info, TorqueColumns* tc,
                        Eigen::VectorXd* bias, ModelVerdict* verdict) {
  const auto run = [&](const Fit& f) {
    return check_jacobian(f, fl, J, r, idx, info, tc, &f == &fit ? an : nullptr) &&
           (J->rows() < kCheckRowsPerColumn * J->cols() || score_bias(f, fl, *J, *r, *tc, bias));
  };
  const Fit* f = &fit;
  if (!run(fit)) {
    const std::vector<int> bad = check_failures(fit);
    const size_t n = fit.samples.size();
    if (bad.empty() || 2 * bad.size() > n) {
      verdict->unchecked = "the model cannot be evaluated under the check's small changes";
      return nullptr;
    }
    *spare = fit;
    spare->samples.clear();
    spare->index.clear();
    for (size_t u = 0, b = 0; u < n; ++u) {
      if (b < bad.size() && bad[b] == static_cast<int>(u)) {
        ++b;
        continue;
      }
      spare->samples.push_back(fit.samples[u]);
      spare->index.push_back(fit.index[u]);
    }
    const std::string where = std::to_string(bad.size()) + " sample" +
                              (bad.size() == 1 ? "" : "s") + " (first " +
                              sample_name(fit.cond.log, fit.index[bad[0]]) + ")";
    for (std::vector<int>& columns : idx) columns.clear();
    if (!run(*spare)) {
      verdict->unchecked =
          "the model cannot be evaluated under the check's small changes, even "
          "without the " +
          where + " where the friction loop does not converge";
      return nullptr;
    }
    out->notes.push_back("model check: " + where +
                         " left out, where the friction loop does not "
                         "converge under the check's small changes (a pose near a singular one?)");
    f = spare;
  }
  if (J->rows() < kCheckRowsPerColumn * J->cols()) {
    verdict->unchecked = "the log has " + std::to_string(J->rows()) + " residuals for its " +
                         std::to_string(J->cols()) + " columns (fewer than " +
                         std::to_string(kCheckRowsPerColumn) + " per column)";
    verdict->short_log = true;
    return nullptr;
  }
  return f;
}

}  // namespace fivebar::identification::stages
