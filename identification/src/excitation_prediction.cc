// A motion's evaluation on a grid (evaluate_motion) and the std identify would report on it
// (predict_identified_std): errors in variables at the window identify's rules choose, its rest
// and reversal samples left out.
#include "fivebar/identification/excitation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

#include <Eigen/Dense>

#include "fivebar/identification/rates.h"
#include "mechanism_stages.h"
#include "excitation_shared.h"
#include "noise_model.h"
#include "setup_shared.h"
#include "smoothing_bias.h"

namespace fivebar::identification {

namespace {
using detail::kNaN;
}  // namespace

// ---------------------------------------------------------------------------------------------
// Evaluation of a motion on a grid

Status evaluate_motion(const Params<double>& scene, const DesignParameters& dp,
                       const std::function<Loads<double>(double)>& loads,
                       const std::vector<double>& t, const std::vector<MotionState>& states,
                       double torque_noise, ExcitationReport* out) {
  // the loads by reference for this call (a copy of a scene's loads recompiles its expressions)
  const auto mech = five_bar_excitation(scene, dp, [&loads](double at) { return loads(at); });
  return evaluate_motion(*mech, t, states, torque_noise, out);
}

Status evaluate_motion(const ExcitationMechanism& mech, const std::vector<double>& t,
                       const std::vector<MotionState>& states, double torque_noise,
                       ExcitationReport* out) {
  const DesignParameters& dp = mech.parameters();
  const int N = static_cast<int>(t.size());
  std::vector<SampleTerms> terms(N);
  std::vector<Status> status(N);
  detail::parallel_for(N,
                       [&](int i) { status[i] = mech.terms(t[i], states[i], nullptr, &terms[i]); });
  for (int i = 0; i < N; ++i) {
    if (!status[i].ok()) {
      std::ostringstream msg;
      msg << "at t = " << t[i] << " s: " << status[i].message;
      return Status::Error(status[i].code, msg.str());
    }
  }
  out->t = t;
  out->states = states;
  out->dof = mech.dof();
  out->joints = mech.joints();
  out->M1.resize(N);
  out->M2.resize(N);
  std::vector<Eigen::MatrixXd> Js(N);
  std::vector<std::array<double, kJoints>> rates(N);
  out->theta_min = {states[0].th1, states[0].th2};
  out->theta_max = out->theta_min;
  for (int i = 0; i < N; ++i) {
    out->M1[i] = terms[i].M1;
    out->M2[i] = terms[i].M2;
    const double peak = std::max(std::abs(terms[i].M1), std::abs(terms[i].M2));
    if (peak > out->peak_torque) {
      out->peak_torque = peak;
      out->peak_time = t[i];
    }
    out->min_sine = std::min(out->min_sine, terms[i].sine);
    Js[i] = std::move(terms[i].J);
    rates[i] = terms[i].w;
    const double th[2] = {states[i].th1, states[i].th2};
    for (int j = 0; j < mech.dof(); ++j) {
      out->theta_min[j] = std::min(out->theta_min[j], th[j]);
      out->theta_max[j] = std::max(out->theta_max[j], th[j]);
    }
  }
  out->reversals = count_reversals(rates);
  out->fisher = fisher_information(Js, torque_noise) + detail::prior_fisher(dp);
  const int P = dp.size();
  const Eigen::VectorXd scale = Eigen::Map<const Eigen::VectorXd>(dp.scale.data(), P);
  const Eigen::MatrixXd Fs = scale.asDiagonal() * out->fisher * scale.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Fs);
  const Eigen::VectorXd ev = es.eigenvalues();
  out->condition_number = ev(0) > 0 ? ev(P - 1) / ev(0) : kNaN;
  out->log_det_scaled =
      ev(0) > 0 ? ev.array().log().sum() : -std::numeric_limits<double>::infinity();
  // covariance: pseudo-inverse of the scaled Fisher (directions below 1e-14 of the largest are
  // unidentifiable: their parameters get an infinite std)
  Eigen::VectorXd inv(P);
  for (int i = 0; i < P; ++i) inv(i) = ev(i) > 1e-14 * ev(P - 1) ? 1.0 / ev(i) : 0.0;
  const Eigen::MatrixXd Cs = es.eigenvectors() * inv.asDiagonal() * es.eigenvectors().transpose();
  out->covariance = scale.asDiagonal() * Cs * scale.asDiagonal();
  out->std_dev.assign(P, kNaN);
  out->relative_std.assign(P, kNaN);
  for (int i = 0; i < P; ++i) {
    bool lost = false;
    for (int e = 0; e < P; ++e)
      lost = lost || (inv(e) == 0 && std::abs(es.eigenvectors()(i, e)) > 1e-6);
    out->std_dev[i] = lost ? std::numeric_limits<double>::infinity()
                           : std::sqrt(std::max(0.0, out->covariance(i, i)));
    if (dp.nominal[i] != 0) out->relative_std[i] = out->std_dev[i] / std::abs(dp.nominal[i]);
  }
  return Status::Ok();
}

