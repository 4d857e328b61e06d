// The four-bar's covariance (identify_four_bar.cc's stage after the fit): the five-bar's
// errors-in-variables sandwich over the crank's sensors (noise_model.h), each std raised to at
// least the sandwich's over blocks of the rate filter's window, the prior's rows of group
// inertia as pseudo-observations; and the estimates with their Wald intervals.
#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "covariance.h"
#include "four_bar_fit.h"
#include "inertia.h"
#include "mechanism_stages.h"
#include "setup_shared.h"

namespace fivebar::identification::four_bar {

void scaled_singular_values(const Eigen::MatrixXd& J, IdentifyResult* out) {
  Eigen::MatrixXd Js = J;
  for (int i = 0; i < J.cols(); ++i) Js.col(i) /= std::max(1e-300, J.col(i).norm());
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Js);
  for (int i = 0; i < svd.singularValues().size(); ++i) {
    out->singular_values.push_back(svd.singularValues()(i));
  }
}

/// The residual's sensitivities to the sensor noise at used sample u (log index i), in the noise
/// model's form (noise_model.h): channel 0 the crank angle's noise over the filter's window
/// through the estimated rate (taps d1, window from log index lo) and acceleration (taps d2) and,
/// at i, the angle itself; channel 2 a logged rate's noise at i. D: kinematic_jacobian's.
detail::Sensitivity noise_sensitivity(const FourBarFit& f, const IdentifyResult& out, int i, int lo,
                                      const std::vector<double>& d1, const std::vector<double>& d2,
                                      const Eigen::Matrix<double, 2, 6>& D) {
  detail::Sensitivity s;
  // r = tau1 - M1: d r / d theta1, omega1, alpha1
  const double dth = -D(0, 0), dw = -D(0, 2), da = -D(0, 4);
  s.sigma[0] = f.noise.angle[0];
  if (out.accels_estimated) {
    s.lo[0] = lo;
    for (size_t r = 0; r < d2.size(); ++r) {
      const double c = (out.rates_estimated ? dw * d1[r] : 0.0) + da * d2[r] +
                       (lo + static_cast<int>(r) == i ? dth : 0.0);
      s.coef[0].push_back(Eigen::Vector2d(c, 0.0));
    }
  } else {
    s.lo[0] = i;
    s.coef[0].push_back(Eigen::Vector2d(dth, 0.0));
  }
  if (!out.rates_estimated) {
    s.lo[2] = i;
    s.sigma[2] = f.noise.rate[0];
    s.coef[2].push_back(Eigen::Vector2d(dw, 0.0));
  }
  return s;
}

/// The errors-in-variables score covariance J^T Sigma J of the five-bar's inverse dynamics
/// (detail::score_covariance): the torque noise at every sample, each angle noise sample
/// through every residual whose filter window holds it (the rates and accelerations estimated
/// from the angles), a logged rate's noise at its sample, and the residual beyond that modelled
/// noise counted as white. Empty when a kinematic Jacobian cannot be formed.
Eigen::MatrixXd score_covariance(const FourBarFit& f, const Eigen::MatrixXd& J,
                                 const IdentifyResult& out) {
  const int m = static_cast<int>(J.rows()), P = static_cast<int>(J.cols());
  const TorqueLog& L = f.cond.log;
  int lo_mid = 0;
  std::vector<double> d1, d2;
  const int mid = L.size() / 2;  // a centred window: on the uniform grid all have its taps
  if (out.accels_estimated) savitzky_golay_taps(L.t, mid, f.sg, &lo_mid, &d1, &d2);
  Eigen::MatrixXd J2 = Eigen::MatrixXd::Zero(2 * m, P);
  std::vector<detail::Sensitivity> sens(m);
  for (int u = 0; u < m; ++u) {
    Eigen::Matrix<double, 2, 6> D;
    double M1 = 0;
    if (!kinematic_jacobian(f, f.x.data(), f.samples[u], &D, &M1)) return {};
    const int i = f.index[u];
    sens[u] = noise_sensitivity(f, out, i, i + lo_mid - mid, d1, d2, D);
    J2.row(2 * u) = J.row(u);
  }
  detail::SensorNoise noise;
  noise.torque[0] = f.noise.torque[0];
  Eigen::MatrixXd S = detail::score_covariance(J2, sens, noise, L.size());
  const double excess = std::max(
      0.0, std::pow(out.rms_torque_residual[0], 2) - std::pow(out.residual_noise_floor[0], 2));
  return S + excess * J.transpose() * J;
}

