// Excitation design: Fisher information by Jets, the Fourier motion, the design problem.
#include "fivebar/identification/excitation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <thread>

#include <ceres/jet.h>
#include <Eigen/Dense>

#include "fivebar/identification/rates.h"
#include "fivebar/model/inertial.h"
#include "fivebar/model/rest_rule.h"
#include "jet_dynamics.h"
#include "noise_model.h"
#include "setup_shared.h"

namespace fivebar::identification {

namespace stages {
/// identify's rest rule on the five-bar (stage_samples.cc; declared in identify_stages.h, whose
/// Ceres stages this unit does not need)
bool held_sample(const Params<double>& p, const Sample& s, const RestThresholds& rest,
                 double angle_noise);
}  // namespace stages

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Runs f(i) for i in [0, n) on up to two threads (the machine's budget), in contiguous chunks.
template <typename F>
void parallel_for(int n, F&& f) {
  const int workers = std::min(2, std::max(1, static_cast<int>(std::thread::hardware_concurrency())));
  if (workers == 1 || n < 64) {
    for (int i = 0; i < n; ++i) f(i);
    return;
  }
  const int half = n / 2;
  std::thread other([&] {
    for (int i = half; i < n; ++i) f(i);
  });
  for (int i = 0; i < half; ++i) f(i);
  other.join();
}

/// The Jet part of sample_terms: friction and inertial columns of dM/dparameter.
template <int N>
Status jet_columns(const Params<double>& scene, const DesignParameters& dp, const Loads<double>& L,
                   const MotionState& s, const JointModes* slip, SampleTerms* out) {
  using J = ceres::Jet<double, N>;
  Params<J> p = scene.template cast<J>();
  std::vector<J> x(std::max(1, dp.jet_size()));
  for (int i = 0; i < dp.jet_size(); ++i) x[i] = J(dp.nominal[i], i);
  if (dp.friction > 0) dp.layout.apply(x.data(), &p.friction);
  if (dp.inertial > 0) set_standard_inertial(x.data() + dp.friction, &p);
  EvalOptions eo;
  eo.want_angles = false;
  Evaluation<J> ev;
  const Status st = inverse_dynamics(p, L.template cast<J>(), J(s.th1), J(s.th2), J(s.w1), J(s.w2),
                                     J(s.a1), J(s.a2), slip, eo, &ev);
  if (!st.ok()) return st;
  out->M1 = ev.M1.a;
  out->M2 = ev.M2.a;
  for (int c = 0; c < dp.jet_size(); ++c) {
    out->J(0, c) = ev.M1.v[c];
    out->J(1, c) = ev.M2.v[c];
  }
  out->sine = std::abs(ev.kin.sin43.a);
  for (int k = 0; k < kJoints; ++k) out->w[k] = ev.w[k].a;
  out->slip = ev.slip;
  return Status::Ok();
}

/// Actuator columns in closed form: tau_j = M_j + offset_j + Fc_j sign(w_j) + Fv_j w_j.
void actuator_columns(const DesignParameters& dp, const MotionState& s, SampleTerms* out) {
  if (dp.actuator == 0) return;
  const int c0 = dp.friction + dp.inertial;
  const double w[2] = {s.w1, s.w2};
  for (int j = 0; j < kActuators; ++j) {
    const int c = c0 + kActuatorPerMotor * j;
    out->J(j, c) = 1.0;
    out->J(j, c + 1) = (w[j] > 0) - (w[j] < 0);
    out->J(j, c + 2) = w[j];
  }
}

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

DesignParameters design_parameters(const Params<double>& scene, const DesignGroups& g) {
  DesignParameters dp;
  dp.layout.law = FrictionLaw::kCoulombViscous;
  dp.layout.per_joint = g.per_joint;
  auto add = [&](const std::string& name, double nominal, double typical) {
    dp.names.push_back(name);
    dp.nominal.push_back(nominal);
    dp.scale.push_back(std::abs(nominal) > 0 ? std::abs(nominal) : typical);
  };
  if (g.friction) {
    const std::vector<std::string> names = dp.layout.names();
    const std::vector<double> x = dp.layout.extract(scene.friction);
    for (size_t i = 0; i < names.size(); ++i) add(names[i], x[i], 1e-3);
    dp.friction = static_cast<int>(names.size());
  }
  if (g.inertia) {
    const std::array<double, kInertialParams> pi = standard_inertial(scene);
    for (int i = 0; i < kInertialParams; ++i) add(inertial_name(i), pi[i], 1e-3);
    dp.inertial = kInertialParams;
  }
  if (g.actuator) {
    for (int j = 1; j <= 2; ++j) {
      add("offset_" + std::to_string(j), 0.0, 0.1);
      add("actuator_coulomb_" + std::to_string(j), 0.0, 0.1);
      add("actuator_viscous_" + std::to_string(j), 0.0, 0.01);
    }
    dp.actuator = 2 * kActuatorPerMotor;
  }
  return dp;
}

Status sample_terms(const Params<double>& scene, const DesignParameters& dp, const Loads<double>& L,
                    const MotionState& s, const JointModes* slip, SampleTerms* out) {
  out->J = Eigen::MatrixXd::Zero(2, dp.size());
  // the Jet widths instantiated: the active parameters of each group combination (the actuator
  // terms alone, 0 Jet parameters, take the narrowest: their columns are in closed form)
  using Columns = Status (*)(const Params<double>&, const DesignParameters&, const Loads<double>&,
                             const MotionState&, const JointModes*, SampleTerms*);
  static const std::pair<int, Columns> kWidths[] = {
      {2, &jet_columns<2>},   {10, &jet_columns<10>}, {16, &jet_columns<16>},
      {18, &jet_columns<18>}, {26, &jet_columns<26>}};
  Columns columns = &jet_columns<26>;  // the widest: every group
  for (const auto& [width, fn] : kWidths) {
    if (dp.jet_size() <= width) {
      columns = fn;
      break;
    }
  }
  const Status st = columns(scene, dp, L, s, slip, out);
  if (!st.ok()) return st;
  actuator_columns(dp, s, out);
  return Status::Ok();
}

Eigen::MatrixXd fisher_information(const std::vector<Eigen::MatrixXd>& jacobians, double sigma) {
  if (jacobians.empty()) return {};
  const int P = static_cast<int>(jacobians.front().cols());
  Eigen::MatrixXd F = Eigen::MatrixXd::Zero(P, P);
  for (const Eigen::MatrixXd& J : jacobians) F.noalias() += J.transpose() * J;
  return F / (sigma * sigma);
}

// ---------------------------------------------------------------------------------------------
// The five-bar as an ExcitationMechanism

namespace {

class FiveBarExcitation : public ExcitationMechanism {
 public:
  FiveBarExcitation(const Params<double>& scene, DesignParameters dp,
                    std::function<Loads<double>(double)> loads)
      : scene_(scene), dp_(std::move(dp)), loads_(std::move(loads)) {}
  int dof() const override { return kDof; }
  int joints() const override { return kJoints; }
  std::string joint_name(int k) const override {
    static const char* const kNames[] = {"O", "B", "C", "D", "D0"};
    return kNames[k];
  }
  std::string type() const override { return "five_bar"; }
  const DesignParameters& parameters() const override { return dp_; }
  Status terms(double t, const MotionState& s, const JointModes* slip,
               SampleTerms* out) const override {
    return sample_terms(scene_, dp_, loads_(t), s, slip, out);
  }
  Status kinematic_jacobian(double t, const MotionState& q,
                            Eigen::Matrix<double, 2, 6>* D) const override {
    Sample s;
    s.t = t, s.th1 = q.th1, s.th2 = q.th2, s.w1 = q.w1, s.w2 = q.w2, s.a1 = q.a1, s.a2 = q.a2;
    s.loads = loads_(t);
    const std::vector<double> x = dp_.layout.extract(scene_.friction);
    if (!detail::kinematic_jacobian(scene_, dp_.layout, x.data(), s, EvalOptions{}, D)) {
      return Status::Error(StatusCode::kSolverFailed,
                           "the torques' derivative along the motion failed");
    }
    return Status::Ok();
  }
  bool fixed_filter(SgOptions*) const override { return false; }
  bool block_sandwich() const override { return false; }
  /// identify's rule (stage_samples.cc: rest_rule, held_sample): thresholds kRestSigmas std of
  /// the filtered rates and accelerations, the angle noise through the joint rates' dependence
  /// on the pose
  bool at_rest(double t, const MotionState& q, double g1, double g2,
               double angle_noise) const override {
    if (!(angle_noise > 0)) return false;
    Sample s;
    s.t = t, s.th1 = q.th1, s.th2 = q.th2, s.w1 = q.w1, s.w2 = q.w2, s.a1 = q.a1, s.a2 = q.a2;
    return stages::held_sample(scene_, s, rest_thresholds(g1 * angle_noise, g2 * angle_noise),
                               angle_noise);
  }
  void rest_gains(const std::vector<double>& t, const SgOptions& sg, double* g1,
                  double* g2) const override {
    stages::sg_noise_gains(t, sg, g1, g2);
  }

 private:
  Params<double> scene_;
  DesignParameters dp_;
  std::function<Loads<double>(double)> loads_;
};

}  // namespace

std::shared_ptr<const ExcitationMechanism> five_bar_excitation(
    const Params<double>& scene, const DesignParameters& dp,
    std::function<Loads<double>(double)> loads) {
  return std::make_shared<FiveBarExcitation>(scene, dp, std::move(loads));
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
    : ExcitationProblem(five_bar_excitation(scene, design_parameters(scene, options.groups),
                                            std::move(loads)),
                        start, options) {}

ExcitationProblem::ExcitationProblem(std::shared_ptr<const ExcitationMechanism> mechanism,
                                     std::array<double, 2> start, const ExcitationOptions& options)
    : mech_(std::move(mechanism)),
      opt_(options),
      motion_(options.harmonics, options.duration / std::max(1, options.periods), options.ramp, start,
              mech_->dof()) {
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
  parallel_for(N, [&](int i) { status[i] = sample(x, i, grad, &all[i]); });
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
  const Eigen::MatrixXd F = weight * fisher_information(Js, opt_.torque_noise);
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
  parallel_for(N, [&](int i) { status[i] = mech.terms(t[i], states[i], nullptr, &terms[i]); });
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
    Js[i] = terms[i].J;
    rates[i] = terms[i].w;
    const double th[2] = {states[i].th1, states[i].th2};
    for (int j = 0; j < mech.dof(); ++j) {
      out->theta_min[j] = std::min(out->theta_min[j], th[j]);
      out->theta_max[j] = std::max(out->theta_max[j], th[j]);
    }
  }
  out->reversals = count_reversals(rates);
  out->fisher = fisher_information(Js, torque_noise);
  const int P = dp.size();
  const Eigen::VectorXd scale = Eigen::Map<const Eigen::VectorXd>(dp.scale.data(), P);
  const Eigen::MatrixXd Fs = scale.asDiagonal() * out->fisher * scale.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Fs);
  const Eigen::VectorXd ev = es.eigenvalues();
  out->condition_number = ev(0) > 0 ? ev(P - 1) / ev(0) : kNaN;
  out->log_det_scaled = ev(0) > 0 ? ev.array().log().sum() : -std::numeric_limits<double>::infinity();
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
    for (int e = 0; e < P; ++e) lost = lost || (inv(e) == 0 && std::abs(es.eigenvectors()(i, e)) > 1e-6);
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
using stages::kWindowExcess;

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
  Eigen::MatrixXd covariance;
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
               const std::array<double, 2>& angle_noise, int order)
      : mech_(mech), r_(r), s_(std::move(samples)), order_(order),
        angle_noise_(std::max(angle_noise[0], angle_noise[1])) {
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
      for (int k = 0; i > 0 && k < kJoints; ++k) flip = flip || (s_[i].w[k] > 0) != (s_[i - 1].w[k] > 0);
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
    parallel_for(size(), [&](int i) {
      maybe_rest_[i] = mech_.at_rest(r_.t[i], r_.states[i], g1, g2, angle_noise_) ? 1 : 0;
    });
  }

