// Synthetic logs from the simulator with seeded sensor noise.
#include "fivebar/identification/synth.h"

#include <cmath>
#include <limits>
#include <random>

#include "fivebar/identification/torque_excitation.h"
#include "fivebar/model/dynamics.h"
#include "fivebar/model/format.h"

namespace fivebar::identification {

sim::LoadFunction multisine_loads(const sim::LoadFunction& scene_loads) {
  // four tones per motor around a bias (torque_excitation.cc); never clipped
  return ToneTorques(4, std::numeric_limits<double>::infinity()).loads(multisine_tones(), scene_loads);
}

SynthResult synthesize_log(const Params<double>& params, const sim::LoadFunction& loads,
                           const sim::Initial& initial, const SynthOptions& opt) {
  SynthResult out;
  sim::LoadFunction f = loads;
  if (opt.multisine) {
    MultisineFitOptions mo;
    mo.torque_limit = opt.torque_limit;
    mo.duration = opt.duration;
    mo.sim = opt.sim;
    const FittedMultisine fit = fit_multisine(params, loads, initial, mo);
    if (!fit.status.ok()) {
      out.status = Status::Error(
          fit.status.code, "the multi-sine runs into the singularity margin on this mechanism "
                           "at every scale down to " + format_significant(fit.factor, 3) +
                               " of its tones: " + fit.status.message);
      return out;
    }
    out.multisine_factor = fit.factor;
    out.multisine_holding_bias = fit.holding_bias;
    f = ToneTorques(4, opt.torque_limit).loads(fit.tones, loads);
  }
  sim::Options so = opt.sim;
  so.duration = opt.duration;
  so.output_step = 1.0 / opt.rate_hz;
  const sim::Result res = sim::simulate(params, f, initial, so);
  out.stats = res.stats;
  if (!res.status.ok()) {
    out.status = res.status;
    return out;
  }
  sample_log(params, res.rows, opt, &out);
  return out;
}

void sample_log(const Params<double>& params, const std::vector<sim::Row>& rows,
                const SynthOptions& opt, SynthResult* out) {
  std::mt19937_64 rng(opt.seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  TorqueLog& log = out->log;
  log.has_rates = log.has_accels = opt.with_rates;
  auto quantize = [&](double x) {
    return opt.quantization > 0 ? opt.quantization * std::round(x / opt.quantization) : x;
  };
  std::vector<std::array<double, kJoints>> rates;
  rates.reserve(rows.size());
  for (const sim::Row& row : rows) {
    // one fixed order of draws per row keeps logs reproducible across options
    const double n_tau1 = gauss(rng), n_tau2 = gauss(rng), n_th1 = gauss(rng), n_th2 = gauss(rng),
                 n_w1 = gauss(rng), n_w2 = gauss(rng);
    log.t.push_back(row.t);
    log.theta1.push_back(quantize(row.theta[0] + opt.angle_noise * n_th1));
    log.theta2.push_back(quantize(row.theta[1] + opt.angle_noise * n_th2));
    // the sensors read the motor torque plus their offset (ActuatorParams)
    log.tau1.push_back(row.M1 + params.actuators.offset[0] + opt.torque_noise * n_tau1);
    log.tau2.push_back(row.M2 + params.actuators.offset[1] + opt.torque_noise * n_tau2);
    if (opt.with_rates) {
      log.omega1.push_back(row.omega[0] + opt.rate_noise * n_w1);
      log.omega2.push_back(row.omega[1] + opt.rate_noise * n_w2);
      log.alpha1.push_back(row.alpha[0]);
      log.alpha2.push_back(row.alpha[1]);
    }
    log.lines.push_back(log.size() + 1);
    // joint reversals: sign changes of w_k = (w1, w3 - w1, w4 - w3, w2 - w4, w2)
    rates.push_back(relative_rates(row.omega[0], row.omega[1], row.omega[2], row.omega[3]));
  }
  out->reversals = count_reversals(rates);
}

std::array<int, kJoints> count_reversals(const std::vector<std::array<double, kJoints>>& rates) {
  std::array<int, kJoints> out{}, prev{};
  for (const auto& w : rates) {
    for (int k = 0; k < kJoints; ++k) {
      const int s = (w[k] > 0) - (w[k] < 0);
      if (s != 0 && prev[k] != 0 && s != prev[k]) ++out[k];
      if (s != 0) prev[k] = s;
    }
  }
  return out;
}

}  // namespace fivebar::identification
