// Covariance stage of identify(): residual levels, covariance, identifiability, estimates, the
// inertial report.
#include "identify_stages.h"

namespace fivebar::identification::stages {

namespace {

/// residual rms above this multiple of the expected noise level is structure: the noise levels
/// are robust estimates good to a few % on a few thousand samples
constexpr double kStructureRatio = 1.15;

/// output error: below this many windows the block sandwich's std are themselves uncertain
/// (their relative error is about 1 / sqrt(2 (windows - 1)), 24 % for 10 windows)
constexpr int kFewWindows = 10;


}  // namespace

Eigen::MatrixXd prior_information(const Fit& f) {
  const int P = f.layout.size();
  if (!f.layout.inertia) return Eigen::MatrixXd::Zero(P, P);
  return detail::prior_information(f.prior, f.prior_scale, P, f.layout.inertia_offset());
}

namespace {

/// Group inertia: detail::inertial_stage at the fit.
void inertial_stage(const Fit& f, const Eigen::MatrixXd& J, IdentifyResult* out) {
  const int off = f.layout.inertia_offset(), n = f.layout.inertial_size();
  const std::vector<double> pi(f.x.begin() + off, f.x.begin() + off + n);
  detail::inertial_stage(J.middleCols(off, n), f.prior, f.prior_scale, pi,
                         out->covariance.block(off, off, n, n), f.opt->inertia_prior, out);
}

/// The parameters of the covariance: those with an effect on the residuals, and of them those
/// at their bound only when `with_bound`; empty index when none is.
FreeSet free_set(const Fit& f, const Eigen::MatrixXd& J, const Eigen::MatrixXd& Hp,
                 bool with_bound) {
  FreeSet fs;
  for (int i = 0; i < f.layout.size(); ++i) {
    const bool off_bound = f.x[i] > f.layout.lower_bound(i) + 1e-12;
    // (a parameter with prior information is informed by it: the crank masses' columns are
    // exactly 0 without gravity, and their posterior is their prior)
    const bool informed = J.col(i).squaredNorm() > 0 || Hp(i, i) > 0;
    if ((with_bound || off_bound) && informed) fs.index.push_back(i);
  }
  const int n = static_cast<int>(fs.index.size());
  fs.J.resize(J.rows(), n);
  fs.Hp.resize(n, n);
  for (int a = 0; a < n; ++a) {
    fs.J.col(a) = J.col(fs.index[a]);
    for (int b = 0; b < n; ++b) fs.Hp(a, b) = Hp(fs.index[a], fs.index[b]);
  }
  fs.s2 = f.prior_scale * f.prior_scale;
  return fs;
}

/// Whether the information H (eigen-decomposed in es) can be inverted to a covariance.
bool well_conditioned(const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>& es,
                      const Eigen::MatrixXd& H) {
  const double emax = es.eigenvalues().maxCoeff(), emin = es.eigenvalues().minCoeff();
  return emax > 0 && emin > 1e-14 * emax && H.allFinite();
}

/// `Cf` (over the free parameters) into the rows and columns fs.index of *C.
void scatter_into(const FreeSet& fs, const Eigen::MatrixXd& Cf, Eigen::MatrixXd* C) {
  for (size_t a = 0; a < fs.index.size(); ++a) {
    for (size_t b = 0; b < fs.index.size(); ++b) (*C)(fs.index[a], fs.index[b]) = Cf(a, b);
  }
}

}  // namespace

/// Covariance of the internal parameters, only on a converged solution with a full-rank
/// Jacobian (of the parameters off their bounds): errors in variables (the method's, sandwich
/// or window sandwich), else s^2 (J^T J)^-1. an->Hinv: (J^T J + Hp)^-1 of the free parameters.
void covariance(const Fit& f, const Eigen::MatrixXd& Hp, Analysis* an, IdentifyResult* out) {
  const int P = f.layout.size();
  out->covariance = Eigen::MatrixXd::Constant(P, P, kNaN);
  an->Hinv = out->covariance;
  if (!out->converged) {
    out->warnings.push_back("the solver did not converge (" + out->solver_message +
                            "): no covariance, standard deviations not given");
    return;
  }
  // parameters without effect on the residuals are left out. Those at a bound are kept, so that
  // the direction a bound holds keeps its uncertainty in the others' std (a light five-bar's
  // viscous at 0 had coulomb's std at half its spread, 3 of 4 such intervals missing the
  // truth), unless the log does not determine them: then the covariance is the others'
  FreeSet fs = free_set(f, an->J, Hp, /*with_bound=*/true);
  if (fs.index.empty()) return;
  // the prior (group inertia) as a pseudo-observation of noise level s: information Hp = s^2 /
  // sigma^2, score covariance s^2 Hp; the covariance is then the posterior one (a direction the
  // log cannot determine gets its prior std, the CAD error it may carry)
  Eigen::MatrixXd H = fs.J.transpose() * fs.J + fs.Hp;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(H);
  if (!well_conditioned(es, H)) {
    fs = free_set(f, an->J, Hp, /*with_bound=*/false);
    if (fs.index.empty()) return;
    H = fs.J.transpose() * fs.J + fs.Hp;
    es.compute(H);
  }
  if (!well_conditioned(es, H)) {
    out->warnings.push_back("covariance could not be computed (Jacobian rank deficient)");
    // a fit with no std cannot say how far to trust it
    if (out->unusable.empty()) {
      out->unusable = "the covariance could not be computed (the log does not determine the "
                      "free coefficients apart): the estimates have no std";
    }
    return;
  }
  // evaluated into a matrix of its own, then copied: assigned into fs.Hinv directly, Eigen
  // takes another product path, whose last bits differ
  const Eigen::MatrixXd Hinv = es.eigenvectors() * es.eigenvalues().cwiseInverse().asDiagonal() *
                               es.eigenvectors().transpose();
  fs.Hinv = Hinv;
  scatter_into(fs, fs.Hinv, &an->Hinv);  // the profile intervals' noise scale (intervals)
  if (f.opt->errors_in_variables) {
    const Eigen::MatrixXd C = f.method->errors_in_variables(f, fs, *an, out);
    if (C.size() > 0) scatter_into(fs, C, &out->covariance);
    return;
  }
  const double sig2 = out->residual_sigma * out->residual_sigma;
  // the prior at the residual's level: H = J^T J + sig2 / sigma^2
  const Eigen::MatrixXd H2 = fs.J.transpose() * fs.J + fs.Hp * (sig2 / fs.s2);
  scatter_into(fs, H2.ldlt().solve(Eigen::MatrixXd::Identity(H2.rows(), H2.cols())) * sig2,
               &out->covariance);
  out->std_method = "residual-variance";
}

/// Inverse dynamics, errors in variables: the sandwich Hinv S Hinv, S the score covariance of
/// the sensor noise through the residual plus the residual beyond the modelled noise counted as
/// white; with the Cramer-Rao bound of the torque noise alone (out->cramer_rao_std).
Eigen::MatrixXd score_sandwich(const Fit& f, const FreeSet& fs, const Analysis& an,
                               IdentifyResult* out) {
  const Eigen::MatrixXd& Jf = fs.J;
  Eigen::MatrixXd S =
      detail::score_covariance(Jf, an.sens, f.noise, f.cond.log.size()) + fs.s2 * fs.Hp;
  // residual beyond the modelled noise (model mismatch, unmodelled noise) counted as white
  for (int j = 0; j < kActuators; ++j) {
    const double excess = std::max(
        0.0, std::pow(out->rms_torque_residual[j], 2) - std::pow(out->residual_noise_floor[j], 2));
    for (int row = j; row < Jf.rows(); row += 2) {
      S += excess * Jf.row(row).transpose() * Jf.row(row);
    }
  }
  out->std_method = "errors-in-variables";
  // Cramer-Rao bound for white torque noise alone (the logged level; angle noise ignored): a
  // lower bound the reported std should approach when the rates are logged
  const double st2 = std::max(f.noise.torque[0], f.noise.torque[1]);
  if (st2 > 0) {
    const Eigen::MatrixXd Hc = Jf.transpose() * Jf / (st2 * st2) + fs.Hp / fs.s2;
    const Eigen::MatrixXd Cc = Hc.ldlt().solve(Eigen::MatrixXd::Identity(Hc.rows(), Hc.cols()));
    out->cramer_rao_std.assign(f.layout.size(), kNaN);
    for (size_t a = 0; a < fs.index.size(); ++a) {
      out->cramer_rao_std[fs.index[a]] = std::sqrt(Cc(a, a));
    }
  }
  return fs.Hinv * S * fs.Hinv;
}

void identifiability(const Eigen::MatrixXd& JtJ, const ParameterLayout& layout,
                     IdentifyResult* out) {
  const std::vector<std::string> names = layout.names();
  const int P = static_cast<int>(JtJ.rows());
  Eigen::VectorXd scale(P);
  for (int i = 0; i < P; ++i) {
    scale(i) = std::sqrt(JtJ(i, i));
    if (!(scale(i) > 0) || !std::isfinite(scale(i))) {
      out->warnings.push_back("parameter " + names[i] +
                              " has no effect on the residuals: the log does not excite it");
      scale(i) = 1;
    }
  }
  const Eigen::MatrixXd S = scale.asDiagonal().inverse() * JtJ * scale.asDiagonal().inverse();
  if (!S.allFinite()) return;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(S);
  // eigenvalues of J^T J ascending: singular values are their square roots
  for (int i = P - 1; i >= 0; --i) {
    out->singular_values.push_back(std::sqrt(std::max(0.0, es.eigenvalues()(i))));
  }
  // every direction with a condition above 100 (unit-norm columns): the smallest is reported
  // when it involves a friction or actuator term (inertial-only directions: the inertial report
  // covers them), the others when they involve an actuator term
  for (int d = 0; d < P; ++d) {
    const double ratio = out->singular_values[P - 1 - d] / out->singular_values.front();
    if (!(ratio < 1e-2)) break;
    const Eigen::VectorXd v = es.eigenvectors().col(d);
    std::string who;
    bool friction = false, motor = false;
    for (int i = 0; i < P; ++i) {
      if (!(std::abs(v(i)) > 0.3)) continue;
      who += (who.empty() ? "" : ", ") + names[i];
      friction = friction || !layout.is_inertial(i);
      motor = motor || layout.is_actuator(i);
    }
    if (d == 0 ? friction : motor) {
      out->warnings.push_back("the log cannot separate " + who +
                              " (smallest/largest scaled singular value " +
                              format_significant(ratio) + ")");
    }
  }
}

void estimates(const Fit& f, const std::vector<double>& x0_public, IdentifyResult* out) {
  const int P = f.layout.size();
  const std::vector<std::string> names = f.layout.names();
  const Eigen::MatrixXd T = to_public(f.layout);
  const Eigen::VectorXd xp = T * Eigen::Map<const Eigen::VectorXd>(f.x.data(), P);
  // to the public parameters; one is determined when every internal one it sums is
  Eigen::MatrixXd C0 = out->covariance;
  std::vector<bool> known(P);
  for (int i = 0; i < P; ++i) known[i] = std::isfinite(C0(i, i));
  for (int i = 0; i < P; ++i) {
    for (int j = 0; j < P; ++j) {
      if (!std::isfinite(C0(i, j))) C0(i, j) = 0;
    }
  }
  out->covariance = T * C0 * T.transpose();
  for (int i = 0; i < P; ++i) {
    bool ok = true;
    for (int j = 0; j < P; ++j) ok = ok && (T(i, j) == 0 || known[j]);
    if (!ok) {
      out->covariance.row(i).setConstant(kNaN);
      out->covariance.col(i).setConstant(kNaN);
    }
  }
  out->correlation = Eigen::MatrixXd::Constant(P, P, kNaN);
  for (int i = 0; i < P; ++i) {
    for (int j = 0; j < P; ++j) {
      out->correlation(i, j) =
          out->covariance(i, j) / std::sqrt(out->covariance(i, i) * out->covariance(j, j));
    }
  }
  correlation_warnings(f.layout, out->correlation, &out->warnings);
  for (int i = 0; i < P; ++i) {
    ParameterEstimate e;
    e.name = names[i];
    e.value = xp(i);
    e.std = std::sqrt(out->covariance(i, i));
    e.initial = x0_public[i];
    e.at_bound = f.x[i] <= f.layout.lower_bound(i) + 1e-12;
    judge_estimate(f.layout, i, out->converged, &e, &out->warnings);
    out->parameters.push_back(e);
  }
}

void correlation_warnings(const ParameterLayout& layout, const Eigen::MatrixXd& correlation,
                          std::vector<std::string>* warnings) {
  const std::vector<std::string> names = layout.names();
  const int P = layout.size();
  for (int i = 0; i < P; ++i) {
    for (int j = i + 1; j < P; ++j) {
      // inertial pairs: the base combinations say which the log separates
      if (layout.is_inertial(i) && layout.is_inertial(j)) continue;
      if (std::abs(correlation(i, j)) > 0.98) {
        warnings->push_back("strong correlation " + format_significant(correlation(i, j)) +
                            " between " + names[i] + " and " + names[j]);
      }
    }
  }
}

void judge_estimate(const ParameterLayout& layout, int i, bool converged, ParameterEstimate* e,
                    std::vector<std::string>* warnings) {
  const bool static_group = layout.static_as_excess && i < layout.friction_size() &&
                            layout.group(i / layout.per_group()) == Coefficient::kStaticCoulomb;
  if (e->at_bound) {
    warnings->push_back(
        e->name + " is at its bound" +
        (static_group ? " static_coulomb = coulomb (static friction cannot be below kinetic)"
                      : " " + format_significant(layout.lower_bound(i))) +
        ": its std is not meaningful (not reported); the log may not support this law or "
        "coefficient");
    e->std = kNaN;
  } else if (!(e->std > 0) || !std::isfinite(e->std)) {
    if (converged) warnings->push_back("std of " + e->name + " not determined");
    e->std = kNaN;
  } else if (e->std > std::abs(e->value) && !layout.is_inertial(i)) {
    // the value is not repeated: a later stage (the smoothing-bias correction) may move it
    warnings->push_back(e->name + " is poorly determined (std " + format_significant(e->std) +
                        ", more than its value)");
  }
}

void analyse(const Fit& f, const std::vector<double>& x0_public,
             const ceres::Solver::Summary& summary, Analysis* an, IdentifyResult* out) {
  const int P = f.layout.size();
  out->residual_sigma =
      std::sqrt(2.0 * summary.final_cost / f.cost_weight / std::max(1, summary.num_residuals - P));
  f.method->residual_levels(f, *an, out);
  const Eigen::MatrixXd Hp = prior_information(f);
  covariance(f, Hp, an, out);
  const Eigen::MatrixXd Tinv = to_public(f.layout).inverse();
  identifiability(Tinv.transpose() * (an->J.transpose() * an->J + Hp) * Tinv, f.layout, out);
  estimates(f, x0_public, out);
  if (f.layout.inertia) inertial_stage(f, an->J, out);
}

Eigen::MatrixXd window_covariance(const std::vector<int>& sizes, const Eigen::MatrixXd& Jf,
                                  const std::vector<double>& r, IdentifyResult* out) {
  const Eigen::VectorXd rv = Eigen::Map<const Eigen::VectorXd>(r.data(), r.size());
  const detail::BlockCovariance bc = detail::block_sandwich(Jf, rv, sizes);
  if (bc.covariance.size() == 0) {
    out->warnings.push_back("output error: " + std::to_string(sizes.size()) +
                            " windows are too few to estimate the correlated residuals' "
                            "covariance: standard deviations not given (use a longer log or a "
                            "shorter --window)");
    return {};
  }
  const auto [lo, hi] = std::minmax_element(bc.inflation.begin(), bc.inflation.end());
  out->std_method = "window-sandwich";
  // the variance is estimated from G independent windows: Student's t with G - 1 degrees of
  // freedom for the 95 % intervals (the cluster-robust standard; 2.09 for 20 windows)
  out->ci_dof = bc.blocks - 1;
  out->ci_quantile = detail::t_quantile_975(out->ci_dof);
  out->std_detail = "block sandwich over the residuals of " + std::to_string(bc.blocks) +
                    " windows (correlated within a window, independent between windows): " +
                    format_significant(*lo) + "-" + format_significant(*hi) +
                    " times the std that treats the angle residuals as independent";
  if (bc.blocks < kFewWindows) {
    out->warnings.push_back("output error: the std come from the residuals of only " +
                            std::to_string(bc.blocks) +
                            " windows and are themselves uncertain (a longer log, or a shorter "
                            "--window, gives more)");
  }
  return bc.covariance;
}

std::string structure_warning(int j, double rms, double floor, double torque_noise,
                              bool from_noise) {
  const double ratio = rms / floor;
  if (!(ratio > kStructureRatio)) return "";
  return "tau" + std::to_string(j + 1) + " residual rms " + format_significant(rms) + " N m is " +
         format_significant(ratio) + " times the noise floor " + format_significant(floor) +
         " N m (" +
         (from_noise ? "torque noise " + format_significant(torque_noise) +
                           " N m with the sensor noise propagated through the rates"
                     : "0.1 % of the rms logged torque, the log being nearly noise-free") +
         "): the residual has structure the fitted law (or the estimated rates) cannot "
         "explain; see fig_residual_vs_rate.png";
}

void torque_residual_levels(const Fit& f, const std::vector<double>& r,
                            const std::vector<detail::Sensitivity>& sens, IdentifyResult* out) {
  rms_pair(r, out->rms_torque_residual);
  double noises[2], floors[2];
  noise_floor(f, sens, out->residual_noise_floor, noises, floors);
  for (int j = 0; j < kActuators; ++j) {
    const std::string w =
        structure_warning(j, out->rms_torque_residual[j], out->residual_noise_floor[j],
                          f.noise.torque[j], noises[j] >= floors[j]);
    if (!w.empty()) out->warnings.push_back(w);
  }
}

}  // namespace fivebar::identification::stages