  /// the noise gains of the filter of half-window m, as identify's rest rule takes them
  void gains(int m, double* g1, double* g2) const {
    SgOptions filter;
    filter.half_window_s = m * dt_;
    filter.order = order_;
    mech_.rest_gains(r_.t, filter, g1, g2);
  }

  /// the filter of half-window m at a centred sample: the same at every one (uniform grid)
  Taps taps(int m) const {
    Taps out;
    out.m = m;
    SgOptions sg;
    sg.half_window_s = m * dt_;
    sg.order = order_;
    int lo = 0;
    savitzky_golay_taps(r_.t, m, sg, &lo, &out.d1, &out.d2);
    return out;
  }

  /// the expected torque residual over identify's noise level at half-window m (its residual
  /// rule: noise and bias add in quadrature), over about 2000 samples with a centred window
  double residual_ratio(int m) const {
    const Taps sg = taps(m);
    const int n = size(), step = std::max(1, (n - 2 * m) / 2000);
    Eigen::Vector2d b2 = Eigen::Vector2d::Zero(), v = b2;
    int count = 0;
    for (int i = m; i < n - m; i += step, ++count) {
      Eigen::Vector2d dM;
      detail::Sensitivity sens;
      at(i, sg, &dM, &sens);
      b2 += dM.cwiseAbs2();
      v += detail::propagated_variance(sens);
    }
    double ratio = 1;
    for (int j = 0; j < mech_.dof() && count > 0; ++j) {
      const double floor2 = noise_.torque[j] * noise_.torque[j] + v(j) / count;
      ratio = std::max(ratio, std::sqrt(1 + b2(j) / count / floor2));
    }
    return ratio;
  }

