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

namespace {

// The sensors of `dof` cranks along `rows`: per row the draws tau1..n, theta1..n, omega1..n (one
// fixed order keeps logs reproducible across options); `offset` is each torque sensor's offset,
// `joint_rates` a row's relative joint rates (for the reversal counts).
template <class JointRates>
void sample_rows(int dof, const std::array<double, kActuators>& offset,
                 const std::vector<sim::Row>& rows, const SynthOptions& opt,
                 JointRates joint_rates, SynthResult* out) {
  std::mt19937_64 rng(opt.seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  TorqueLog& log = out->log;
  log.dof = dof;
  log.has_rates = log.has_accels = opt.with_rates;
  auto quantize = [&](double x) {
    return opt.quantization > 0 ? opt.quantization * std::round(x / opt.quantization) : x;
  };
  std::vector<std::array<double, kJoints>> rates;
  rates.reserve(rows.size());
  for (const sim::Row& row : rows) {
    std::array<double, 3 * kActuators> n{};
    for (int i = 0; i < 3 * dof; ++i) n[i] = gauss(rng);
    const double M[kActuators] = {row.M1, row.M2};
    log.t.push_back(row.t);
    for (int j = 0; j < dof; ++j) {
      // the sensors read the motor torque plus their offset (ActuatorParams)
      log.tau(j).push_back(M[j] + offset[j] + opt.torque_noise * n[j]);
      log.theta(j).push_back(quantize(row.theta[j] + opt.angle_noise * n[dof + j]));
      if (opt.with_rates) {
        log.omega(j).push_back(row.omega[j] + opt.rate_noise * n[2 * dof + j]);
        log.alpha(j).push_back(row.alpha[j]);
      }
    }
    log.lines.push_back(log.size() + 1);
    rates.push_back(joint_rates(row));
  }
  out->reversals = count_reversals(rates);
}

}  // namespace

void sample_log(const Params<double>& params, const std::vector<sim::Row>& rows,
                const SynthOptions& opt, SynthResult* out) {
  // joint reversals: sign changes of w_k = (w1, w3 - w1, w4 - w3, w2 - w4, w2)
  sample_rows(kDof, params.actuators.offset, rows, opt, [](const sim::Row& r) {
    return relative_rates(r.omega[0], r.omega[1], r.omega[2], r.omega[3]);
  }, out);
}

void sample_log(const FourBarParams& params, const std::vector<sim::Row>& rows,
                const SynthOptions& opt, SynthResult* out) {
  sample_rows(
      1, params.actuators.offset, rows, opt,
      [](const sim::Row& r) {
        std::array<double, kJoints> w{};
        for (int k = 0; k < kFourBarJoints; ++k) w[k] = sim::four_bar_omega_rel(r, k);
        return w;
      },
      out);
}

SynthResult synthesize_log(const FourBarParams& params, const sim::FourBarLoadFunction& loads,
                           const sim::Initial& initial, const SynthOptions& opt) {
  SynthResult out;
  if (opt.multisine) {
    out.status = Status::Error(StatusCode::kInvalidInput,
                               "the built-in multi-sine drives the five-bar's two cranks; a "
                               "four-bar's log follows the scene's loads.M1");
    return out;
  }
  sim::Options so = opt.sim;
  so.duration = opt.duration;
  so.output_step = 1.0 / opt.rate_hz;
  const sim::Result res = sim::simulate(params, loads, initial, so);
  out.stats = res.stats;
  out.status = res.status;
  if (res.status.ok()) sample_log(params, res.rows, opt, &out);
  return out;
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
