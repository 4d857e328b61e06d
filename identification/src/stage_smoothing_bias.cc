// Smoothing bias of the data-driven window, for any mechanism (mechanism_stages.h): the window
// limited by its predicted bias, and the bias taken off the estimates; the five-bar's inputs of
// the prediction.
#include <map>

#include "identify_stages.h"

namespace fivebar::identification::stages {

namespace {

// ---- the smoothing bias of the data-driven window ----

/// The noise's bias is evaluated at about this many samples of the fit (noise_bias)
constexpr int kNoiseBiasSamples = 800;

}  // namespace

void motion_terms(const Fit& f, int i, int reach, int min_half, int order, int extra,
                  std::array<Eigen::VectorXd, kDof>* terms,
                  std::array<Eigen::MatrixXd, kDof>* weights, int* lo,
                  detail::HighOrderCache* cache) {
  const TorqueLog& log = f.cond.log;
  const int n = log.size();
  const double dt = log.duration() / std::max(1, n - 1);
  int a = std::max(0, i - reach), b = std::min(n - 1, i + reach);
  while (!f.reversals.empty() && a < i - min_half && f.reversals[i] - f.reversals[a] > 0) ++a;
  while (!f.reversals.empty() && b > i + min_half && f.reversals[b] - f.reversals[i] > 0) --b;
  if (cache) {
    (*terms)[0] = cache->terms(log.theta1, i, a, b);
    (*terms)[1] = cache->terms(log.theta2, i, a, b);
  } else {
    (*terms)[0] = detail::high_order_terms(log.t, log.theta1, i, a, b, dt, order, extra);
    (*terms)[1] = detail::high_order_terms(log.t, log.theta2, i, a, b, dt, order, extra);
  }
  if (weights) {
    (*weights)[0] = (*weights)[1] =
        cache ? cache->weights(i, a, b)
              : detail::high_order_weights(log.t, i, a, b, dt, order, extra);
    *lo = a;
  }
}

/// At the preliminary fit (f.x, f.samples): the residual's and the kinematic Jacobians.
const detail::BiasInputs& FiveBarWindowFit::fit_inputs() const {
  if (fit_inputs_) return *fit_inputs_;
  const Fit& f = f_;
  const int P = f.layout.size();
  fit_inputs_ = std::make_unique<detail::BiasInputs>();
  detail::BiasInputs& in = *fit_inputs_;
  in.index = f.index;
  ceres::Problem problem;
  std::vector<double> x = f.x;
  add_inverse_dynamics_terms(f.scene, f.layout, f.samples, f.eval, Loss::kNone, 1, x.data(),
                             &problem);
  ceres::CRSMatrix crs;
  std::vector<double> r;
  if (problem.NumResidualBlocks() > 0 && raw_residuals(&problem, &r, &crs)) in.J = dense(crs, P);
  const detail::KinematicJacobians jacobian(f.scene, f.layout, f.x.data());
  for (size_t u = 0; u < f.samples.size(); ++u) {
    Eigen::Matrix<double, 2, 6> D;
    if (!jacobian(f.samples[u], f.eval, &D)) {
      D.setZero();
    }
    in.D.push_back(D);
  }
  in.Hp = prior_information(f);
  in.s2 = f.prior_scale * f.prior_scale;
  in.T = to_public(f.layout);
  in.friction_size = f.layout.friction_size();
  in.source = f.source;
  in.noise = f.noise;
  return in;
}

/// fit_inputs with the motion's higher terms (motion_terms).
detail::BiasInputs FiveBarWindowFit::bias_inputs(int reach, int min_half, int order) const {
  const Fit& f = f_;
  detail::BiasInputs in = fit_inputs();
  const TorqueLog& log = f.cond.log;
  detail::HighOrderCache cache(log.t, log.duration() / std::max(1, log.size() - 1), order);
  for (size_t u = 0; u < f.samples.size(); ++u) {
    std::array<Eigen::VectorXd, kDof> terms;
    std::array<Eigen::MatrixXd, kDof> weights;
    int lo = 0;
    motion_terms(f, f.index[u], reach, min_half, order, detail::kReconExtra, &terms, &weights, &lo,
                 &cache);
    in.terms[0].push_back(terms[0]);
    in.terms[1].push_back(terms[1]);
    in.weights[0].push_back(std::move(weights[0]));
    in.weights[1].push_back(std::move(weights[1]));
    in.recon_lo.push_back(lo);
  }
  return in;
}

bool FiveBarWindowFit::base_residual(int u, Eigen::Vector2d* r, Eigen::MatrixXd* J) const {
  const Fit& f = f_;
  if (base_ok_.size() != f.samples.size()) {
    base_ok_.assign(f.samples.size(), -1);
    base_r_.assign(f.samples.size(), Eigen::Vector2d::Zero());
    base_J_.assign(f.samples.size(), Eigen::MatrixXd());
  }
  if (base_ok_[u] < 0) {
    base_ok_[u] = sample_residual(f.scene, f.layout, f.samples[u], f.eval, f.x.data(), &base_r_[u],
                                  &base_J_[u]);
  }
  *r = base_r_[u];
  *J = base_J_[u];
  return base_ok_[u] == 1;
}

detail::NoiseBias FiveBarWindowFit::noise_bias(const SgOptions& sg) const {
  const Fit& f = f_;
  const int P = f.layout.size(), m = static_cast<int>(f.samples.size());
  detail::NoiseBias nb;
  if (f.source != detail::RateSource::kFromAngles) return nb;
  const std::array<Eigen::Vector3d, 3> axes = detail::noise_axes(f.cond.log.t, sg);
  nb.shift.assign(m, Eigen::Vector2d::Zero());
  nb.score.assign(m, Eigen::VectorXd::Zero(P));
  // the bias is a sum over the samples of a smooth function of the motion: evaluated at every
  // few samples of a long log (kNoiseBiasSamples in all), each stands for its neighbours
  const int stride = std::max(1, m / kNoiseBiasSamples);
  for (int u0 = 0; u0 < m; u0 += stride) {
    const Sample& s = f.samples[u0];
    Eigen::Vector2d r0, r1;
    Eigen::MatrixXd J0, J1;
    if (!base_residual(u0, &r0, &J0)) continue;
    Eigen::Vector2d shift = Eigen::Vector2d::Zero();
    Eigen::VectorXd score = Eigen::VectorXd::Zero(P);
    bool ok = true;
    for (int c = 0; c < kDof && ok; ++c) {
      for (int k = 0; k < 3 && ok; ++k) {
        const Eigen::Vector3d e = f.noise.angle[c] * axes[k];
        for (double side : {1.0, -1.0}) {
          Sample p = s;
          (c == 0 ? p.th1 : p.th2) += side * e(0);
          (c == 0 ? p.w1 : p.w2) += side * e(1);
          (c == 0 ? p.a1 : p.a2) += side * e(2);
          ok = sample_residual(f.scene, f.layout, p, f.eval, f.x.data(), &r1, &J1);
          if (!ok) break;
          // r = tau - M: the torques' change is -(r1 - r0), their Jacobian's -(J1 - J0)
          shift -= (r1 - r0) / 6;
          score += (J1 - J0).transpose() * (r1 - r0) / 6;
        }
      }
    }
    if (!ok) continue;
    for (int u = u0; u < std::min(m, u0 + stride); ++u) nb.shift[u] = shift, nb.score[u] = score;
  }
  return nb;
}

namespace {

/// The largest predicted |bias| / std over the coefficients (0 where the std is not > 0); with
/// `spread` (the prediction's own std), the bias and its spread in quadrature: a prediction that
/// the angle noise makes uncertain counts as a bias of that size.
double worst_ratio(const Eigen::VectorXd& bias, const Eigen::VectorXd& std,
                   const Eigen::VectorXd& spread = Eigen::VectorXd()) {
  double worst = 0;
  for (int p = 0; p < bias.size(); ++p) {
    const double b = p < spread.size() ? std::hypot(bias(p), spread(p)) : std::abs(bias(p));
    if (std(p) > 0) worst = std::max(worst, b / std(p));
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

namespace {

/// The predicted bias (the smoothing's, and the noise's where the mechanism predicts it) of the
/// filters of one order over the window candidates, each evaluated once, on demand: the
/// smoothing's where it is asked for, the noise's (the costlier) only where the bias with it is.
class WindowBias {
 public:
  /// the motion's higher terms over +-kReconSpan times the half-window `reach_half`, or the
  /// candidate's where it is larger
  WindowBias(const WindowFit& w, const SgOptions& sg, const std::vector<int>& cand, int reach_half)
      : w_(w),
        sg_(sg),
        cand_(cand),
        worst_(cand.size(), -1),
        smooth_(cand.size(), -1),
        bias_(cand.size()),
        smooth_bias_(cand.size()),
        spread_(cand.size()),
        done_(cand.size(), 0),
        noise_done_(cand.size(), 0),
        pred_(cand.size()),
        keep_(cand.size()),
        in_(cand.size(), nullptr) {
    const int n = w.log().size();
    dt_ = w.log().duration() / std::max(1, n - 1);
    reach_half_ = reach_half;
  }
  /// candidate k's largest predicted |bias| / std, the noise's included; -1: not predicted
  double worst(int k) {
    evaluate(k);
    add_noise(k);
    return worst_[k];
  }
  /// the same of the smoothing's bias alone
  double smoothing(int k) {
    evaluate(k);
    return smooth_[k];
  }
  bool within(int k) { return worst(k) >= 0 && worst(k) <= kBiasFraction; }
  const Eigen::VectorXd& bias(int k) const { return bias_[k]; }
  const Eigen::VectorXd& smoothing_bias(int k) const { return smooth_bias_[k]; }
  /// the std of candidate k's prediction from the angle noise through the reconstruction
  const Eigen::VectorXd& spread(int k) const { return spread_[k]; }
  SgOptions filter(int k) const {
    SgOptions sg = sg_;
    sg.half_window_s = cand_[k] * dt_;
    return sg;
  }
  /// "h: ratio (smoothing's ratio), ..." over the candidates evaluated ("h: - (smoothing's
  /// ratio)" where only the smoothing's was needed)
  std::string table() const {
    std::string t;
    for (size_t k = 0; k < cand_.size(); ++k) {
      if (smooth_[k] < 0 || (noise_done_[k] && worst_[k] < 0)) continue;
      t += (t.empty() ? "" : ", ") + std::to_string(cand_[k]) + ": " +
           (noise_done_[k] ? format_significant(worst_[k]) : std::string("-")) + " (" +
           format_significant(smooth_[k]) + ")";
    }
    return t;
  }

 private:
  /// the inputs of candidate k: the motion's higher terms over +-kReconSpan times the larger of
  /// its half-window and the rule's. Read over a span narrower than the filter's, the terms are
  /// noise the filter's response multiplies (a light mechanism's clean logs, rule at 7 samples:
  /// the smoothing's bias predicted at 14-16 std at 15-18 samples, where it is below 0.5)
  const detail::BiasInputs* inputs(int k) {
    const int reach = std::lround(detail::kReconSpan * std::max(reach_half_, cand_[k]));
    auto it = inputs_.find(reach);
    if (it == inputs_.end()) {
      it = inputs_.emplace(reach, w_.bias_inputs(reach, cand_.size() > 1 ? cand_[1] : 1, sg_.order))
               .first;
    }
    const bool ok = it->second.J.rows() == 2 * static_cast<int>(w_.index().size());
    return ok ? &it->second : nullptr;
  }
  /// candidate k's smoothing bias
  void evaluate(int k) {
    if (done_[k]) return;
    done_[k] = true;
    in_[k] = inputs(k);
    if (!in_[k]) return;
    const detail::BiasInputs& in = *in_[k];
    keep_[k] = centred_samples(w_, cand_[k]);
    // the smoothing's prediction, whose solve the noise's bias shares
    detail::BiasPrediction& pred = pred_[k];
    if (!detail::predict_smoothing_bias(w_.log().t, in, keep_[k], filter(k), true, &pred)) return;
    smooth_bias_[k] = pred.bias;
    spread_[k] = pred.spread;
    smooth_[k] = worst_ratio(pred.bias, pred.std, pred.spread);
  }
  /// candidate k's bias with the noise's, after its smoothing's (evaluate)
  void add_noise(int k) {
    if (noise_done_[k] || smooth_[k] < 0) return;
    noise_done_[k] = true;
    const detail::BiasInputs& in = *in_[k];
    const Eigen::VectorXd& std = pred_[k].std;
    const detail::NoiseBias noise = w_.noise_bias(filter(k));
    const size_t m = w_.index().size();
    if (noise.shift.size() != m || noise.score.size() != m) {
      bias_[k] = smooth_bias_[k], worst_[k] = smooth_[k];
    } else if (detail::noisy_bias(in, keep_[k], noise, pred_[k], &bias_[k])) {
      worst_[k] = worst_ratio(bias_[k], std, spread_[k]);
    }
    pred_[k] = detail::BiasPrediction();
  }
  const WindowFit& w_;
  SgOptions sg_;
  std::vector<int> cand_;
  std::vector<double> worst_, smooth_;
  std::vector<Eigen::VectorXd> bias_, smooth_bias_, spread_;
  std::vector<char> done_, noise_done_;
  std::vector<detail::BiasPrediction> pred_;  ///< until the noise's bias is added
  std::vector<std::vector<char>> keep_;
  std::vector<const detail::BiasInputs*> in_;
  std::map<int, detail::BiasInputs> inputs_;  ///< by reach
  int reach_half_ = 1;
  double dt_ = 1;
};

/// The candidate of least predicted bias from `from` up, while the bias falls (-1: none)
int least_bias_up(WindowBias* wb, int from, int K) {
  int pick = wb->worst(from) >= 0 ? from : -1;
  for (int k = from + 1; pick == k - 1 && k < K; ++k) {
    if (wb->worst(k) >= 0 && wb->worst(k) < wb->worst(pick)) pick = k;
  }
  return pick;
}

}  // namespace

bool predicted_biases(const WindowFit& w, const SgOptions& sg, const std::vector<int>& halves,
                      int reach_half, std::vector<Eigen::VectorXd>* bias,
                      std::vector<Eigen::VectorXd>* spread) {
  const int n = w.log().size();
  if (w.source() != detail::RateSource::kFromAngles || n < 2) return false;
  const double dt = w.log().duration() / (n - 1);
  // the walk's two smallest candidates first: the motion's terms are cut at slip reversals to
  // no fewer than the second's samples each side, as in the walk
  std::vector<int> cand = window_candidates(n, dt, sg.order);
  if (cand.size() < 2) return false;
  cand.resize(2);
  cand.insert(cand.end(), halves.begin(), halves.end());
  WindowBias wb(w, sg, cand, reach_half);
  bias->clear();
  spread->clear();
  for (size_t k = 2; k < cand.size(); ++k) {
    if (wb.worst(static_cast<int>(k)) < 0) return false;
    bias->push_back(wb.bias(static_cast<int>(k)));
    spread->push_back(wb.spread(static_cast<int>(k)));
  }
  return true;
}

void limit_smoothing_bias(const WindowFit& w, int given_order, bool rates_biased, SgOptions* sg_fit,
                          Eigen::VectorXd* bias_kept, std::string* choice, double* left,
                          Eigen::VectorXd* spread) {
  *left = 0;
  const TorqueLog& log = w.log();
  const int n = log.size();
  if (w.source() != detail::RateSource::kFromAngles || n < 2) return;
  const double dt = log.duration() / (n - 1);
  SgOptions given = *sg_fit;
  given.order = given_order;
  const std::vector<int> cand = window_candidates(n, dt, given_order);
  const int K = static_cast<int>(cand.size());
  const bool raised = sg_fit->order != given_order;
  // the order raised by the window rule: its one window, kept when within kBiasFraction (a log
  // sampled too slowly for order 5) or when every window showed bias in the residual
  if (raised && (rates_biased || K < 2)) return;
  const int rule =
      raised ? 1
             : static_cast<int>(std::find(cand.begin(), cand.end(), sg_half_window(*sg_fit, dt)) -
                                cand.begin());
  if (rule < 1 || rule >= K) return;
  std::string table;
  std::unique_ptr<WindowBias> raised_bias;
  if (raised) {
    const std::vector<int> one{cand[0], sg_half_window(*sg_fit, dt)};
    raised_bias = std::make_unique<WindowBias>(w, *sg_fit, one, one[1]);
    if (raised_bias->worst(1) < 0 || raised_bias->within(1)) return;
    table = "order " + std::to_string(sg_fit->order) + " " + raised_bias->table() + "; order " +
            std::to_string(given_order) + " ";
  }
  WindowBias wb(w, given, cand, cand[rule]);
  // the largest window up to the rule's whose smoothing bias is within kBiasFraction (else the
  // rule's); with the raised order, the second smallest
  int base = raised ? 1 : -1;
  for (int k = rule; k >= 1 && base < 0; --k) {
    if (wb.smoothing(k) < 0) break;
    if (wb.smoothing(k) <= kBiasFraction) base = k;
  }
  if (base < 0) base = rule;
  // where the noise's bias, with the smoothing's, exceeds kBiasFraction there (a heavy
  // mechanism's reactions), up from it while the predicted bias falls: the noise's bias falls as
  // the window grows, the smoothing's grows. Never down: the prediction of the noise's bias is
  // least reliable where it is largest, at the smallest windows (a light mechanism's at half-window
  // 4: +0.003 std predicted, -2.3 measured).
  const int pick = wb.within(base) ? base : least_bias_up(&wb, base, K);
  if (pick < 0) return;
  if (raised_bias && raised_bias->worst(1) <= wb.worst(pick)) {
    *left = raised_bias->worst(1);
    *bias_kept = raised_bias->bias(1);
    *spread = raised_bias->spread(1);
    *choice +=
        "; the raised order's predicted bias the least (predicted |bias| / std, the "
        "smoothing's and the noise's through the reactions (-: the smoothing's alone was "
        "needed): " +
        table + wb.table() + ")";
    return;
  }
  *sg_fit = wb.filter(pick);
  if (!wb.within(pick)) *left = wb.worst(pick);
  // within kBiasFraction at the window the smoothing's bias chose, the smoothing's alone is taken
  // off, as without the noise's prediction (the shipped paper log's estimates stay as they were)
  *bias_kept = pick == base ? wb.smoothing_bias(pick) : wb.bias(pick);
  *spread = wb.spread(pick);
  *choice +=
      "; then half-window " + std::to_string(cand[pick]) + " samples" +
      (raised ? " of order " + std::to_string(given_order) : std::string()) + ", " +
      (pick == base
           ? "the largest up to the rule's whose predicted smoothing bias is within " +
                 format_significant(kBiasFraction) + " std of every friction coefficient"
           : "the one of least predicted bias up from the largest whose smoothing bias is within " +
                 format_significant(kBiasFraction) + " std") +
      " (predicted |bias| / std by half-window, the smoothing's and the noise's through "
      "the reactions (the smoothing's alone; -: the smoothing's alone was needed), the motion's "
      "higher terms from local "
      "polynomials of degree " +
      std::to_string(given_order + detail::kReconExtra) + " over +-" +
      format_significant(detail::kReconSpan) + " times the rule's half-window: " + table +
      wb.table() + ")";
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
  bool judged_all = false;  ///< the bias judged in every fitted parameter (BiasInputs::judged)
  // candidate k's predicted |bias| / std; false when the inputs cannot be formed
  const auto evaluate = [&](int k, double* worst) {
    const detail::BiasInputs in =
        w.bias_inputs(std::lround(detail::kReconSpan * cand[k]), cand[1], sg_fit->order);
    if (in.J.rows() != 2 * static_cast<int>(w.index().size())) return false;
    judged_all = in.judged > in.friction_size;
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
                 (judged_all ? " std of every fitted parameter"
                             : " std of every friction coefficient")) +
      " (the smoothing bias and the noise's through the reactions, errors in variables; "
      "predicted |bias| / std by half-window, the motion's higher terms from local polynomials of "
      "degree " +
      std::to_string(sg_fit->order + detail::kReconExtra) + " over +-" +
      format_significant(detail::kReconSpan) + " half-windows: " + table + ")";
}

void unbiased_window_check(const Fit& f, const ModelVerdict& verdict, IdentifyResult* out) {
  // the first reason stays, but for a model error no cause explains: the window's bias is one
  // the check's causes cannot explain (a clean log at 1e-4 rad along a fast design read the
  // inertias' fall at 292 against 14 for the noise alone)
  const bool unattributed = !verdict.unattributed.empty() && out->unusable == verdict.unattributed;
  // per joint only: a shared law's window walk takes its predicted bias off, and its prediction
  // read 4.6-5.6 std on clean logs of a light, slow five-bar whose estimates were within 1.3 std
  if (!f.layout.per_joint || !(f.window_bias_left > kUnusableBias) ||
      !(out->unusable.empty() || unattributed)) {
    return;
  }
  const TorqueLog& log = f.cond.log;
  const double dt = log.duration() / std::max(1, log.size() - 1);
  out->unusable =
      "no Savitzky-Golay window estimates this log's accelerations without a bias the error bars "
      "miss: the least biased, half-window " +
      std::to_string(sg_half_window(f.sg, dt)) + " samples of order " + std::to_string(f.sg.order) +
      ", predicts a friction coefficient off by " + format_significant(f.window_bias_left, 2) +
      " std (the smoothing's bias grows with the window, the angle noise's through the reactions "
      "as it shrinks): this motion is too fast for accelerations estimated from its angles at " +
      std::to_string(std::lround(1 / dt)) +
      " Hz; log the rates (or at a much higher rate), or drive the motion slower";
}

void correct_smoothing_bias(const ParameterLayout& layout, const Eigen::VectorXd& b,
                            std::vector<double>* x, IdentifyResult* out,
                            const Eigen::VectorXd& spread) {
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
    // an open side (+-inf) stays open; a lower end that respected the bound still does after
    // the shift, and one at the bound (a profile interval that reached it: the cost there is
    // within the threshold) stays there, whichever way the estimate moves
    const double lb = layout.lower_bound(p);
    const bool within_bound = e.ci_low >= lb, at_bound = e.ci_low == lb;
    // the prediction's own std in quadrature, the interval widened by as many quantiles
    const double s = p < spread.size() && std::isfinite(spread(p)) ? spread(p) : 0.0;
    const double widen = out->ci_quantile * (std::hypot(e.std, s) - e.std);
    e.std = std::hypot(e.std, s);
    e.ci_low -= applied(p) + widen;
    if (within_bound) e.ci_low = std::max(e.ci_low, lb);
    if (at_bound) e.ci_low = lb;
    e.ci_high += widen - applied(p);
    list += (list.empty() ? "" : ", ") + e.name + " " + format_significant(-applied(p));
    if (s > 0) list += " +- " + format_significant(s, 2);
    // the shift's rounding in x - dx is eps |x|, far above eps |shift| for a small shift
    if (std::abs(applied(p) - shift(p)) > 1e-6 * std::abs(shift(p))) {
      list += " (limited by its bound: predicted " + format_significant(-shift(p)) + ")";
    }
  }
  if (list.empty()) return;
  out->window_choice +=
      "; the predicted bias at it taken off the estimates (" + list +
      (spread.size() > 0 ? "; +- its std from the angle noise, added to the std" : "") + ")";
}

}  // namespace fivebar::identification::stages