  /// covariance and bias of the coefficients over the samples whose window of half-width
  /// `exclude` spans no slip reversal and that identify's rest rule keeps, with rates from
  /// half-window m
  WindowPrediction predict(int m, int exclude) const {
    const Taps sg = taps(m);
    WindowPrediction out;
    const int n = size(), P = static_cast<int>(s_.front().J.cols());
    double g1 = 0, g2 = 0;
    gains(m, &g1, &g2);
    std::vector<int> used;
    for (int i = m; i < n - m; ++i) {
      const int a = std::max(0, i - exclude), b = std::min(n - 1, i + exclude);
      if (reversals_[b] - reversals_[a] != 0) continue;
      const bool maybe = maybe_rest_.empty() || maybe_rest_[i];
      if (maybe && mech_.at_rest(r_.t[i], r_.states[i], g1, g2, angle_noise_)) continue;
      used.push_back(i);
    }
    if (static_cast<int>(used.size()) <= P) return out;
    Eigen::MatrixXd J(2 * used.size(), P);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(P);
    std::vector<detail::Sensitivity> sens(used.size());
    for (size_t u = 0; u < used.size(); ++u) {
      Eigen::Vector2d dM;
      at(used[u], sg, &dM, &sens[u]);
      J.middleRows(2 * u, 2) = s_[used[u]].J;
      g += s_[used[u]].J.transpose() * dM;  // one Gauss-Newton step: the residual moves by -dM
    }
    const Eigen::MatrixXd H = J.transpose() * J;
    if (!H.allFinite()) return out;
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(H);
    const Eigen::VectorXd ev = es.eigenvalues();
    if (!(ev(0) > 1e-14 * ev(P - 1))) return out;  // the samples do not determine them all
    const Eigen::MatrixXd Hinv =
        es.eigenvectors() * ev.cwiseInverse().asDiagonal() * es.eigenvectors().transpose();
    const Eigen::MatrixXd S = mech_.block_sandwich() ? block_score_covariance(J, used, sens, m)
                                                     : detail::score_covariance(J, sens, noise_, n);
    out.covariance = Hinv * S * Hinv;
    out.bias = -Hinv * g;
    out.ok = out.covariance.allFinite();
    return out;
  }

