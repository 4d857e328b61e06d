// The model check's Savitzky-Golay window (angles-only logs): the fit's, or a smaller one where
// the fit's smooths the motion's accelerations enough to show in the residual.
#include "identify_stages.h"

namespace fivebar::identification::stages {

namespace {

/// The motion's terms above the filter's order that the smoothing error is read from: the first
/// (even: the centred filter's acceleration error) and the second (odd: its rate error)
constexpr int kCheckTerms = 2;

/// The check's window keeps the predicted smoothing error's whitened cost at most this. The
/// freed causes absorbed from a quarter of it (the inertias and the zeros together on a fast
/// five-bar, 418 of 1695 at its fit's half-window of 7 samples) to all of it (a heavy one's
/// zeros, 43 of 40 at 6 samples); what leaks at the check's window can only confirm the first
/// check's verdict, while a smaller window, noisier, sees less of a real error (the fast
/// five-bar's clean 3 s logs: cost 16-27 at 5 samples, every fall there within 5 std, where a real
/// error reads about 0.21 of its evidence at 7; at 4 samples 0.07).
constexpr double kCheckSmoothingCost = 64;

/// What the smoothing error of any window needs about the fit's samples: each one's kinematic
/// Jacobian D and its cranks' higher terms (motion_terms over the fit's window's reach).
struct SmoothingInputs {
  std::vector<Eigen::Matrix<double, 2, 6>> D;
  std::vector<std::array<Eigen::VectorXd, kDof>> terms;
};

SmoothingInputs smoothing_inputs(const Fit& f, int m) {
  SmoothingInputs in;
  const int reach = static_cast<int>(std::lround(detail::kReconSpan * m));
  const detail::KinematicJacobians jacobian(f.scene, f.layout, f.x.data());
  for (size_t u = 0; u < f.samples.size(); ++u) {
    Eigen::Matrix<double, 2, 6> D;
    if (!jacobian(f.samples[u], f.eval, &D)) {
      D.setZero();
    }
    in.D.push_back(D);
    in.terms.emplace_back();
    motion_terms(f, f.index[u], reach, m, f.sg.order, kCheckTerms, &in.terms.back());
  }
  return in;
}

/// The noise floors (noise_floor) of the residual with the rates estimated by sg.
void floors_at(const Fit& f, const SmoothingInputs& in, const SgOptions& sg, double floor[2]) {
  std::vector<detail::Sensitivity> sens;
  sens.reserve(in.D.size());
  SgTapCache taps(f.cond.log.t, sg);
  for (size_t u = 0; u < in.D.size(); ++u) {
    sens.push_back(detail::sensitivity(&taps, f.index[u], f.source, f.noise, in.D[u]));
  }
  noise_floor(f, sens, floor);
}

/// The whitened cost sum_u |e_u / floor|^2 of the errors e_u that the filter sg's smoothing puts
/// in the residual: D times the errors of the rates and accelerations that the motion's higher
/// terms give through the filter's response.
double smoothing_cost(const Fit& f, const SmoothingInputs& in, const SgOptions& sg,
                      const double floor[2]) {
  const TorqueLog& log = f.cond.log;
  const double dt = log.duration() / std::max(1, log.size() - 1);
  Eigen::VectorXd r1, r2;
  detail::filter_response(sg, dt, &r1, &r2, kCheckTerms);
  double cost = 0;
  for (size_t u = 0; u < in.D.size(); ++u) {
    Eigen::Vector2d e = Eigen::Vector2d::Zero();
    for (int c = 0; c < kDof; ++c) {
      const Eigen::VectorXd& k = in.terms[u][c];
      e += in.D[u].col(2 + c) * k.dot(r1) + in.D[u].col(4 + c) * k.dot(r2);
    }
    cost += std::pow(e(0) / floor[0], 2) + std::pow(e(1) / floor[1], 2);
  }
  return std::isfinite(cost) ? cost : 0.0;
}

}  // namespace

CheckWindow check_window(const Fit& f, const IdentifyResult& out) {
  CheckWindow cw;
  cw.sg = f.sg;
  cw.floor[0] = out.residual_noise_floor[0];
  cw.floor[1] = out.residual_noise_floor[1];
  const TorqueLog& log = f.cond.log;
  if (f.source != detail::RateSource::kFromAngles || log.size() < 2 || f.samples.empty()) {
    return cw;
  }
  const double dt = log.duration() / (log.size() - 1);
  const int m = sg_half_window(f.sg, dt);
  const SmoothingInputs in = smoothing_inputs(f, m);
  cw.fit_cost = cw.cost = smoothing_cost(f, in, f.sg, cw.floor);
  if (!(cw.fit_cost > kCheckSmoothingCost)) return cw;
  for (int h = m - 1; h >= f.sg.order / 2 + 1; --h) {
    SgOptions sg = f.sg;
    sg.half_window_s = h * dt;
    double floor[2];
    floors_at(f, in, sg, floor);
    const double cost = smoothing_cost(f, in, sg, floor);
    if (!(cost < cw.cost)) continue;
    cw.sg = sg;
    cw.cost = cost;
    cw.floor[0] = floor[0];
    cw.floor[1] = floor[1];
    if (cost <= kCheckSmoothingCost) break;
  }
  return cw;
}

namespace {

/// "N samples": the half-window of sg on f's log
std::string half_window_text(const Fit& f, const SgOptions& sg) {
  const TorqueLog& log = f.cond.log;
  const double dt = log.duration() / std::max(1, log.size() - 1);
  return std::to_string(sg_half_window(sg, dt)) + " samples";
}

/// "inertia 41, angle_offsets 75": the model causes of a check's report evidenced alone
std::string evidence_text(const std::vector<IdentifyResult::MisfitCause>& causes) {
  std::string read;
  for (const IdentifyResult::MisfitCause& c : causes) {
    if (!counts_alone(c) || !c.checked || !(c.z > detail::kCauseZ)) continue;
    read += (read.empty() ? "" : ", ") + c.name + " " + format_significant(c.z, 2);
  }
  return read.empty() ? "all of them together" : read;
}

}  // namespace

double largest_evidence(const std::vector<IdentifyResult::MisfitCause>& causes) {
  double z = 0;
  for (const IdentifyResult::MisfitCause& c : causes) {
    // (the model causes: the motors' friction, judged beside them, is left out of the
    // prediction, which was measured on theirs)
    if (counts_alone(c) && c.name != kCauseText[kCauseMotors].name && c.checked && c.z > z) z = c.z;
  }
  return z;
}

double floor_ratio(const IdentifyResult& out, const CheckWindow& cw) {
  double r = 0;
  for (int c = 0; c < kDof; ++c) r += std::pow(out.residual_noise_floor[c] / cw.floor[c], 2) / kDof;
  return std::isfinite(r) ? r : 0.0;
}

std::string confirmed_note(const Fit& f, const CheckWindow& cw,
                           const std::vector<IdentifyResult::MisfitCause>& again, double seen) {
  const std::string why =
      seen > detail::kCauseZ
          ? "evidences a model error too (evidence alone, in std: " + evidence_text(again) + ")"
          : "would not see this error (its evidence there, about " + format_significant(seen, 2) +
                " std, below " + format_significant(detail::kCauseZ) + ")";
  return "model check: the fit's half-window of " + half_window_text(f, f.sg) +
         " smooths this motion's accelerations (a predicted error of whitened cost " +
         format_significant(cw.fit_cost, 3) + " in the residual), but the check at " +
         half_window_text(f, cw.sg) + " (cost " + format_significant(cw.cost, 2) + ") " + why +
         ": the verdict is the fit's window's";
}

std::string smoothing_warning(const Fit& f, const CheckWindow& cw,
                              const std::vector<IdentifyResult::MisfitCause>& first) {
  const auto samples = [&](const SgOptions& sg) { return half_window_text(f, sg); };
  return "the model check at the fit's Savitzky-Golay half-window of " + samples(f.sg) +
         " evidenced a model error (evidence alone, in std: " + evidence_text(first) +
         ") that the estimated accelerations' smoothing error explains: that window smooths "
         "this motion's accelerations (a predicted error of whitened cost " +
         format_significant(cw.fit_cost, 3) + " in the residual, more than " +
         format_significant(kCheckSmoothingCost) + "), and at a half-window of " + samples(cw.sg) +
         " (cost " + format_significant(cw.cost, 2) + ", noise floor " +
         format_significant(cw.floor[0], 3) + ", " + format_significant(cw.floor[1], 3) +
         " N m) the check evidences no cause. The residual's structure is the rates': the log's "
         "rate is low for this motion's accelerations (log the rates, or sample faster, for a "
         "model check at the fit's window)";
}

Fit refiltered(const Fit& f, const IdentifyResult& out, const SgOptions& sg) {
  Fit g = f;
  g.sg = sg;
  g.samples.clear();
  g.index.clear();
  const TorqueLog& log = f.cond.log;
  std::vector<double> w1, a1, w2, a2;
  savitzky_golay(log.t, log.theta1, sg, &w1, &a1);
  savitzky_golay(log.t, log.theta2, sg, &w2, &a2);
  // the rest rule at sg's thresholds (select_samples): its noisier rates hold more samples
  const RestThresholds rest = rest_rule(log, out, *f.opt, sg);
  g.eval.rest_rate = rest.rate;
  const double noise = std::max(f.noise.angle[0], f.noise.angle[1]);
  for (size_t u = 0; u < f.samples.size(); ++u) {
    const int i = f.index[u];
    Sample s = f.samples[u];
    s.w1 = w1[i];
    s.w2 = w2[i];
    s.a1 = a1[i];
    s.a2 = a2[i];
    if (held_sample(f.scene, s, rest, noise)) continue;
    g.samples.push_back(s);
    g.index.push_back(i);
  }
  return g;
}

namespace {

/// What a model check adds to the result (warnings, notes, the reason not to use the fit, the
/// causes' report), set aside by take_check so that another check's may replace it.
struct CheckOutputs {
  std::vector<std::string> warnings, notes;
  std::string unusable;
  std::vector<IdentifyResult::MisfitCause> causes;
};

/// Moves out of *out what a check added after it held `warnings` warnings and `notes` notes and
/// the reason `unusable`, which is restored.
CheckOutputs take_check(IdentifyResult* out, size_t warnings, size_t notes,
                        const std::string& unusable) {
  CheckOutputs c;
  c.warnings.assign(out->warnings.begin() + warnings, out->warnings.end());
  c.notes.assign(out->notes.begin() + notes, out->notes.end());
  out->warnings.resize(warnings);
  out->notes.resize(notes);
  c.unusable = out->unusable;
  out->unusable = unusable;
  c.causes = std::move(out->model_check);
  out->model_check.clear();
  return c;
}

void put_check(CheckOutputs c, IdentifyResult* out) {
  out->warnings.insert(out->warnings.end(), c.warnings.begin(), c.warnings.end());
  out->notes.insert(out->notes.end(), c.notes.begin(), c.notes.end());
  out->unusable = c.unusable;
  out->model_check = std::move(c.causes);
}

}  // namespace

ModelVerdict model_check(const Fit& fit, const Analysis& an, IdentifyResult* out) {
  if (!out->converged) {
    ModelVerdict verdict;
    verdict.unchecked = "the fit did not converge";
    return verdict;
  }
  const size_t warnings = out->warnings.size(), notes = out->notes.size();
  const std::string unusable = out->unusable;
  bool evidenced = false;
  const ModelVerdict verdict = check_at(fit, out->residual_noise_floor, &an, out, &evidenced);
  if (!evidenced) return verdict;
  // a model error evidenced where the fit's window smooths the motion's accelerations beyond
  // the noise: checked again at the window where it does not (check_window); evidenced there
  // too (or not checked), the first check stands
  const CheckWindow cw = check_window(fit, *out);
  if (!cw.changed()) return verdict;
  CheckOutputs first = take_check(out, warnings, notes, unusable);
  const ModelVerdict second =
      check_at(refiltered(fit, *out, cw.sg), cw.floor, nullptr, out, &evidenced);
  // quiet there, the error is the smoothing's only if that check would have seen it: a model
  // error's fall scales with the whitening, so its evidence there is the first's times the
  // floors' ratio squared (the paper scene's masses +-5 % at 2 s: inertias 15 std at 7 samples,
  // quiet at 6, where they would read about 7)
  const double seen = largest_evidence(first.causes) * floor_ratio(*out, cw);
  if (evidenced || !second.unchecked.empty() || !(seen > detail::kCauseZ)) {
    const CheckOutputs again = take_check(out, warnings, notes, unusable);
    put_check(std::move(first), out);
    out->notes.push_back(confirmed_note(fit, cw, again.causes, seen));
    return verdict;
  }
  out->warnings.push_back(smoothing_warning(fit, cw, first.causes));
  return second;
}

}  // namespace fivebar::identification::stages
