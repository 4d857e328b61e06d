// The model check's Savitzky-Golay window (angles-only logs): the fit's, or a smaller one where
// the fit's smooths the motion's accelerations enough to show in the residual.
#include "identify_stages.h"

namespace fivebar::identification::stages {

namespace {

/// The motion's terms above the filter's order that the smoothing error is read from: the first
/// (even: the centred filter's acceleration error) and the second (odd: its rate error)
constexpr int kCheckTerms = 2;

/// The check's window keeps the predicted smoothing error's whitened cost at most this: the
/// freed causes absorbed about a quarter of it on a fast five-bar (1 kHz, cranks up to 55
/// rad/s, a clean 3 s log: 418 of 1695 at its fit's half-window of 7 samples, 66 of 256 at 6),
/// so that at this cost they absorb about the encoders' zeros' evidence bar (kCauseZ std of
/// their fall under noise alone, 2 +- 2), and the inertias' fall at 5 samples (cost 26) was -9.
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
  for (size_t u = 0; u < f.samples.size(); ++u) {
    Eigen::Matrix<double, 2, 6> D;
    if (!detail::kinematic_jacobian(f.scene, f.layout, f.x.data(), f.samples[u], f.eval, &D)) {
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
  for (size_t u = 0; u < in.D.size(); ++u) {
    sens.push_back(detail::sensitivity(f.cond.log.t, f.index[u], f.source, sg, f.noise, in.D[u]));
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

std::string smoothing_warning(const Fit& f, const CheckWindow& cw,
                              const std::vector<IdentifyResult::MisfitCause>& first) {
  const TorqueLog& log = f.cond.log;
  const double dt = log.duration() / std::max(1, log.size() - 1);
  const auto samples = [&](const SgOptions& sg) {
    return std::to_string(sg_half_window(sg, dt)) + " samples";
  };
  std::string read;
  for (const IdentifyResult::MisfitCause& c : first) {
    if (c.name == "delay" || c.name == "any" || !c.checked || !(c.z > detail::kCauseZ)) continue;
    read += (read.empty() ? "" : ", ") + c.name + " " + format_significant(c.z, 2);
  }
  return "the model check at the fit's Savitzky-Golay half-window of " + samples(f.sg) +
         " evidenced a model error (evidence alone, in std: " + read +
         ") that the estimated accelerations' smoothing error explains: that window smooths "
         "this motion's accelerations (a predicted error of whitened cost " +
         format_significant(cw.fit_cost, 3) + " in the residual, more than " +
         format_significant(kCheckSmoothingCost) + "), and at a half-window of " +
         samples(cw.sg) + " (cost " + format_significant(cw.cost, 2) + ", noise floor " +
         format_significant(cw.floor[0], 3) + ", " + format_significant(cw.floor[1], 3) +
         " N m) the check evidences no cause. The residual's structure is the rates': the log's "
         "rate is low for this motion's accelerations (log the rates, or sample faster, for a "
         "model check at the fit's window)";
}

Fit refiltered(const Fit& f, const SgOptions& sg) {
  Fit g = f;
  g.sg = sg;
  const TorqueLog& log = f.cond.log;
  std::vector<double> w1, a1, w2, a2;
  savitzky_golay(log.t, log.theta1, sg, &w1, &a1);
  savitzky_golay(log.t, log.theta2, sg, &w2, &a2);
  for (size_t u = 0; u < g.samples.size(); ++u) {
    const int i = f.index[u];
    g.samples[u].w1 = w1[i];
    g.samples[u].w2 = w2[i];
    g.samples[u].a1 = a1[i];
    g.samples[u].a2 = a2[i];
  }
  return g;
}

}  // namespace fivebar::identification::stages