 private:
  /// The expected meat of identify's block sandwich: blocks of used samples within 2 m + 1 log
  /// samples of the block's first (identify_four_bar.cc's block_sizes), each block's score
  /// covariance alone (the correlations between blocks, through the filter's overlapping
  /// windows, are not in the sandwich)
  Eigen::MatrixXd block_score_covariance(const Eigen::MatrixXd& J, const std::vector<int>& used,
                                         const std::vector<detail::Sensitivity>& sens, int m) const {
    const int P = static_cast<int>(J.cols()), span = 2 * m + 1;
    Eigen::MatrixXd S = Eigen::MatrixXd::Zero(P, P);
    for (size_t u0 = 0; u0 < used.size();) {
      size_t u1 = u0 + 1;
      while (u1 < used.size() && used[u1] - used[u0] < span) ++u1;
      // the block's noise samples lie within [used[u0] - m, used[u1 - 1] + m]: shift them to 0
      const int lo = std::max(0, used[u0] - m);
      std::vector<detail::Sensitivity> block(sens.begin() + u0, sens.begin() + u1);
      for (detail::Sensitivity& b : block) {
        for (int c = 0; c < 4; ++c) b.lo[c] -= lo;
      }
      const int width = std::min(size(), used[u1 - 1] + m + 1) - lo;
      S += detail::score_covariance(J.middleRows(2 * u0, 2 * (u1 - u0)), block, noise_, width);
      u0 = u1;
    }
    return S;
  }

  const ExcitationMechanism& mech_;
  const ExcitationReport& r_;
  std::vector<EivSample> s_;
  int order_;
  double angle_noise_;
  detail::SensorNoise noise_;
  std::vector<int> reversals_;
  std::vector<char> maybe_rest_;  ///< bound_rest's (empty: test every sample)
  double dt_ = 1;
};

