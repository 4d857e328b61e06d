// Smoothing bias of the data-driven window, for any mechanism (mechanism_stages.h): the window
// limited by its predicted bias, and the bias taken off the estimates; the five-bar's inputs of
// the prediction.
#include "identify_stages.h"

namespace fivebar::identification::stages {

namespace {

// ---- the smoothing bias of the data-driven window ----

/// The reconstruction of the motion for the bias prediction reaches this many times the residual
/// rule's half-window each side (the polynomial of degree order + kReconExtra then averages the
/// angle noise far below the filter's own noise, while following the motion over the filter's
/// span)
constexpr double kReconSpan = 2.0;

}  // namespace

/// At the preliminary fit (f.x, f.samples): the residual's and the kinematic Jacobians, the
/// motion's higher terms cut short where they would span a slip reversal (the motion is not
/// smooth across it).
detail::BiasInputs FiveBarWindowFit::bias_inputs(int reach, int min_half, int order) const {
  const Fit& f = f_;
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
    in.terms[0].push_back(detail::high_order_terms(log.t, log.theta1, i, a, b, dt, order));
    in.terms[1].push_back(detail::high_order_terms(log.t, log.theta2, i, a, b, dt, order));
  }
  in.Hp = prior_information(f);
  in.s2 = f.prior_scale * f.prior_scale;
  in.T = to_public(f.layout);
  in.friction_size = f.layout.friction_size();
  in.source = f.source;
  in.noise = f.noise;
  return in;
}

namespace {

/// The largest predicted |bias| / std over the coefficients (0 where the std is not > 0).
double worst_ratio(const Eigen::VectorXd& bias, const Eigen::VectorXd& std) {
  double worst = 0;
  for (int p = 0; p < bias.size(); ++p) {
    if (std(p) > 0) worst = std::max(worst, std::abs(bias(p)) / std(p));
  }
  return worst;
}

/// The samples of the fit whose window of half-width m is centred in the log and spans no slip
/// reversal.
std::vector<char> centred_samples(const WindowFit& w, int m) {
  const std::vector<int>& index = w.index();
  const int n = w.log().size();
  std::vector<char> keep(index.size(), 0);
  for (size_t u = 0; u < keep.size(); ++u) {
    const int i = index[u];
    keep[u] = i - m >= 0 && i + m < n && !w.spans_reversal(i, m);
  }
  return keep;
}

}  // namespace

void limit_smoothing_bias(const WindowFit& w, int given_order, SgOptions* sg_fit,
                          Eigen::VectorXd* bias_kept, std::string* choice) {
  const TorqueLog& log = w.log();
  const std::vector<int>& index = w.index();
  const int n = log.size();
  if (w.source() != detail::RateSource::kFromAngles || sg_fit->order != given_order || n < 2) {
    return;
  }
  const double dt = log.duration() / (n - 1);
  const std::vector<int> cand = window_candidates(n, dt, sg_fit->order);
  const int rule = static_cast<int>(
      std::find(cand.begin(), cand.end(), sg_half_window(*sg_fit, dt)) - cand.begin());
  if (rule < 1 || rule >= static_cast<int>(cand.size())) return;
  const detail::BiasInputs in =
      w.bias_inputs(std::lround(kReconSpan * cand[rule]), cand[1], sg_fit->order);
  if (in.J.rows() != 2 * static_cast<int>(index.size())) return;
  std::string table;
  int chosen = -1;
  Eigen::VectorXd at_rule, at_chosen;
  for (int k = rule; k >= 1 && chosen < 0; --k) {
    const int m = cand[k];
    SgOptions sg = *sg_fit;
    sg.half_window_s = m * dt;
    Eigen::VectorXd bias, std;
    if (!detail::smoothing_bias(log.t, in, centred_samples(w, m), sg, &bias, &std)) break;
    const double worst = worst_ratio(bias, std);
    table += (table.empty() ? "" : ", ") + std::to_string(m) + ": " + format_significant(worst);
    if (k == rule) at_rule = bias;
    if (worst <= kBiasFraction) chosen = k, at_chosen = bias;
  }
  if (table.empty()) return;
  const int pick = chosen < 0 ? rule : chosen;
  sg_fit->half_window_s = cand[pick] * dt;
  *bias_kept = chosen < 0 ? at_rule : at_chosen;
  *choice +=
      "; then half-window " + std::to_string(cand[pick]) + " samples, " +
      (chosen < 0 ? "the rule's (no window down to " + std::to_string(cand[1]) +
                        " samples keeps it within " + format_significant(kBiasFraction) + " std)"
                  : "the largest up to the rule's whose predicted smoothing bias is within " +
                        format_significant(kBiasFraction) + " std of every friction coefficient") +
      " (predicted |bias| / std by half-window, the motion's higher terms from local polynomials "
      "of degree " +
      std::to_string(sg_fit->order + detail::kReconExtra) + " over +-" +
      std::to_string(std::lround(kReconSpan * cand[rule])) + " samples: " + table + ")";
}