/// The block sizes of a sandwich: samples whose filter windows overlap share their rate errors,
/// so consecutive runs of 2 hw + 1 log samples form a block (one sample each when the
/// accelerations are logged); the rows after the samples' (the inertial prior's) one each.
std::vector<int> block_sizes(const FourBarFit& f, int rows) {
  std::vector<int> sizes;
  const int span = 2 * f.hw + 1;
  int start = -1;
  for (int i : f.index) {
    if (start < 0 || i - start >= span) {
      sizes.push_back(0);
      start = i;
    }
    ++sizes.back();
  }
  sizes.resize(sizes.size() + std::max(0, rows - static_cast<int>(f.index.size())), 1);
  return sizes;
}

/// The errors-in-variables covariance `C` with each variance raised to at least the block
/// sandwich's (its correlations kept). The noise model counts the residual beyond the sensors'
/// noise as white; where that excess is correlated over the filter's window (the smoothing
/// error of a double rocker's estimated accelerations, half-window 22 samples) the std were half
/// the estimates' spread (6 s logs of a non-Grashof four-bar, 15 seeds: 5 and 3 of 15 truths
/// inside), and the block sandwich sees it (14 and 14). Where the excess is white the block
/// sandwich is the noisier of the two, and the larger std is kept.
Eigen::MatrixXd at_least_block_sandwich(const FourBarFit& f, const Eigen::MatrixXd& J,
                                        const std::vector<double>& r, Eigen::MatrixXd C) {
  const Eigen::VectorXd rv = Eigen::Map<const Eigen::VectorXd>(r.data(), r.size());
  const Eigen::MatrixXd Cb =
      detail::block_sandwich(J, rv, block_sizes(f, static_cast<int>(J.rows()))).covariance;
  if (Cb.rows() != C.rows() || !Cb.allFinite()) return C;
  Eigen::VectorXd d(C.rows());
  for (int i = 0; i < C.rows(); ++i) {
    d(i) = C(i, i) > 0 ? std::max(1.0, std::sqrt(Cb(i, i) / C(i, i))) : 1.0;
  }
  return d.asDiagonal() * C * d.asDiagonal();
}

/// Whether the information H is numerically singular (the five-bar's rank test, well_conditioned):
/// a direction the log does not determine at all, as the sensor offset and the motor's Coulomb
/// friction of a crank that turns one way.
bool rank_deficient(const Eigen::MatrixXd& H) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(H);
  const double emax = es.eigenvalues().maxCoeff(), emin = es.eigenvalues().minCoeff();
  return !(emax > 0 && emin > 1e-14 * emax && H.allFinite());
}