/// The largest |bias| / std over the friction coefficients of a prediction.
double bias_in_std(const WindowPrediction& p, int friction) {
  double worst = 0;
  for (int i = 0; i < friction; ++i) {
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
  parallel_for(n, [&](int i) {
    SampleTerms terms;
    status[i] = mech.terms(r.t[i], r.states[i], nullptr, &terms);
    if (status[i].ok()) status[i] = mech.kinematic_jacobian(r.t[i], r.states[i], &(*samples)[i].D);
    if (!status[i].ok()) return;
    (*samples)[i].J = terms.J;
    (*samples)[i].w = terms.w;
  });
  for (int i = 0; i < n; ++i) {
    if (!status[i].ok()) {
      return Status::Error(status[i].code, "at t = " + digits3(r.t[i]) + " s: " + status[i].message);
    }
  }
  return Status::Ok();
}

}  // namespace

namespace {

/// The window identify's rules choose on the five-bar (predict_identified_std): the prediction
/// there into *chosen, the half-window into r->sg_half_window and r->window_choice.
void choose_window(EivPredictor* predictor, const DesignParameters& dp, ExcitationReport* r,
                   WindowPrediction* chosen) {
  const int n = static_cast<int>(r->t.size());
  const std::vector<int> cand = stages::window_candidates(n, predictor->dt(), SgOptions{}.order);
  predictor->bound_rest(cand.front());  // the candidates grow: the first's thresholds are the largest
  const EivPredictor& eiv = *predictor;
  // the residual rule: the largest candidate within the excess (scanned until the bias clearly
  // dominates), one below it past the second
  std::vector<double> ratio;
  for (size_t k = 0; k < cand.size(); ++k) {
    ratio.push_back(eiv.residual_ratio(cand[k]));
    if (k >= 2 && ratio[k] > 1.5 * *std::min_element(ratio.begin(), ratio.begin() + k)) break;
  }
  const double best = std::max(1.0, *std::min_element(ratio.begin(), ratio.end()));
  int rule = 0;
  for (size_t k = 0; k < ratio.size(); ++k) {
    if (ratio[k] <= best * (1 + kWindowExcess)) rule = static_cast<int>(k);
  }
  if (rule > 1) --rule;
  // the bias rule: from the residual rule's window down, the first within kBiasFraction std
  // (none: the residual rule's)
  int pick = rule;
  *chosen = eiv.predict(cand[rule], cand[rule]);
  std::string table;
  for (int k = rule; k >= 1 && chosen->ok; --k) {
    WindowPrediction p = k == rule ? *chosen : eiv.predict(cand[k], cand[k]);
    if (!p.ok) break;
    const double b = bias_in_std(p, dp.friction);
    table += (table.empty() ? "" : ", ") + std::to_string(cand[k]) + ": " + digits3(b);
    if (b <= kBiasFraction) {
      pick = k;
      *chosen = std::move(p);
      break;
    }
  }
  r->sg_half_window = cand[pick];
  r->window_choice = "half-window " + std::to_string(cand[rule]) +
                     " samples by the residual rule (expected ratio " + digits3(ratio[rule]) +
                     "), " + std::to_string(cand[pick]) + " by the bias rule (|bias| / std: " + table + ")";
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
  SgOptions fixed;
  const bool is_fixed = mech.fixed_filter(&fixed);
  EivPredictor eiv(mech, *r, std::move(samples), torque_noise, {angle_noise, angle_noise},
                         is_fixed ? fixed.order : SgOptions{}.order);
  WindowPrediction chosen;
  if (is_fixed) {
    const int m = sg_half_window(fixed, eiv.dt());
    chosen = eiv.predict(m, m);
    r->sg_half_window = m;
    r->window_choice = "half-window " + std::to_string(m) + " samples, order " +
                       std::to_string(fixed.order) + ": identify's filter for a " + mech.type();
    if (chosen.ok) {
      r->window_choice += " (its smoothing bias of the coefficients, |bias| / std: " +
                          digits3(bias_in_std(chosen, dp.friction)) + ")";
    }
  } else {
    choose_window(&eiv, dp, r, &chosen);
  }
  if (!chosen.ok) {  // no std identify could report: none predicted
    r->sg_half_window = 0;
    r->std_dev.assign(dp.size(), kNaN);
    r->relative_std.assign(dp.size(), kNaN);
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