// ---------------------------------------------------------------------------------------------
// The std identify reports: errors in variables at the window it chooses

namespace {

using stages::kBiasFraction;  // identify's window rules (noise_model.h)

/// What one sample of the motion gives the prediction: J (2 x P), the kinematic Jacobian D of
/// the torques (noise_model.h) and the joints' relative rates.
struct EivSample {
  Eigen::MatrixXd J;
  Eigen::Matrix<double, 2, 6> D;
  std::array<double, kJoints> w{};
};

/// The prediction at one half-window m: the samples it keeps, the std and the bias of the
/// coefficients, the expected torque residual over its noise level.
struct WindowPrediction {
  Eigen::MatrixXd covariance;  ///< errors in variables, identify's
  Eigen::VectorXd bias;
  double residual_ratio = 1;
  bool ok = false;
};

/// Savitzky-Golay taps of a centred window of half-width m (savitzky_golay_taps)
struct Taps {
  int m = 0;
  std::vector<double> d1, d2;
};

class EivPredictor {
 public:
  EivPredictor(const ExcitationMechanism& mech, const ExcitationReport& r,
               std::vector<EivSample> samples, double torque_noise,
               const std::array<double, 2>& angle_noise, int order, bool noise_bias = false)
      : mech_(mech),
        r_(r),
        s_(std::move(samples)),
        order_(order),
        noise_bias_(noise_bias),
        angle_noise_(std::max(angle_noise[0], angle_noise[1])),
        prior_(detail::prior_fisher(mech.parameters()).diagonal()) {
    const int n = static_cast<int>(r.t.size());
    dt_ = (r.t.back() - r.t.front()) / std::max(1, n - 1);
    for (int c = 0; c < mech.dof(); ++c) {
      noise_.angle[c] = angle_noise[c];
      noise_.torque[c] = torque_noise;
    }
    // prefix counts of the sample steps over which some joint's rate changes sign
    reversals_.assign(n + 1, 0);
    for (int i = 0; i < n; ++i) {
      bool flip = false;
      for (int k = 0; i > 0 && k < kJoints; ++k)
        flip = flip || (s_[i].w[k] > 0) != (s_[i - 1].w[k] > 0);
      reversals_[i + 1] = reversals_[i] + (flip ? 1 : 0);
    }
  }
  double dt() const { return dt_; }
  int size() const { return static_cast<int>(r_.t.size()); }

  /// the bias of the filter's rates and accelerations on the exact motion at sample i, and the
  /// residual's sensitivities to the angle noise
  void at(int i, const Taps& taps, Eigen::Vector2d* dM, detail::Sensitivity* sens) const {
    const int lo = i - taps.m;
    const std::vector<double>&d1 = taps.d1, &d2 = taps.d2;
    double e[4] = {0, 0, 0, 0};
    for (size_t k = 0; k < d1.size(); ++k) {
      const MotionState& q = r_.states[lo + k];
      e[0] += d1[k] * q.th1, e[1] += d1[k] * q.th2, e[2] += d2[k] * q.th1, e[3] += d2[k] * q.th2;
    }
    const MotionState& q = r_.states[i];
    const Eigen::Vector4d delta(e[0] - q.w1, e[1] - q.w2, e[2] - q.a1, e[3] - q.a2);
    *dM = s_[i].D.rightCols<4>() * delta;
    *sens = detail::sensitivity(i, lo, d1, d2, detail::RateSource::kFromAngles, noise_, s_[i].D);
  }