BiasWalk walk_window_by_bias(int K, int start, const std::function<bool(int, double*)>& worst) {
  BiasWalk w;
  w.ratio.assign(std::max(0, K), -1.0);
  if (K < 2) return w;
  // candidate k's ratio into w.ratio; false when the inputs cannot be formed
  const auto evaluate = [&](int k) { return worst(k, &w.ratio[k]); };
  const auto within = [&](int k) { return w.ratio[k] <= kBiasFraction; };
  start = std::clamp(start, 1, K - 1);
  if (!evaluate(start)) return w;
  int chosen = -1;
  if (within(start)) {
    chosen = start;
    for (int k = start - 1; k >= 1; --k) {
      if (!evaluate(k)) return w;
      if (!within(k)) break;
      chosen = k;
    }
  } else {
    double least = std::isnan(w.ratio[start]) ? INFINITY : w.ratio[start];
    for (int k = start + 1; k < K && chosen < 0; ++k) {
      if (!evaluate(k)) return w;
      if (within(k)) chosen = k;
      if (w.ratio[k] < least) least = w.ratio[k];
      // the noise's bias falls and the smoothing's grows with the window: past the least, once
      // it is twice the least, the larger windows only add
      if (w.ratio[k] > 2 * std::max(least, kBiasFraction)) break;
    }
  }
  int pick = chosen;
  for (int k = 1; k < K; ++k) {
    if (w.ratio[k] < 0 || std::isnan(w.ratio[k])) continue;
    if (pick < 0 || (chosen < 0 && w.ratio[k] < w.ratio[pick])) pick = k;
  }
  w.pick = pick;
  w.within = chosen >= 0;
  return w;
}