/// The covariance of the parameters, those at a bound included (the direction a bound holds keeps
/// its uncertainty in the others' std; a parameter at its bound reports none, estimates): the
/// errors-in-variables sandwich (score_covariance: the rates' noise enters the reactions and the
/// friction's sign terms), or s^2 (J^T J)^-1 with --classical-std; the singular values of the
/// scaled Jacobian. *Hinv: (J^T J)^-1, the profile intervals' noise scale. With the actuator group
/// a rank-deficient information leaves every std undetermined and the fit not to be used (the
/// five-bar's rule). Per-joint
/// crank-rocker logs (10 s, angles only, seeds 1-10): the intervals hold 74 of 80 truths. The
/// sandwich's meat is the noise model's, not the residuals' (a sandwich over blocks of one filter
/// window: the same std on average at 300 Hz, but varying 15 % from log to log where the slip
/// reversals leave a few windows between them, which widened the errors' spread in its std).
void covariance(FourBarFit& f, ceres::Problem* problem, IdentifyResult* out,
                Eigen::MatrixXd* Hinv) {
  const int P = f.layout.size();
  std::vector<double> r;
  Eigen::MatrixXd J;
  out->covariance = Eigen::MatrixXd::Constant(P, P, kNaN);
  *Hinv = out->covariance;
  ceres::CRSMatrix crs;
  if (!stages::raw_residuals(problem, &r, &crs)) return;
  J = stages::dense(crs, P);
  // the samples' rows, then (group inertia) the prior's: pseudo-observations of noise level
  // prior_scale, in the information and, as that noise, in the score
  const int m = static_cast<int>(f.samples.size());
  const Eigen::MatrixXd Jd = J.topRows(m), Jp = J.bottomRows(J.rows() - m);
  const std::vector<double> rd(r.begin(), r.begin() + m);
  out->rms_torque_residual[0] = rms(rd);
  out->residual_sigma = std::sqrt(rms(rd) * rms(rd) * m / std::max(1, m - P));
  if (f.layout.actuator) {  // the five-bar's report: which actuator terms the log cannot separate
    const Eigen::MatrixXd Jpub = J * stages::to_public(f.layout).inverse();
    stages::identifiability(Jpub.transpose() * Jpub, f.layout, out);
  } else {
    scaled_singular_values(Jd, out);
  }
  if (!out->converged) return;
  Eigen::MatrixXd C;
  const Eigen::MatrixXd H = J.transpose() * J;
  if (f.layout.actuator && rank_deficient(H)) {  // as the five-bar's fit: no std, not to be used
    out->warnings.push_back("covariance could not be computed (Jacobian rank deficient)");
    if (out->unusable.empty()) {
      out->unusable =
          "the covariance could not be computed (the log does not determine the "
          "free coefficients apart): the estimates have no std";
    }
    return;
  }
  const Eigen::MatrixXd Hf = H.ldlt().solve(Eigen::MatrixXd::Identity(H.rows(), H.cols()));
  if (f.opt->errors_in_variables) {
    Eigen::MatrixXd S = score_covariance(f, Jd, *out);
    if (S.size() > 0) {
      if (Jp.rows() > 0) S += f.prior_scale * f.prior_scale * Jp.transpose() * Jp;
      f.noise_covariance = Hf * S * Hf;
      C = at_least_block_sandwich(f, J, r, f.noise_covariance);
      out->std_method = "errors-in-variables";
      out->std_detail =
          "the sensors' noise through the model, each std at least the sandwich's "
          "over blocks of " +
          std::to_string(2 * f.hw + 1) + " samples (the rate filter's window)";
    }
  }
  if (C.size() == 0) {
    C = out->residual_sigma * out->residual_sigma * Hf;
    out->std_method = "residual-variance";
  }
  out->covariance = C;
  *Hinv = Hf;
  if (f.layout.inertia) {
    const int off = f.layout.inertia_offset(), n = f.layout.inertial_size();
    const std::vector<double> pi(f.x.begin() + off, f.x.begin() + off + n);
    detail::inertial_stage(Jd.middleCols(off, n), f.prior, f.prior_scale, pi,
                           C.block(off, off, n, n), f.opt->inertia_prior, out);
  }
}

/// Estimates, correlation and Wald intervals (value +- ci_quantile std) of the public parameters
/// (to_public: Stribeck's static_coulomb = coulomb + the fitted excess); a parameter at its
/// bound, or made of one (static_coulomb = coulomb), has no std. The five-bar's warnings on an
/// estimate (judge_estimate), but not its strong-correlation warning: a crank that turns one way
/// correlates coulomb and viscous beyond 0.98 on most clean 3 s logs, which their std says.
void estimates(const FourBarFit& f, const std::vector<double>& x0, IdentifyResult* out) {
  const int P = f.layout.size();
  const std::vector<std::string> names = f.layout.names();
  const Eigen::MatrixXd T = stages::to_public(f.layout);
  const Eigen::VectorXd x = T * Eigen::Map<const Eigen::VectorXd>(f.x.data(), P);
  std::vector<char> bound(P, 0);  // public i depends on an internal parameter at its bound
  for (int i = 0; i < P; ++i) {
    for (int j = 0; j < P; ++j) {
      const bool off =
          f.x[j] > f.layout.lower_bound(j) + 1e-12 && std::isfinite(out->covariance(j, j));
      if (T(i, j) != 0 && !off) bound[i] = 1;
    }
  }
  const Eigen::MatrixXd C = T * out->covariance.unaryExpr([](double v) {
    return std::isfinite(v) ? v : 0.0;
  }) * T.transpose();
  out->correlation = Eigen::MatrixXd::Constant(P, P, kNaN);
  for (int i = 0; i < P; ++i) {
    ParameterEstimate e;
    e.name = names[i];
    e.value = x[i];
    e.initial = x0[i];
    e.at_bound = bound[i] && !(f.x[i] > f.layout.lower_bound(i) + 1e-12);
    e.std = !bound[i] && C(i, i) > 0 ? std::sqrt(C(i, i)) : kNaN;
    stages::judge_estimate(f.layout, i, out->converged, &e, &out->warnings);
    if (std::isfinite(e.std)) {
      e.ci_low = e.value - out->ci_quantile * e.std;
      e.ci_high = e.value + out->ci_quantile * e.std;
      e.ci_method = "wald";
    }
    out->parameters.push_back(e);
    for (int j = 0; j < P; ++j) {
      const double d = std::sqrt(C(i, i) * C(j, j));
      if (!bound[i] && !bound[j] && d > 0) out->correlation(i, j) = C(i, j) / d;
    }
  }
}

}  // namespace fivebar::identification::four_bar