  /// The samples the rest rule may hold at any half-window from m up (its thresholds grow with
  /// the filter's noise gains, which fall as the window grows): the others need no rest test
  void bound_rest(int m) {
    double g1 = 0, g2 = 0;
    gains(m, &g1, &g2);
    maybe_rest_.assign(size(), 0);
    detail::parallel_for(size(), [&](int i) {
      maybe_rest_[i] = mech_.at_rest(r_.t[i], r_.states[i], g1, g2, angle_noise_) ? 1 : 0;
    });
  }

  /// the noise gains of the filter of half-window m, as identify's rest rule takes them
  void gains(int m, double* g1, double* g2, int order = -1) const {
    SgOptions filter;
    filter.half_window_s = m * dt_;
    filter.order = order < 0 ? order_ : order;
    stages::sg_noise_gains(r_.t, filter, g1, g2);
  }

  /// the filter of half-window m at a centred sample: the same at every one (uniform grid); of
  /// the predictor's order unless given
  Taps taps(int m, int order = -1) const {
    Taps out;
    out.m = m;
    SgOptions sg;
    sg.half_window_s = m * dt_;
    sg.order = order < 0 ? order_ : order;
    int lo = 0;
    savitzky_golay_taps(r_.t, m, sg, &lo, &out.d1, &out.d2);
    return out;
  }

  /// The samples identify's fit keeps with rates from half-window m: centred, whose window of
  /// half-width `exclude` spans no slip reversal, not at rest by identify's rule at half-window
  /// rest_m (-1: m), of the filter's order (-1: the predictor's)
  std::vector<int> kept(int m, int exclude, int rest_m = -1, int order = -1) const {
    const int n = size();
    double g1 = 0, g2 = 0;
    gains(rest_m < 0 ? m : rest_m, &g1, &g2, order);
    std::vector<int> used;
    const int edge = std::max(m, exclude);
    for (int i = edge; i < n - edge; ++i) {
      if (stages::window_spans_reversal(reversals_, i, exclude)) continue;
      const bool maybe = maybe_rest_.empty() || maybe_rest_[i] || (order >= 0 && order != order_);
      if (maybe && mech_.at_rest(r_.t[i], r_.states[i], g1, g2, angle_noise_)) continue;
      used.push_back(i);
    }
    return used;
  }

  /// The half-width identify's fit keeps clear of slip reversals with rates from half-window m
  /// (its rule: none where that would leave out more than half of the centred samples)
  int reversal_window(int m) const {
    const int n = size();
    int near = 0, total = 0;
    for (int i = m; i <= n - 1 - m; ++i, ++total) {
      near += stages::window_spans_reversal(reversals_, i, m) ? 1 : 0;
    }
    return stages::leaves_out_reversals(near, total) ? m : 0;
  }

  /// covariance and bias of the coefficients over the samples kept (kept) with rates from
  /// half-window m
  WindowPrediction predict(int m, int exclude, int rest_m = -1, int scale_m = -1) const {
    return predict_over(kept(m, exclude, rest_m), m, -1, scale_m);
  }

  /// identify's noise level of the prior (the four-bar's residual floor): the torque noise and
  /// the noise of the accelerations of the filter of half-window m through the crank's effective
  /// inertia over the samples `used`, at least kAbsoluteFloor of the torques' rms
  double prior_scale(const std::vector<int>& used, int m, int order = -1) const {
    double g1 = 0, g2 = 0;
    gains(m, &g1, &g2, order);
    double s2 = 0, tau2 = 0;
    for (int i : used) {
      const double accel = s_[i].D(0, 4) * g2 * angle_noise_;
      s2 += noise_.torque[0] * noise_.torque[0] + accel * accel;
      tau2 += r_.M1[i] * r_.M1[i];
    }
    const double count = std::max<double>(1, used.size());
    return std::max(std::sqrt(s2 / count), stages::kAbsoluteFloor * std::sqrt(tau2 / count));
  }

