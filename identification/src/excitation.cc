// Excitation design over any mechanism: the Fisher information, the Fourier motion, the design
// problem (a motion's evaluation; the std identify would report: excitation_prediction.cc; the
// five-bar's information columns: excitation_five_bar.cc).
#include "fivebar/identification/excitation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <thread>

#include <ceres/jet.h>
#include <Eigen/Dense>

#include "fivebar/identification/identify.h"
#include "fivebar/identification/rates.h"
#include "fivebar/identification/synth.h"
#include "fivebar/model/inertial.h"
#include "fivebar/model/rest_rule.h"
#include "jet_dynamics.h"
#include "noise_model.h"
#include "excitation_shared.h"
#include "setup_shared.h"

namespace fivebar::identification {

namespace {

/// Smooth lower bound of max_i v_i: the log-mean-exp (never above the maximum).
double soft_max(const std::vector<double>& v, double rho, std::vector<double>* weights) {
  const double m = *std::max_element(v.begin(), v.end());
  double sum = 0;
  weights->resize(v.size());
  for (size_t i = 0; i < v.size(); ++i) sum += ((*weights)[i] = std::exp(rho * (v[i] - m)));
  for (double& w : *weights) w /= sum;
  return m + std::log(sum / v.size()) / rho;
}

}  // namespace

bool parse_groups(const std::string& list, DesignGroups* g, std::string* bad) {
  std::array<bool, 3> on{};
  if (!parse_group_list(list, &on, bad)) return false;
  g->friction = on[0];
  g->inertia = on[1];
  g->actuator = on[2];
  return true;
}

Eigen::MatrixXd fisher_information(const std::vector<Eigen::MatrixXd>& jacobians, double sigma) {
  if (jacobians.empty()) return {};
  const int P = static_cast<int>(jacobians.front().cols());
  Eigen::MatrixXd F = Eigen::MatrixXd::Zero(P, P);
  // a sample whose reactions vanish (a mechanism at rest without gravity or loads) has no
  // derivative of their norms: it carries no information, and identify's rest rule leaves it out
  for (const Eigen::MatrixXd& J : jacobians) {
    if (J.rows() == 0 || !J.allFinite()) continue;
    // F += J^T J: each entry plus the sum of its products over J's rows in order (the
    // product's own sums, bit for bit), the lower triangle mirrored; columns as J's storage
    const Eigen::Index R = J.rows();
    const double* j = J.data();
    double* f = F.data();
    for (Eigen::Index b = 0; b < P; ++b) {
      for (Eigen::Index a = b; a < P; ++a) {
        double sum = j[a * R] * j[b * R];
        for (Eigen::Index r = 1; r < R; ++r) sum += j[a * R + r] * j[b * R + r];
        f[b * P + a] += sum;
      }
    }
  }
  for (Eigen::Index b = 0; b < P; ++b) {
    for (Eigen::Index a = b + 1; a < P; ++a) F(b, a) = F(a, b);
  }
  return F / (sigma * sigma);
}

// ---------------------------------------------------------------------------------------------
// Fourier motion

FourierMotion::FourierMotion(int harmonics, double period, double ramp, std::array<double, 2> start,
                             int dof)
    : h_(std::max(1, harmonics)), period_(period), ramp_(ramp), start_(start), dof_(dof) {}

void FourierMotion::basis(double t, std::vector<std::array<double, 3>>* d) const {
  const double w = 2 * M_PI / period_;
  d->assign(per_joint(), {0, 0, 0});
  // the shapes psi_v and their first two derivatives
  (*d)[0] = {t, 1, 0};
  for (int l = 1; l <= h_; ++l) {
    const double sl = std::sin(l * w * t), cl = std::cos(l * w * t), lw = l * w;
    (*d)[l] = {sl, lw * cl, -lw * lw * sl};
    (*d)[h_ + l] = {cl - 1, -lw * sl, -lw * lw * cl};
  }
  // times the ramp r: (r psi)' = r' psi + r psi', (r psi)'' = r'' psi + 2 r' psi' + r psi''
  double r = 1, r1 = 0, r2 = 0;
  if (ramp_ > 0 && t < ramp_) {
    const double u = std::max(0.0, t / ramp_);
    r = u * u * u * (10 + u * (-15 + 6 * u));
    r1 = 30 * u * u * (1 + u * (-2 + u)) / ramp_;
    r2 = 60 * u * (1 + u * (-3 + 2 * u)) / (ramp_ * ramp_);
  }
  for (auto& v : *d) v = {r * v[0], r1 * v[0] + r * v[1], r2 * v[0] + 2 * r1 * v[1] + r * v[2]};
}

MotionState FourierMotion::state(const std::vector<double>& x, double t) const {
  std::vector<std::array<double, 3>> d;
  basis(t, &d);
  std::array<std::array<double, 3>, 2> q{};
  for (int j = 0; j < kDof; ++j) q[j][0] = start_[j];
  for (int j = 0; j < dof_; ++j) {
    for (int v = 0; v < per_joint(); ++v) {
      for (int k = 0; k < 3; ++k) q[j][k] += x[j * per_joint() + v] * d[v][k];
    }
  }
  return {q[0][0], q[1][0], q[0][1], q[1][1], q[0][2], q[1][2]};
}

std::vector<double> FourierMotion::fit(const std::vector<double>& t, const std::vector<double>& th1,
                                       const std::vector<double>& th2) const {
  const int n = static_cast<int>(t.size()), pj = per_joint();
  Eigen::MatrixXd A(n, pj);
  Eigen::MatrixXd b(n, 2);
  std::vector<std::array<double, 3>> d;
  for (int i = 0; i < n; ++i) {
    basis(t[i], &d);
    for (int v = 0; v < pj; ++v) A(i, v) = d[v][0];
    b(i, 0) = th1[i] - start_[0];
    b(i, 1) = th2[i] - start_[1];
  }
  const Eigen::MatrixXd c = A.colPivHouseholderQr().solve(b);
  std::vector<double> x(num_variables());
  for (int j = 0; j < dof_; ++j) {
    for (int v = 0; v < pj; ++v) x[j * pj + v] = c(v, j);
  }
  return x;
}

// ---------------------------------------------------------------------------------------------
// Design problem

struct ExcitationProblem::Derivs {
  SampleTerms v;                            // at the sample
  std::array<SampleTerms, 6> d;             // d/ds of J, M, sine, w (s: th1, th2, w1, w2, a1, a2)
  MotionState s;
};

ExcitationProblem::ExcitationProblem(const Params<double>& scene,
                                     std::function<Loads<double>(double)> loads,
                                     std::array<double, 2> start, const ExcitationOptions& options)
    : ExcitationProblem(
          five_bar_excitation(scene, design_parameters(scene, options.groups), std::move(loads)),
          start, options) {}

ExcitationProblem::ExcitationProblem(std::shared_ptr<const ExcitationMechanism> mechanism,
                                     std::array<double, 2> start, const ExcitationOptions& options)
    : mech_(std::move(mechanism)),
      opt_(options),
      motion_(options.harmonics, options.duration / std::max(1, options.periods), options.ramp,
              start, mech_->dof()) {
  // a count that is not a multiple of the periods samples every period at other phases
  int n = std::max(8, options.design_samples);
  if (n % std::max(1, options.periods) == 0) ++n;
  for (int i = 0; i < n; ++i) times_.push_back(options.duration * (i + 0.5) / n);
  objective_samples_ = n;
  for (double t : options.extra_times) times_.push_back(t);
}

int ExcitationProblem::per_sample_constraints() const {
  int c = 2 * mech_->dof() + 1;  // +-M_j, sine
  for (int j = 0; j < mech_->dof(); ++j) c += std::isfinite(opt_.theta_lo[j]) ? 2 : 0;
  return c;
}

int ExcitationProblem::constraint_kinds() const {
  int k = 2;  // torque, sine
  for (int j = 0; j < mech_->dof(); ++j) k += std::isfinite(opt_.theta_lo[j]) ? 1 : 0;
  return k;
}

int ExcitationProblem::blocks() const {
  return std::max(1, std::min(static_cast<int>(times_.size()), opt_.constraint_blocks));
}

int ExcitationProblem::num_constraints() const {
  return blocks() * constraint_kinds() + reversal_constraints();
}

void ExcitationProblem::aggregate(const std::vector<double>& raw, const std::vector<double>& raw_grad,
                                  bool grad, DesignValue* out) const {
  const int N = static_cast<int>(times_.size()), n = num_variables(), ps = per_sample_constraints();
  const int nb = blocks(), kinds = constraint_kinds();
  // kind of each per-sample row: +-M_j -> torque; sine; theta1 range; theta2 range
  const int nt = 2 * mech_->dof();  // torque rows
  std::vector<int> kind(ps);
  for (int r = 0; r < ps; ++r) kind[r] = r < nt ? 0 : r == nt ? 1 : 2 + (r - nt - 1) / 2;
  if (ps > nt + 1 && !std::isfinite(opt_.theta_lo[0])) {
    for (int r = nt + 1; r < ps; ++r) kind[r] = 2;
  }
  const double rho = opt_.aggregation_sharpness;
  for (int b = 0; b < nb; ++b) {
    const int i0 = b * N / nb, i1 = (b + 1) * N / nb;
    for (int k = 0; k < kinds; ++k) {
      std::vector<int> rows;
      double top = -std::numeric_limits<double>::infinity();
      for (int i = i0; i < i1; ++i) {
        for (int r = 0; r < ps; ++r) {
          if (kind[r] != k) continue;
          rows.push_back(i * ps + r);
          top = std::max(top, raw[i * ps + r]);
        }
      }
      // KS upper bound of the block's maximum: top + log(sum exp(rho (g - top))) / rho
      double sum = 0;
      for (int q : rows) sum += std::exp(rho * (raw[q] - top));
      const int row = b * kinds + k;
      out->constraints[row] = top + std::log(sum) / rho;
      if (!grad) continue;
      double* g = &out->constraints_grad[static_cast<size_t>(row) * n];
      for (int q : rows) {
        const double wq = std::exp(rho * (raw[q] - top)) / sum;
        for (int v = 0; v < n; ++v) g[v] += wq * raw_grad[static_cast<size_t>(q) * n + v];
      }
    }
  }
}

Status ExcitationProblem::sample(const std::vector<double>& x, int i, bool grad, Derivs* d) const {
  d->s = motion_.state(x, times_[i]);
  const double t = times_[i];
  Status st = mech_->terms(t, d->s, nullptr, &d->v);
  if (!st.ok() || !grad) return st;
  const std::array<double, 6> base = {d->s.th1, d->s.th2, d->s.w1, d->s.w2, d->s.a1, d->s.a2};
  for (int c = 0; c < 6; ++c) {
    if (c % 2 >= mech_->dof()) continue;  // a crank the mechanism does not have
    // forward differences (one Jet evaluation per motion variable) at the sample's slip signs
    const double h = 1e-7 * std::max(1.0, std::abs(base[c]));
    std::array<double, 6> b = base;
    b[c] += h;
    SampleTerms plus;
    st = mech_->terms(t, {b[0], b[1], b[2], b[3], b[4], b[5]}, &d->v.slip, &plus);
    if (!st.ok()) return st;
    SampleTerms& o = d->d[c];
    o.J = (plus.J - d->v.J) / h;
    o.M1 = (plus.M1 - d->v.M1) / h;
    o.M2 = (plus.M2 - d->v.M2) / h;
    o.sine = (plus.sine - d->v.sine) / h;
    for (int k = 0; k < kJoints; ++k) o.w[k] = (plus.w[k] - d->v.w[k]) / h;
  }
  return Status::Ok();
}

double ExcitationProblem::criterion_value(const Eigen::MatrixXd& F, Eigen::MatrixXd* dF) const {
  const DesignParameters& dp = mech_->parameters();
  return design_criterion(F, dp.scale, dp.nominal, opt_.regularization, opt_.criterion, dF);
}

namespace {

/// log of a p-norm of the diagonal of R^-1 over the parameters with a non-zero nominal, halved
/// (a std), and its derivative with respect to R
double worst_std_value(const Eigen::MatrixXd& Rinv, const std::vector<double>& nominal,
                       Eigen::MatrixXd* W) {
  constexpr double kP = 16;
  const int P = static_cast<int>(Rinv.rows());
  const bool any = std::any_of(nominal.begin(), nominal.end(), [](double v) { return v != 0; });
  double top = 0;
  for (int i = 0; i < P; ++i) {
    if (!any || nominal[i] != 0) top = std::max(top, Rinv(i, i));
  }
  double sum = 0;
  Eigen::VectorXd c = Eigen::VectorXd::Zero(P);
  for (int i = 0; i < P; ++i) {
    if (any && nominal[i] == 0) continue;
    c(i) = std::pow(Rinv(i, i) / top, kP - 1);
    sum += c(i) * Rinv(i, i) / top;
  }
  // value = 0.5 log (sum v^p)^(1/p); dvalue/dv_i = 0.5 v_i^(p-1) / sum v^p; dv_i/dR = -Rinv e_i e_i' Rinv
  c *= 0.5 / (sum * top);
  *W = -(Rinv * c.asDiagonal() * Rinv);
  return 0.5 * (std::log(top) + std::log(sum) / kP);
}

}  // namespace

double design_criterion(const Eigen::MatrixXd& F, const std::vector<double>& scale_v,
                        const std::vector<double>& nominal, double regularization,
                        Criterion criterion, Eigen::MatrixXd* dF) {
  const int P = static_cast<int>(F.rows());
  const Eigen::VectorXd scale = Eigen::Map<const Eigen::VectorXd>(scale_v.data(), P);
  const Eigen::MatrixXd Fs = scale.asDiagonal() * F * scale.asDiagonal();
  const double lambda = regularization * Fs.trace() / P;
  const Eigen::MatrixXd R = Fs + lambda * Eigen::MatrixXd::Identity(P, P);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(R);
  const Eigen::VectorXd ev = es.eigenvalues().cwiseMax(1e-300);
  const Eigen::MatrixXd& V = es.eigenvectors();
  double value = 0;
  Eigen::MatrixXd W;  // d value / d R
  if (criterion == Criterion::kDOptimal) {
    value = -ev.array().log().sum() / P;  // minimize -log det / P
    W = -(V * ev.cwiseInverse().asDiagonal() * V.transpose()) / P;
  } else if (criterion == Criterion::kCondition) {
    value = std::log(ev(P - 1) / ev(0));
    W = V.col(P - 1) * V.col(P - 1).transpose() / ev(P - 1) - V.col(0) * V.col(0).transpose() / ev(0);
  } else {
    value = worst_std_value(V * ev.cwiseInverse().asDiagonal() * V.transpose(), nominal, &W);
  }
  if (dF) {
    // R = Fs + lambda(Fs) I with lambda = reg tr(Fs) / P; then Fs = S F S
    const Eigen::MatrixXd Ws = W + (regularization / P) * W.trace() * Eigen::MatrixXd::Identity(P, P);
    *dF = scale.asDiagonal() * Ws * scale.asDiagonal();
  }
  return value;
}

void ExcitationProblem::add_sample_constraints(int i, const Derivs& d, bool grad,
                                               const std::vector<std::array<double, 3>>& basis,
                                               std::vector<double>* raw,
                                               std::vector<double>* raw_grad) const {
  const int n = num_variables(), pj = motion_.per_joint();
  const double lim = opt_.torque_limit, keep = 1.0 - opt_.torque_margin;
  // value and d/ds (six motion variables) of every constraint of this sample
  std::vector<std::pair<double, std::array<double, 6>>> cs;
  auto of = [&](auto member, double a, double b) {  // a * member / b - ...
    std::array<double, 6> g{};
    for (int c = 0; c < 6; ++c) g[c] = a * member(d.d[c]) / b;
    return g;
  };
  auto m1 = [](const SampleTerms& t) { return t.M1; };
  auto m2 = [](const SampleTerms& t) { return t.M2; };
  auto sine = [](const SampleTerms& t) { return t.sine; };
  const int dof = mech_->dof();
  cs.push_back({d.v.M1 / lim - keep, of(m1, 1, lim)});
  cs.push_back({-d.v.M1 / lim - keep, of(m1, -1, lim)});
  if (dof > 1) {
    cs.push_back({d.v.M2 / lim - keep, of(m2, 1, lim)});
    cs.push_back({-d.v.M2 / lim - keep, of(m2, -1, lim)});
  }
  cs.push_back({1.0 - d.v.sine / opt_.singular_margin, of(sine, -1, opt_.singular_margin)});
  const double th[2] = {d.s.th1, d.s.th2};
  for (int j = 0; j < dof; ++j) {
    if (!std::isfinite(opt_.theta_lo[j])) continue;
    const double span = opt_.theta_hi[j] - opt_.theta_lo[j];
    std::array<double, 6> g{};
    g[j] = 1.0 / span;
    cs.push_back({(th[j] - opt_.theta_hi[j]) / span, g});
    g[j] = -1.0 / span;
    cs.push_back({(opt_.theta_lo[j] - th[j]) / span, g});
  }
  const int row0 = i * per_sample_constraints();
  for (size_t r = 0; r < cs.size(); ++r) {
    (*raw)[row0 + r] = cs[r].first;
    if (!grad) continue;
    double* g = &(*raw_grad)[(row0 + r) * n];
    for (int j = 0; j < dof; ++j) {
      for (int v = 0; v < pj; ++v) {
        // s = (th1, th2, w1, w2, a1, a2): crank j's angle, rate, acceleration at 0+j, 2+j, 4+j
        g[j * pj + v] = cs[r].second[j] * basis[v][0] + cs[r].second[2 + j] * basis[v][1] +
                        cs[r].second[4 + j] * basis[v][2];
      }
    }
  }
}

void ExcitationProblem::add_reversal_constraints(
    const std::vector<Derivs>& all, bool grad,
    const std::vector<std::vector<std::array<double, 3>>>& basis, DesignValue* out) const {
  const int n = num_variables(), pj = motion_.per_joint();
  const int row0 = blocks() * constraint_kinds();
  const double vr = opt_.reversal_rate, rho = 10.0 / vr;
  for (int k = 0; k < mech_->joints(); ++k) {
    for (int sgn : {+1, -1}) {
      std::vector<double> v(all.size()), wts;
      for (size_t i = 0; i < all.size(); ++i) v[i] = sgn * all[i].v.w[k];
      const double sm = soft_max(v, rho, &wts);
      const int row = row0 + 2 * k + (sgn > 0 ? 0 : 1);
      out->constraints[row] = 1.0 - sm / vr;
      if (!grad) continue;
      double* g = &out->constraints_grad[static_cast<size_t>(row) * n];
      for (size_t i = 0; i < all.size(); ++i) {
        for (int j = 0; j < mech_->dof(); ++j) {
          for (int q = 0; q < pj; ++q) {
            double dw = 0;
            for (int o = 0; o < 3; ++o) dw += all[i].d[2 * o + j].w[k] * basis[i][q][o];
            g[j * pj + q] -= wts[i] * sgn * dw / vr;
          }
        }
      }
    }
  }
}

Status ExcitationProblem::evaluate(const std::vector<double>& x, bool grad, DesignValue* out) const {
  const int N = static_cast<int>(times_.size()), n = num_variables(), m = num_constraints();
  std::vector<Derivs> all(N);
  std::vector<Status> status(N);
  detail::parallel_for(N, [&](int i) { status[i] = sample(x, i, grad, &all[i]); });
  for (int i = 0; i < N; ++i) {
    if (!status[i].ok()) return status[i];
  }
  std::vector<std::vector<std::array<double, 3>>> basis(N);
  for (int i = 0; i < N; ++i) motion_.basis(times_[i], &basis[i]);
  // Fisher of the log: each design sample stands for rate_hz * duration / N0 log samples
  const int N0 = objective_samples_;
  const double weight = opt_.rate_hz * opt_.duration / N0;
  std::vector<Eigen::MatrixXd> Js(N0);
  for (int i = 0; i < N0; ++i) Js[i] = all[i].v.J;
  const Eigen::MatrixXd F = weight * fisher_information(Js, opt_.torque_noise) +
                            detail::prior_fisher(mech_->parameters());
  Eigen::MatrixXd G;
  out->objective = criterion_value(F, grad ? &G : nullptr);
  out->constraints.assign(m, 0.0);
  out->objective_grad.assign(n, 0.0);
  out->constraints_grad.assign(grad ? static_cast<size_t>(m) * n : 0, 0.0);
  const double c = 2.0 * weight / (opt_.torque_noise * opt_.torque_noise);
  const int pj = motion_.per_joint();
  const int ps = per_sample_constraints();
  std::vector<double> raw(static_cast<size_t>(N) * ps), raw_grad(grad ? raw.size() * n : 0, 0.0);
  for (int i = 0; i < N; ++i) {
    add_sample_constraints(i, all[i], grad, basis[i], &raw, &raw_grad);
    if (!grad || i >= N0) continue;
    // d Phi / d s_c = 2 w / sigma^2 sum (J G) .* dJ/ds_c
    const Eigen::MatrixXd JG = all[i].v.J * G;
    std::array<double, 6> ds{};
    for (int cc = 0; cc < 6; ++cc) {
      if (cc % 2 < mech_->dof()) ds[cc] = c * JG.cwiseProduct(all[i].d[cc].J).sum();
    }
    for (int j = 0; j < mech_->dof(); ++j) {
      for (int v = 0; v < pj; ++v) {
        out->objective_grad[j * pj + v] += ds[j] * basis[i][v][0] + ds[2 + j] * basis[i][v][1] +
                                           ds[4 + j] * basis[i][v][2];
      }
    }
  }
  aggregate(raw, raw_grad, grad, out);
  add_reversal_constraints(all, grad, basis, out);
  return Status::Ok();
}

double worst_relative_std(const ExcitationReport& r) {
  double worst = 0;
  for (double v : r.relative_std) {
    if (std::isfinite(v)) worst = std::max(worst, v);
  }
  return worst;
}

}  // namespace fivebar::identification