// The smallest candidate within kBiasFraction, found by a walk from the filter's window as given
// (walk_window_by_bias: the predicted bias falls with the window as far as the noise's
// dominates). The motion's higher terms over +-kReconSpan times each window. (Over 30 seeded
// crank-rocker logs at angle noise 1e-5 rad, keeping the largest window within kBiasFraction
// instead chose 12-41 samples and covered 86.7 %, the smallest 8-15 samples and 98.3 %.)
void choose_window_by_bias(const WindowFit& w, SgOptions* sg_fit, Eigen::VectorXd* bias_kept,
                           std::string* choice) {
  const int n = w.log().size();
  const double dt = w.log().duration() / std::max(1, n - 1);
  const std::vector<int> cand = window_candidates(n, dt, sg_fit->order);
  const int K = static_cast<int>(cand.size());
  *choice = "default: half-window " + std::to_string(sg_half_window(*sg_fit, dt)) +
            " samples (no window's bias could be predicted)";
  if (w.source() != detail::RateSource::kFromAngles || n < 2 || K < 2) return;
  std::vector<Eigen::VectorXd> biases(K);
  // candidate k's predicted |bias| / std; false when the inputs cannot be formed
  const auto evaluate = [&](int k, double* worst) {
    const detail::BiasInputs in =
        w.bias_inputs(std::lround(kReconSpan * cand[k]), cand[1], sg_fit->order);
    if (in.J.rows() != 2 * static_cast<int>(w.index().size())) return false;
    SgOptions sg = *sg_fit;
    sg.half_window_s = cand[k] * dt;
    const detail::NoiseBias noise = w.noise_bias(sg);
    Eigen::VectorXd std;
    const bool ok = noise.shift.size() == w.index().size() &&
                    noise.score.size() == w.index().size() &&
                    detail::smoothing_bias(w.log().t, in, centred_samples(w, cand[k]), sg,
                                           &biases[k], &std, &noise);
    *worst = ok ? worst_ratio(biases[k], std) : std::numeric_limits<double>::quiet_NaN();
    return true;
  };
  const int start = static_cast<int>(
      std::lower_bound(cand.begin(), cand.end(), sg_half_window(*sg_fit, dt)) - cand.begin());
  const BiasWalk walk = walk_window_by_bias(K, start, evaluate);
  if (walk.pick < 0) return;
  std::string table;
  for (int k = 1; k < K; ++k) {
    const double r = walk.ratio[k];
    if (r < 0 || std::isnan(r)) continue;
    table += (table.empty() ? "" : ", ") + std::to_string(cand[k]) + ": " + format_significant(r);
  }
  const int pick = walk.pick;
  sg_fit->half_window_s = cand[pick] * dt;
  *bias_kept = biases[pick];
  *choice =
      "data-driven: half-window " + std::to_string(cand[pick]) + " samples (" +
      format_significant(cand[pick] * dt * 1e3) + " ms), " +
      (!walk.within
           ? "the one of least predicted bias (none keeps it within " +
                 format_significant(kBiasFraction) + " std)"
           : "the smallest whose predicted bias is within " + format_significant(kBiasFraction) +
                 " std of every friction coefficient") +
      " (the smoothing bias and the noise's through the reactions, errors in variables; "
      "predicted |bias| / std by half-window, the motion's higher terms from local polynomials of "
      "degree " +
      std::to_string(sg_fit->order + detail::kReconExtra) + " over +-" +
      format_significant(kReconSpan) + " half-windows: " + table + ")";
}

void correct_smoothing_bias(const ParameterLayout& layout, const Eigen::VectorXd& b,
                            std::vector<double>* x, IdentifyResult* out) {
  const int P = layout.size();
  if (b.size() == 0 || static_cast<int>(out->parameters.size()) < b.size()) return;
  Eigen::VectorXd shift = Eigen::VectorXd::Zero(P);
  for (int p = 0; p < b.size(); ++p) {
    const ParameterEstimate& e = out->parameters[p];
    if (!e.at_bound && std::isfinite(e.std) && std::isfinite(b(p))) shift(p) = b(p);
  }
  if (shift.isZero(0.0)) return;
  const Eigen::MatrixXd T = to_public(layout);
  const Eigen::VectorXd dx = T.inverse() * shift;
  Eigen::VectorXd x_old(P), x_new(P);
  for (int i = 0; i < P; ++i) {
    x_old(i) = (*x)[i];
    (*x)[i] = std::max(layout.lower_bound(i), (*x)[i] - dx(i));
    x_new(i) = (*x)[i];
  }
  const Eigen::VectorXd applied = T * (x_old - x_new);  // the shift each public value took
  std::string list;
  for (int p = 0; p < b.size(); ++p) {
    if (shift(p) == 0 && applied(p) == 0) continue;
    ParameterEstimate& e = out->parameters[p];
    e.value -= applied(p);
    // an open side (+-inf) stays open; a lower end that respected the bound (a profile interval
    // ends there) still does after the shift
    const bool within_bound = e.ci_low >= layout.lower_bound(p);
    e.ci_low -= applied(p);
    if (within_bound) e.ci_low = std::max(e.ci_low, layout.lower_bound(p));
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