  /// covariance and bias of the coefficients over the samples `used`, with rates from half-window
  /// m of the filter's order (-1: the predictor's); with a prior (DesignParameters::prior_std), its
  /// pseudo-observations weighed at prior_scale of the window scale_m (-1: m), as identify's
  WindowPrediction predict_over(const std::vector<int>& used, int m, int order = -1,
                                int scale_m = -1) const {
    const Taps sg = taps(m, order);
    WindowPrediction out;
    const int n = size(), P = static_cast<int>(s_.front().J.cols());
    if (static_cast<int>(used.size()) <= P) return out;
    Eigen::MatrixXd J(2 * used.size(), P);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(P);
    std::vector<detail::Sensitivity> sens(used.size());
    // per used sample, with the noise's bias: J^T (dM + shift) + score (smoothing_bias.h)
    std::vector<Eigen::VectorXd> mean_score;
    if (noise_bias_) mean_score = noise_scores(used, sg);
    for (size_t u = 0; u < used.size(); ++u) {
      Eigen::Vector2d dM;
      at(used[u], sg, &dM, &sens[u]);
      J.middleRows(2 * u, 2) = s_[used[u]].J;
      if (noise_bias_) {
        mean_score[u] += s_[used[u]].J.transpose() * dM;
        g += mean_score[u];
      } else {
        g += s_[used[u]].J.transpose() * dM;  // one Gauss-Newton step: the residual moves by -dM
      }
    }
    Eigen::MatrixXd H = J.transpose() * J;
    Eigen::MatrixXd S_prior = Eigen::MatrixXd::Zero(P, P);
    if (prior_.any()) {  // rows s / sigma_i, each a pseudo-observation of noise s
      const double s = prior_scale(used, scale_m < 0 ? m : scale_m, order), s2 = s * s;
      H.diagonal() += s2 * prior_;
      S_prior.diagonal() = s2 * s2 * prior_;
    }
    if (!H.allFinite()) return out;
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(H);
    const Eigen::VectorXd ev = es.eigenvalues();
    if (!(ev(0) > 1e-14 * ev(P - 1))) return out;  // the samples do not determine them all
    const Eigen::MatrixXd Hinv =
        es.eigenvectors() * ev.cwiseInverse().asDiagonal() * es.eigenvectors().transpose();
    out.bias = -Hinv * g;
    out.covariance = Hinv * (detail::score_covariance(J, sens, noise_, n) + S_prior) * Hinv;
    out.ok = out.covariance.allFinite();
    return out;
  }

 private:
  /// Per used sample: J^T shift + score of the noise's bias (smoothing_bias.h, NoiseBias), the
  /// first crank's angle noise through the filter `sg` (detail::noise_bias_at: identify's
  /// prediction on four-bars); zero where an evaluation fails.
  std::vector<Eigen::VectorXd> noise_scores(const std::vector<int>& used, const Taps& sg) const {
    const int P = static_cast<int>(s_.front().J.cols());
    const Eigen::Matrix3d C =
        detail::filtered_noise_covariance(sg.m, 0, sg.d1, sg.d2, noise_.angle[0]);
    std::vector<Eigen::VectorXd> out(used.size(), Eigen::VectorXd::Zero(P));
    detail::parallel_for(static_cast<int>(used.size()), [&](int u) {
      const int i = used[u];
      const detail::PerturbedTorques torques = [&](const Eigen::Vector3d& dn, Eigen::Vector2d* M,
                                                   Eigen::MatrixXd* A) {
        MotionState q = r_.states[i];
        q.th1 += dn(0), q.w1 += dn(1), q.a1 += dn(2);
        SampleTerms terms;
        if (!mech_.terms(r_.t[i], q, nullptr, &terms).ok()) return false;
        *M = Eigen::Vector2d(terms.M1, terms.M2);
        *A = terms.J;
        return true;
      };
      Eigen::Vector2d shift;
      Eigen::VectorXd score;
      if (detail::noise_bias_at(C, torques, &shift, &score)) {
        out[u] = s_[i].J.transpose() * shift + score;
      }
    });
    return out;
  }

