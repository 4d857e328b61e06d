// Smoothing bias of the data-driven window: the window limited by its predicted bias, and the
// bias taken off the estimates.
#include "identify_stages.h"

namespace fivebar::identification::stages {

namespace {

// ---- the smoothing bias of the data-driven window ----

/// The reconstruction of the motion for the bias prediction reaches this many times the residual
/// rule's half-window each side (the polynomial of degree order + kReconExtra then averages the
/// angle noise far below the filter's own noise, while following the motion over the filter's
/// span)
constexpr double kReconSpan = 2.0;

/// The inputs of the bias prediction at the preliminary fit (f.x, f.samples): the Jacobians, and
/// the motion's high-order terms from local polynomials over +-reach samples, cut short (not
/// below +-min_half) where they would span a slip reversal (the motion is not smooth across it).
detail::BiasInputs bias_inputs(const Fit& f, int reach, int min_half) {
  const TorqueLog& log = f.cond.log;
  const int n = log.size(), P = f.layout.size();
  const double dt = log.duration() / std::max(1, n - 1);
  detail::BiasInputs in;
  in.index = f.index;
  ceres::Problem problem;
  std::vector<double> x = f.x;
  add_inverse_dynamics_terms(f.scene, f.layout, f.samples, f.eval, Loss::kNone, 1, x.data(),
                             &problem);
  ceres::CRSMatrix crs;
  std::vector<double> r;
  if (problem.NumResidualBlocks() > 0 && raw_residuals(&problem, &r, &crs)) in.J = dense(crs, P);
  for (size_t u = 0; u < f.samples.size(); ++u) {
    Eigen::Matrix<double, 2, 6> D;
    if (!detail::kinematic_jacobian(f.scene, f.layout, f.x.data(), f.samples[u], f.eval, &D)) {
      D.setZero();
    }
    in.D.push_back(D);
    const int i = f.index[u];
    int a = std::max(0, i - reach), b = std::min(n - 1, i + reach);
    while (!f.reversals.empty() && a < i - min_half && f.reversals[i] - f.reversals[a] > 0) ++a;
    while (!f.reversals.empty() && b > i + min_half && f.reversals[b] - f.reversals[i] > 0) --b;
    in.terms[0].push_back(detail::high_order_terms(log.t, log.theta1, i, a, b, dt, f.sg.order));
    in.terms[1].push_back(detail::high_order_terms(log.t, log.theta2, i, a, b, dt, f.sg.order));
  }
  in.Hp = prior_information(f);
  in.s2 = f.prior_scale * f.prior_scale;
  in.T = to_public(f.layout);
  in.friction_size = f.layout.friction_size();
  in.source = f.source;
  in.noise = f.noise;
  return in;
}

}  // namespace

void limit_smoothing_bias(Fit* f, IdentifyResult* out) {
  const TorqueLog& log = f->cond.log;
  const int n = log.size();
  if (f->source != detail::RateSource::kFromAngles || f->sg.order != f->opt->sg.order || n < 2) {
    return;
  }
  const double dt = log.duration() / (n - 1);
  const std::vector<int> cand = window_candidates(n, dt, f->sg.order);
  const int rule = static_cast<int>(
      std::find(cand.begin(), cand.end(), sg_half_window(f->sg, dt)) - cand.begin());
  if (rule < 1 || rule >= static_cast<int>(cand.size())) return;
  const detail::BiasInputs in = bias_inputs(*f, std::lround(kReconSpan * cand[rule]), cand[1]);
  if (in.J.rows() != 2 * static_cast<int>(f->samples.size())) return;
  std::string table;
  int chosen = -1;
  Eigen::VectorXd at_rule, at_chosen;
  for (int k = rule; k >= 1 && chosen < 0; --k) {
    const int m = cand[k];
    std::vector<char> keep(f->index.size(), 0);
    for (size_t u = 0; u < keep.size(); ++u) {
      const int i = f->index[u];
      keep[u] = i - m >= 0 && i + m < n && !spans_reversal(*f, i, m);
    }
    SgOptions sg = f->sg;
    sg.half_window_s = m * dt;
    Eigen::VectorXd bias, std;
    if (!detail::smoothing_bias(log.t, in, keep, sg, &bias, &std)) break;
    double worst = 0;
    for (int p = 0; p < bias.size(); ++p) {
      if (std(p) > 0) worst = std::max(worst, std::abs(bias(p)) / std(p));
    }
    table += (table.empty() ? "" : ", ") + std::to_string(m) + ": " + format_significant(worst);
    if (k == rule) at_rule = bias;
    if (worst <= kBiasFraction) chosen = k, at_chosen = bias;
  }
  if (table.empty()) return;
  const int pick = chosen < 0 ? rule : chosen;
  f->sg.half_window_s = cand[pick] * dt;
  f->smoothing_bias = chosen < 0 ? at_rule : at_chosen;
  out->window_choice +=
      "; then half-window " + std::to_string(cand[pick]) + " samples, " +
      (chosen < 0 ? "the rule's (no window down to " + std::to_string(cand[1]) +
                        " samples keeps it within " + format_significant(kBiasFraction) + " std)"
                  : "the largest up to the rule's whose predicted smoothing bias is within " +
                        format_significant(kBiasFraction) + " std of every friction coefficient") +
      " (predicted |bias| / std by half-window, the motion's higher terms from local polynomials "
      "of degree " +
      std::to_string(f->sg.order + detail::kReconExtra) + " over +-" +
      std::to_string(std::lround(kReconSpan * cand[rule])) + " samples: " + table + ")";
}

void correct_smoothing_bias(Fit* f, IdentifyResult* out) {
  const Eigen::VectorXd& b = f->smoothing_bias;
  const int P = f->layout.size();
  if (b.size() == 0 || static_cast<int>(out->parameters.size()) < b.size()) return;
  Eigen::VectorXd shift = Eigen::VectorXd::Zero(P);
  for (int p = 0; p < b.size(); ++p) {
    const ParameterEstimate& e = out->parameters[p];
    if (!e.at_bound && std::isfinite(e.std) && std::isfinite(b(p))) shift(p) = b(p);
  }
  if (shift.isZero(0.0)) return;
  const Eigen::MatrixXd T = to_public(f->layout);
  const Eigen::VectorXd dx = T.inverse() * shift;
  Eigen::VectorXd x_old(P), x_new(P);
  for (int i = 0; i < P; ++i) {
    x_old(i) = f->x[i];
    f->x[i] = std::max(f->layout.lower_bound(i), f->x[i] - dx(i));
    x_new(i) = f->x[i];
  }
  const Eigen::VectorXd applied = T * (x_old - x_new);  // the shift each public value took
  std::string list;
  for (int p = 0; p < b.size(); ++p) {
    if (shift(p) == 0 && applied(p) == 0) continue;
    ParameterEstimate& e = out->parameters[p];
    e.value -= applied(p);
    e.ci_low -= applied(p);  // an open side (+-inf) stays open
    e.ci_high -= applied(p);
    list += (list.empty() ? "" : ", ") + e.name + " " + format_significant(-applied(p));
    if (std::abs(applied(p) - shift(p)) > 1e-12 * std::abs(shift(p))) {
      list += " (limited by its bound: predicted " + format_significant(-shift(p)) + ")";
    }
  }
  if (list.empty()) return;
  out->window_choice += "; the predicted bias at it taken off the estimates (" + list + ")";
}

}  // namespace fivebar::identification::stages