  const ExcitationMechanism& mech_;
  const ExcitationReport& r_;
  std::vector<EivSample> s_;
  int order_;
  bool noise_bias_;  ///< the noise's bias in the prediction (the mechanisms of window_by_bias)
  double angle_noise_;
  detail::SensorNoise noise_;
  Eigen::VectorXd prior_;  ///< the prior's information per parameter (prior_fisher; 0: none)
  std::vector<int> reversals_;
  std::vector<char> maybe_rest_;  ///< bound_rest's (empty: test every sample)
  double dt_ = 1;
};

/// The largest |bias| / std over the first `judged` parameters of a prediction (its
/// errors-in-variables std, as identify's bias rules take it).
double bias_in_std(const WindowPrediction& p, int judged) {
  double worst = 0;
  for (int i = 0; i < judged; ++i) {
    const double sd = std::sqrt(std::max(0.0, p.covariance(i, i)));
    if (sd > 0) worst = std::max(worst, std::abs(p.bias(i)) / sd);
  }
  return worst;
}

/// v to 3 significant digits
std::string digits3(double v) {
  std::ostringstream o;
  o.precision(3);
  o << v;
  return o.str();
}

/// std and relative std of a covariance (NaN relative std for a zero nominal value).
void set_std(const DesignParameters& dp, const Eigen::MatrixXd& C, ExcitationReport* r) {
  for (int i = 0; i < dp.size(); ++i) {
    r->std_dev[i] = std::sqrt(std::max(0.0, C(i, i)));
    r->relative_std[i] = dp.nominal[i] != 0 ? r->std_dev[i] / std::abs(dp.nominal[i]) : kNaN;
  }
}

/// The Jacobians J and D and the joint rates at every sample of the motion of `r` (exact); the
/// first sample that fails, named by its time.
Status eiv_samples(const ExcitationMechanism& mech, const ExcitationReport& r,
                   std::vector<EivSample>* samples) {
  const int n = static_cast<int>(r.t.size());
  samples->clear();
  samples->resize(n);
  std::vector<Status> status(n);
  detail::parallel_for(n, [&](int i) {
    SampleTerms terms;
    status[i] = mech.terms(r.t[i], r.states[i], nullptr, &terms);
    if (status[i].ok()) status[i] = mech.kinematic_jacobian(r.t[i], r.states[i], &(*samples)[i].D);
    if (!status[i].ok()) return;
    (*samples)[i].J = terms.J;
    (*samples)[i].w = terms.w;
  });
  for (int i = 0; i < n; ++i) {
    if (!status[i].ok()) {
      return Status::Error(status[i].code,
                           "at t = " + digits3(r.t[i]) + " s: " + status[i].message);
    }
  }
  return Status::Ok();
}

}  // namespace

namespace {

/// The window identify chooses on the five-bar (predict_identified_std): its window stages
/// themselves on a log of synth-log's sensors along the motion (ExcitationMechanism::
/// identify_window); the prediction there, over the samples identify's fit keeps (stage_samples.cc:
/// a raised order keeps those near the slip reversals), into *chosen; the half-window into
/// r->sg_half_window, the choice's text into r->window_choice.
Status choose_window(const EivPredictor* predictor, const ExcitationMechanism& mech,
                     double torque_noise, double angle_noise, ExcitationReport* r,
                     WindowPrediction* chosen) {
  const SgOptions first;  // identify's filter before its choice
  SgOptions sg = first;
  std::string choice;
  if (!mech.identify_window(*r, torque_noise, angle_noise, &sg, &choice)) {
    return Status::Error(StatusCode::kSolverFailed,
                         "identify stops before its window on a log along the motion (the samples "
                         "it keeps, away from the slip reversals and not at rest, are too few): " +
                             choice);
  }
  const int m = sg_half_window(sg, predictor->dt());
  const EivPredictor& eiv = *predictor;
  const int exclude = sg.order > first.order ? 0 : eiv.reversal_window(m);
  *chosen = eiv.predict_over(eiv.kept(m, exclude, m, sg.order), m, sg.order);
  r->sg_half_window = m;
  r->window_choice = "identify's on a log along the motion (seed 1): " + choice;
  return Status::Ok();
}

/// The window identify's walk by predicted bias chooses (a mechanism of window_by_bias; its
/// identify: choose_window_by_bias), by the same walk (stages::walk_window_by_bias) from its
/// filter `start`: each candidate's bias, the smoothing's and the noise's, over the samples its
/// rules keep before the choice (the rest rule at the start's filter, the slip reversals within
/// the larger of the two windows left out); then the prediction at the window chosen, with the
/// samples identify's fit keeps there, into *chosen; the half-window into r->sg_half_window and
/// r->window_choice. No window predicted: identify's, the start.
void walk_window(EivPredictor* predictor, const DesignParameters& dp, const SgOptions& start,
                 ExcitationReport* r, WindowPrediction* chosen) {
  const int n = static_cast<int>(r->t.size());
  const std::vector<int> cand = stages::window_candidates(n, predictor->dt(), start.order);
  const int K = static_cast<int>(cand.size()), m0 = sg_half_window(start, predictor->dt());
  predictor->bound_rest(std::min(cand.front(), m0));  // the largest thresholds
  const EivPredictor& eiv = *predictor;
  // identify's walk judges every fitted parameter where the links' inertias are fitted
  const int judged = dp.inertial > 0 ? dp.size() : dp.friction;
  const auto worst = [&](int k, double* ratio) {
    const WindowPrediction p = eiv.predict(cand[k], std::max(cand[k], m0), m0, m0);
    *ratio = p.ok ? bias_in_std(p, judged) : kNaN;
    return true;
  };
  const int first = static_cast<int>(std::lower_bound(cand.begin(), cand.end(), m0) - cand.begin());
  const stages::BiasWalk walk = stages::walk_window_by_bias(K, first, worst);
  const int m = walk.pick < 0 ? m0 : cand[walk.pick];
  *chosen = eiv.predict(m, m);
  r->sg_half_window = m;
  std::string table;
  for (int k = 1; k < K; ++k) {
    if (walk.ratio[k] < 0 || std::isnan(walk.ratio[k])) continue;
    table += (table.empty() ? "" : ", ") + std::to_string(cand[k]) + ": " + digits3(walk.ratio[k]);
  }
  r->window_choice =
      "half-window " + std::to_string(m) + " samples, order " + std::to_string(start.order) +
      ": identify's walk by predicted bias from " + std::to_string(m0) + " samples, " +
      (walk.pick < 0 ? "no window's bias predicted: the start"
       : walk.within ? "the smallest within " + digits3(stages::kBiasFraction) + " std"
                     : "none within " + digits3(stages::kBiasFraction) + " std: the least") +
      " (the smoothing bias and the noise's through the reactions, |bias| / std by half-window: " +
      table + ")";
}

}  // namespace

Status predict_identified_std(const Params<double>& scene, const DesignParameters& dp,
                              const std::function<Loads<double>(double)>& loads,
                              double torque_noise, double angle_noise, ExcitationReport* r) {
  // the loads by reference for this call (a copy of a scene's loads recompiles its expressions)
  const auto mech = five_bar_excitation(scene, dp, [&loads](double at) { return loads(at); });
  return predict_identified_std(*mech, torque_noise, angle_noise, r);
}

Status predict_identified_std(const ExcitationMechanism& mech, double torque_noise,
                              double angle_noise, ExcitationReport* r) {
  const DesignParameters& dp = mech.parameters();
  const int n = static_cast<int>(r->t.size());
  r->torque_only_std = r->std_dev;
  if (!(angle_noise > 0) || n < 8 || dp.size() == 0) return Status::Ok();
  for (double v : r->std_dev) {
    if (!std::isfinite(v)) return Status::Ok();  // an unidentifiable direction stays so
  }
  std::vector<EivSample> samples;
  const Status st = eiv_samples(mech, *r, &samples);
  if (!st.ok()) return st;
  SgOptions start;
  const bool by_bias = mech.window_by_bias(&start);
  EivPredictor eiv(mech, *r, std::move(samples), torque_noise, {angle_noise, angle_noise},
                   by_bias ? start.order : SgOptions{}.order, by_bias);
  WindowPrediction chosen;
  Status window = Status::Ok();
  if (by_bias) {
    walk_window(&eiv, dp, start, r, &chosen);
  } else {
    window = choose_window(&eiv, mech, torque_noise, angle_noise, r, &chosen);
  }
  if (!window.ok() || !chosen.ok) {  // no std identify could report: none predicted
    r->sg_half_window = 0;
    r->std_dev.assign(dp.size(), kNaN);
    r->relative_std.assign(dp.size(), kNaN);
    if (!window.ok()) return window;
    return Status::Error(StatusCode::kSolverFailed,
                         "the errors-in-variables covariance could not be formed (the samples "
                         "identify keeps, away from the slip reversals and not at rest, do not "
                         "determine the parameters)");
  }
  r->covariance = chosen.covariance;
  set_std(dp, chosen.covariance, r);
  return Status::Ok();
}

}  // namespace fivebar::identification
