#include "fivebar/trajectory/problem.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <thread>

#include <ceres/jet.h>

#include "fivebar/model/kinematics.h"
#include "fivebar/model/names.h"
#include "fivebar/model/rest.h"
#include "fivebar/trajectory/quadrature.h"

namespace fivebar::trajectory {
namespace {

using Jet6 = ceres::Jet<double, 6>;

// fewer nodes than this per thread are evaluated on fewer threads (a thread costs ~20 us)
constexpr int kMinNodesPerThread = 32;

EvalOptions eval_options(const ProblemOptions& o) {
  EvalOptions e;
  e.singular_margin = 0.0;  // the margin is a constraint of the problem, not a failure
  e.friction_tol = o.friction_tol;
  return e;
}

// smooth |p| = sqrt(p^2 + eps^2) - eps
template <typename T>
T smooth_abs(const T& p, double eps) {
  using std::sqrt;
  return sqrt(p * p + T(eps * eps)) - T(eps);
}

// softplus eps log(1 + exp(p / eps)), a smooth max(0, p) above it by at most eps ln 2
template <typename T>
T softplus(const T& p, double eps) {
  using std::exp;
  using std::log;
  const T e = value_of(p) > 0.0 ? T(exp(-p / eps)) : T(exp(p / eps));
  const T tail = T(eps) * log(T(1.0) + e);
  return value_of(p) > 0.0 ? T(p + tail) : tail;
}

// the supply power of both motors from their powers p (M w + heat): max(0, .) exact or smoothed
template <typename T>
T supply_power(const std::array<T, 2>& p, const ProblemOptions& o, bool exact) {
  auto clip = [&](const T& v) {
    return exact ? (value_of(v) > 0.0 ? v : T(0.0)) : softplus(v, o.power_smoothing);
  };
  if (o.regeneration == Regeneration::kSharedBus) return clip(T(p[0] + p[1]));
  return clip(p[0]) + clip(p[1]);
}

// the powers of one node [W]: everything Energies integrates
template <typename T>
struct NodePowers {
  T dissipated{}, input{}, input_smooth{}, heat{}, supply{}, supply_smooth{};
};

// the powers of one state from its inverse dynamics
template <typename T>
NodePowers<T> node_powers(const Evaluation<T>& ev, const std::array<T, 6>& s,
                          const ProblemOptions& o) {
  NodePowers<T> out;
  out.dissipated = ev.P_diss;
  const std::array<T, 2> M = {ev.M1, ev.M2}, mech = {T(ev.M1 * s[2]), T(ev.M2 * s[3])};
  std::array<T, 2> electric;
  for (int a = 0; a < kActuators; ++a) {
    const T heat = o.winding_heat[a] * M[a] * M[a];
    out.heat += heat;
    out.input += value_of(mech[a]) < 0.0 ? T(-mech[a]) : mech[a];
    out.input_smooth += smooth_abs(mech[a], o.power_smoothing);
    electric[a] = mech[a] + heat;
  }
  out.supply = supply_power(electric, o, true);
  out.supply_smooth = supply_power(electric, o, false);
  return out;
}

// the integrand of objective o (the smoothed one of kInputEnergy and kSupplyEnergy)
template <typename T>
T integrand(const NodePowers<T>& pw, Objective o) {
  switch (o) {
    case Objective::kDissipatedEnergy: return pw.dissipated;
    case Objective::kInputEnergy: return pw.input_smooth;
    case Objective::kTotalDissipation: return pw.dissipated + pw.heat;
    case Objective::kSupplyEnergy: return pw.supply_smooth;
  }
  return pw.dissipated;
}

// integrand of the objective, M1 and M2 at one state (th1, th2, w1, w2, a1, a2); all the
// powers when asked
template <typename T>
Status node_values(const Params<T>& p, const Loads<T>& L, const std::array<T, 6>& s,
                   const ProblemOptions& o, T* f, T* M1, T* M2, NodePowers<T>* powers = nullptr) {
  Evaluation<T> ev;
  const Status st =
      inverse_dynamics(p, L, s[0], s[1], s[2], s[3], s[4], s[5], nullptr, eval_options(o), &ev);
  if (!st.ok()) return st;
  const NodePowers<T> pw = node_powers(ev, s, o);
  *f = integrand(pw, o.objective);
  *M1 = ev.M1;
  *M2 = ev.M2;
  if (powers) *powers = pw;
  return Status::Ok();
}

// c = cos^2(C) - (1 - m^2) at (th1, th2), with C the coupler angle at C, and its gradient
// (the model's coupler_cosine: smooth through the singular poses); |sin C| when asked
double coupler_constraint(const Params<double>& p, double th1, double th2, double margin,
                          double* d1, double* d2, double* abs_sine = nullptr) {
  Row2<double> g;
  const double cosC = coupler_cosine(p, th1, th2, d1 || d2 ? &g : nullptr);
  if (d1) *d1 = 2.0 * cosC * g[0];
  if (d2) *d2 = 2.0 * cosC * g[1];
  if (abs_sine) *abs_sine = cosC * cosC <= 1.0 ? std::sqrt(1.0 - cosC * cosC) : 0.0;
  return cosC * cosC - (1.0 - margin * margin);
}

// W_in and W_ext of trajectory rows (inverse_rows leaves them zero): the powers M1 w1 + M2 w2
// and M3 w3 + F . v_P integrated by the trapezoidal rule, the rule of E_diss in the same rows
Status add_work(const Params<double>& p, const sim::LoadFunction& loads,
                std::vector<sim::Row>* rows) {
  double prev_in = 0, prev_ext = 0;
  for (size_t i = 0; i < rows->size(); ++i) {
    sim::Row& r = (*rows)[i];
    Evaluation<double> ev;
    const Status st = inverse_dynamics(p, loads(r.t), r.theta[0], r.theta[1], r.omega[0],
                                       r.omega[1], r.alpha[0], r.alpha[1], nullptr,
                                       EvalOptions{}, &ev);
    if (!st.ok()) return st;
    const double dt = i == 0 ? 0.0 : r.t - (*rows)[i - 1].t;
    r.W_in = i == 0 ? 0.0 : (*rows)[i - 1].W_in + 0.5 * dt * (prev_in + ev.P_in);
    r.W_ext = i == 0 ? 0.0 : (*rows)[i - 1].W_ext + 0.5 * dt * (prev_ext + ev.P_ext);
    prev_in = ev.P_in;
    prev_ext = ev.P_ext;
  }
  return Status::Ok();
}

}  // namespace

namespace {
constexpr Named<Objective> kObjectiveNames[] = {
    {Objective::kTotalDissipation, "total_dissipation"},
    {Objective::kSupplyEnergy, "supply_energy"},
    {Objective::kDissipatedEnergy, "dissipated_energy"},
    {Objective::kInputEnergy, "input_energy"},
    {Objective::kDissipatedEnergy, "dissipated"},
    {Objective::kInputEnergy, "input"}};
constexpr Named<Regeneration> kRegenerationNames[] = {{Regeneration::kNone, "none"},
                                                      {Regeneration::kSharedBus, "shared_bus"}};
constexpr Named<EndAcceleration> kEndAccelerationNames[] = {{EndAcceleration::kFree, "free"},
                                                            {EndAcceleration::kZero, "zero"}};
}  // namespace

const char* objective_name(Objective o) { return name_in(kObjectiveNames, o); }

bool parse_objective(const std::string& name, Objective* out) {
  return parse_in(kObjectiveNames, name, out);
}

std::string objective_names() {
  return "total_dissipation, supply_energy, dissipated_energy, input_energy";
}

double TrajectoryProblem::heat_share(const double* x) const {
  if (!needs_winding(options_.objective)) return 0.0;
  Energies e;
  if (!energies(x, options_.quadrature_points, &e).ok()) return NAN;
  const double objective = options_.objective == Objective::kSupplyEnergy ? e.supply : e.total();
  return objective > 0.0 ? e.winding_heat / objective : NAN;
}

bool needs_winding(Objective o) {
  return o == Objective::kTotalDissipation || o == Objective::kSupplyEnergy;
}

const char* regeneration_name(Regeneration r) { return name_in(kRegenerationNames, r); }

bool parse_regeneration(const std::string& name, Regeneration* out) {
  return parse_in(kRegenerationNames, name, out);
}

const char* end_acceleration_name(EndAcceleration e) { return name_in(kEndAccelerationNames, e); }

bool parse_end_acceleration(const std::string& name, EndAcceleration* out) {
  return parse_in(kEndAccelerationNames, name, out);
}

double Energies::of(Objective o) const {
  switch (o) {
    case Objective::kDissipatedEnergy: return dissipated;
    case Objective::kInputEnergy: return input;
    case Objective::kTotalDissipation: return total();
    case Objective::kSupplyEnergy: return supply;
  }
  return dissipated;
}

Params<double> smoothed_params(const Params<double>& params, const ProblemOptions& options) {
  Params<double> p = params;
  if (!(p.friction.smoothing_velocity > 0.0)) {
    p.friction.smoothing_velocity = options.smoothing_velocity;
  }
  return p;
}

TrajectoryProblem::TrajectoryProblem(const Params<double>& params, const sim::LoadFunction& loads,
                                     const RestToRest& motion, const ProblemOptions& options)
    : params_(smoothed_params(params, options)),
      exact_params_(params),
      loads_(loads),
      motion_(motion),
      options_(options) {
  if (options.quadrature_points < 1) {
    throw std::invalid_argument("TrajectoryProblem: quadrature_points < 1");
  }
  // composite Gauss-Legendre: quadrature_points nodes per knot span; with free end
  // accelerations the torques step at the ends, which no Gauss node reaches: two nodes of weight
  // 0 there carry the constraints only
  const ClampedBasis& basis = motion_.basis();
  const bool ends = motion_.ends() == EndAcceleration::kFree;
  auto add = [&](double t, double weight) {
    Node node;
    node.t = t;
    node.weight = weight;
    node.basis = basis.at(t);
    node.loads = loads_(t);
    nodes_.push_back(node);
  };
  if (ends) add(0.0, 0.0);
  for (int s = 0; s < basis.spans(); ++s) {
    const Rule rule =
        gauss_legendre(options.quadrature_points, basis.span_begin(s), basis.span_end(s));
    for (size_t i = 0; i < rule.nodes.size(); ++i) add(rule.nodes[i], rule.weights[i]);
  }
  if (ends) add(motion_.duration(), 0.0);
}

std::array<double, 6> TrajectoryProblem::node_state(const double* x, const Node& node) const {
  std::array<double, 6> s{};
  for (int j = 0; j < kDof; ++j) {
    for (int i = 0; i <= kDegree; ++i) {
      const double cp = motion_.control_point(x, node.basis.first + i, j);
      for (int k = 0; k < 3; ++k) s[2 * k + j] += node.basis.d[k][i] * cp;
    }
  }
  return s;
}

Status TrajectoryProblem::evaluate(const double* x, bool want_gradients, Evaluated* out) const {
  return evaluate_as(x, want_gradients ? Gradients::kDense : Gradients::kNone, out);
}

Status TrajectoryProblem::evaluate_local(const double* x, Evaluated* out) const {
  return evaluate_as(x, Gradients::kLocal, out);
}

std::array<int, kLocalVariables> TrajectoryProblem::node_variables(int node) const {
  std::array<int, kLocalVariables> v{};
  for (int i = 0; i <= kDegree; ++i) {
    for (int j = 0; j < kDof; ++j) v[2 * i + j] = variable_of(nodes_[node].basis.first + i, j);
  }
  return v;
}

// one node: integrand, torques and (Jets) their gradients in the node state
Status TrajectoryProblem::node_pass(const Params<Jet6>* pj, const Node& node,
                                   const std::array<double, 6>& s, NodeValues* v) const {
  if (!pj) return node_values(params_, node.loads, s, options_, &v->f, &v->M1, &v->M2);
  // seed the node state: derivative k of the Jets is d/d s[k]
  std::array<Jet6, 6> sj;
  for (int k = 0; k < 6; ++k) sj[k] = Jet6(s[k], k);
  Jet6 fj, M1j, M2j;
  const Status st = node_values(*pj, node.loads.cast<Jet6>(), sj, options_, &fj, &M1j, &M2j);
  if (!st.ok()) return st;
  v->f = fj.a;
  v->M1 = M1j.a;
  v->M2 = M2j.a;
  for (int k = 0; k < 6; ++k) {
    v->df[k] = fj.v[k];
    v->dM1[k] = M1j.v[k];
    v->dM2[k] = M2j.v[k];
  }
  return Status::Ok();
}

// the gradients of node q by the chain rule, s[2 k + j] = sum_i basis.d[k][i] cp(j, first + i):
// the objective's share in local form (12 values), the three constraint rows' in the form `how`
// asks
void TrajectoryProblem::node_gradients(int q, const NodeValues& v, double ds1, double ds2,
                                       Gradients how, double* objective_grad,
                                       Evaluated* out) const {
  const Node& node = nodes_[q];
  const int nv = num_variables();
  const double lim = options_.torque_limit;
  const bool limited = std::isfinite(lim);
  const double g1 = limited ? 2.0 * v.M1 / (lim * lim) : 0.0;
  const double g2 = limited ? 2.0 * v.M2 / (lim * lim) : 0.0;
  const std::array<int, kLocalVariables> vars = node_variables(q);
  for (int l = 0; l < kLocalVariables; ++l) {
    const int i = l / 2, j = l % 2, var = vars[l];
    if (var < 0) continue;  // fixed end control points
    double gf = 0, gm1 = 0, gm2 = 0;
    for (int k = 0; k < 3; ++k) {
      const double b = node.basis.d[k][i];
      gf += v.df[2 * k + j] * b;
      gm1 += v.dM1[2 * k + j] * b;
      gm2 += v.dM2[2 * k + j] * b;
    }
    objective_grad[l] = node.weight * gf;
    const double row[3] = {g1 * gm1, g2 * gm2, (j == 0 ? ds1 : ds2) * node.basis.d[0][i]};
    for (int r = 0; r < 3; ++r) {
      if (how == Gradients::kDense) {
        out->constraints_grad[static_cast<size_t>(3 * q + r) * nv + var] += row[r];
      } else {
        out->constraints_grad_local[static_cast<size_t>(3 * q + r) * kLocalVariables + l] = row[r];
      }
    }
  }
}

// the nodes [begin, end) of one evaluation: the constraints and their gradients (each row
// belongs to one node), and each node's share of the objective and of its gradient, which
// evaluate_as() sums in node order (the same numbers for any number of threads)
Status TrajectoryProblem::evaluate_nodes(const double* x, Gradients how, int begin, int end,
                                         std::vector<double>* shares, Evaluated* out) const {
  const double lim = options_.torque_limit;
  const bool limited = std::isfinite(lim);
  // the parameters as Jets (a small copy per evaluation, cheap beside the nodes)
  Params<Jet6> pj;
  if (how != Gradients::kNone) pj = params_.cast<Jet6>();
  for (int q = begin; q < end; ++q) {
    const Node& node = nodes_[q];
    const std::array<double, 6> s = node_state(x, node);
    NodeValues v;
    const Status st = node_pass(how == Gradients::kNone ? nullptr : &pj, node, s, &v);
    if (!st.ok()) return st;
    double* share = &(*shares)[static_cast<size_t>(q) * (1 + kLocalVariables)];
    share[0] = node.weight * v.f;
    // constraints of this node
    double* c = &out->constraints[3 * q];
    c[0] = limited ? (v.M1 / lim) * (v.M1 / lim) - 1.0 : -1.0;
    c[1] = limited ? (v.M2 / lim) * (v.M2 / lim) - 1.0 : -1.0;
    double ds1 = 0, ds2 = 0;
    c[2] = coupler_constraint(params_, s[0], s[1], options_.singular_margin, &ds1, &ds2);
    if (how != Gradients::kNone) node_gradients(q, v, ds1, ds2, how, share + 1, out);
  }
  return Status::Ok();
}

Status TrajectoryProblem::evaluate_as(const double* x, Gradients how, Evaluated* out) const {
  const int nv = num_variables(), nc = num_constraints(), nn = num_nodes();
  out->constraints.assign(nc, 0.0);
  if (how == Gradients::kDense) out->constraints_grad.assign(static_cast<size_t>(nc) * nv, 0.0);
  if (how == Gradients::kLocal) {
    out->constraints_grad_local.assign(static_cast<size_t>(nc) * kLocalVariables, 0.0);
  }
  std::vector<double> shares(static_cast<size_t>(nn) * (1 + kLocalVariables), 0.0);
  // contiguous blocks of nodes, one per thread (this one takes the first)
  const int threads = std::max(1, std::min(options_.threads, nn / kMinNodesPerThread));
  std::vector<Status> status(threads);
  std::vector<std::thread> pool;
  auto block = [&](int k) {
    status[k] = evaluate_nodes(x, how, nn * k / threads, nn * (k + 1) / threads, &shares, out);
  };
  for (int k = 1; k < threads; ++k) pool.emplace_back(block, k);
  block(0);
  for (std::thread& t : pool) t.join();
  for (const Status& st : status) {
    if (!st.ok()) return st;
  }
  out->objective = 0.0;
  if (how != Gradients::kNone) out->objective_grad.assign(nv, 0.0);
  for (int q = 0; q < nn; ++q) {
    const double* share = &shares[static_cast<size_t>(q) * (1 + kLocalVariables)];
    out->objective += share[0];
    if (how == Gradients::kNone) continue;
    const std::array<int, kLocalVariables> vars = node_variables(q);
    for (int l = 0; l < kLocalVariables; ++l) {
      if (vars[l] >= 0) out->objective_grad[vars[l]] += share[1 + l];
    }
  }
  return Status::Ok();
}

int TrajectoryProblem::variable_of(int c, int j) const { return motion_.variable_of(c, j); }

Status TrajectoryProblem::node_gradient(const Params<Jet6>& pj, const Node& node,
                                        const std::array<double, 6>& s, double* f,
                                        std::array<double, 6>* df) const {
  NodeValues v;
  const Status st = node_pass(&pj, node, s, &v);
  *f = v.f;
  *df = v.df;
  return st;
}

Status TrajectoryProblem::node_hessian(const Params<Jet6>& pj, const Node& node,
                                       const std::array<double, 6>& s, bool gauss_newton,
                                       std::array<std::array<double, 6>, 6>* hs) const {
  if (gauss_newton) {
    // the winding heat's Gauss-Newton part 2 c_a dM_a dM_a^T, from one Jet pass: the
    // preconditioner needs the scale of the curvature, which the heat sets (the friction's
    // share is left to the quasi-Newton updates)
    NodeValues v;
    const Status st = node_pass(&pj, node, s, &v);
    const double c1 = 2.0 * options_.winding_heat[0], c2 = 2.0 * options_.winding_heat[1];
    for (int i = 0; i < 6; ++i) {
      for (int k = 0; k < 6; ++k) {
        (*hs)[i][k] = c1 * v.dM1[i] * v.dM1[k] + c2 * v.dM2[i] * v.dM2[k];
      }
    }
    return st;
  }
  constexpr double kStep = 1e-7;  // relative difference step of the node state
  double f = 0;
  std::array<double, 6> g0{}, g{};
  Status st = node_gradient(pj, node, s, &f, &g0);
  for (int k = 0; k < 6 && st.ok(); ++k) {
    std::array<double, 6> sk = s;
    const double h = kStep * std::max(1.0, std::abs(s[k]));
    sk[k] += h;
    st = node_gradient(pj, node, sk, &f, &g);
    for (int i = 0; i < 6; ++i) (*hs)[i][k] = (g[i] - g0[i]) / h;
  }
  if (!st.ok()) return st;
  for (int i = 0; i < 6; ++i) {
    for (int k = 0; k < i; ++k) (*hs)[i][k] = (*hs)[k][i] = 0.5 * ((*hs)[i][k] + (*hs)[k][i]);
  }
  return Status::Ok();
}

Status TrajectoryProblem::objective_hessian(const double* x, std::vector<double>* hessian,
                                            bool gauss_newton) const {
  const int nv = num_variables();
  hessian->assign(static_cast<size_t>(nv) * nv, 0.0);
  const Params<Jet6> pj = params_.cast<Jet6>();
  for (const Node& node : nodes_) {
    std::array<std::array<double, 6>, 6> hs{};
    const Status st = node_hessian(pj, node, node_state(x, node), gauss_newton, &hs);
    if (!st.ok()) return st;
    // s[2 k + j] = sum_i d[k][i] cp(j, first + i): H[v][v'] += w sum_kk' d[k][i] hs d[k'][i']
    for (int i = 0; i <= kDegree; ++i) {
      for (int j = 0; j < kDof; ++j) {
        const int v = variable_of(node.basis.first + i, j);
        if (v < 0) continue;
        for (int i2 = 0; i2 <= kDegree; ++i2) {
          for (int j2 = 0; j2 < kDof; ++j2) {
            const int v2 = variable_of(node.basis.first + i2, j2);
            if (v2 < 0) continue;
            double sum = 0;
            for (int k = 0; k < 3; ++k) {
              for (int k2 = 0; k2 < 3; ++k2) {
                sum += node.basis.d[k][i] * hs[2 * k + j][2 * k2 + j2] * node.basis.d[k2][i2];
              }
            }
            (*hessian)[static_cast<size_t>(v) * nv + v2] += node.weight * sum;
          }
        }
      }
    }
  }
  return Status::Ok();
}

Status TrajectoryProblem::objective(const double* x, double* value) const {
  Evaluated e;
  const Status st = evaluate(x, false, &e);
  if (st.ok()) *value = e.objective;
  return st;
}

Status TrajectoryProblem::energies(const double* x, int points, Energies* out) const {
  return energies_with(params_, x, points, out);
}

Status TrajectoryProblem::exact_energies(const double* x, int points, Energies* out) const {
  return energies_with(exact_params_, x, points, out);
}

Status TrajectoryProblem::energies_with(const Params<double>& params, const double* x,
                                        int points, Energies* out) const {
  const ClampedBasis& basis = motion_.basis();
  *out = Energies{};
  for (int s = 0; s < basis.spans(); ++s) {
    const Rule rule = gauss_legendre(points, basis.span_begin(s), basis.span_end(s));
    for (size_t i = 0; i < rule.nodes.size(); ++i) {
      Node node;
      node.t = rule.nodes[i];
      node.basis = basis.at(node.t);
      node.loads = loads_(node.t);
      const std::array<double, 6> st = node_state(x, node);
      double f, M1, M2;
      NodePowers<double> pw;
      const Status status = node_values(params, node.loads, st, options_, &f, &M1, &M2, &pw);
      if (!status.ok()) return status;
      const double w = rule.weights[i];
      out->dissipated += w * pw.dissipated;
      out->input += w * pw.input;
      out->input_smoothed += w * pw.input_smooth;
      out->winding_heat += w * pw.heat;
      out->supply += w * pw.supply;
      out->supply_smoothed += w * pw.supply_smooth;
    }
  }
  return Status::Ok();
}

ConstraintCheck TrajectoryProblem::check(const double* x, int points) const {
  ConstraintCheck out;
  out.points = std::max(points, 2);
  const double T = motion_.duration();
  for (int i = 0; i < out.points; ++i) {
    const double t = T * i / (out.points - 1);
    const auto s = motion_.state(x, t);
    double sine = 0;
    coupler_constraint(params_, s[0][0], s[0][1], options_.singular_margin, nullptr, nullptr,
                       &sine);
    out.min_coupler_sine = std::min(out.min_coupler_sine, sine);
    double M1 = 0, M2 = 0;
    out.status = torques(x, t, &M1, &M2);
    if (!out.status.ok()) return out;
    out.peak_torque = std::max({out.peak_torque, std::abs(M1), std::abs(M2)});
  }
  const double lim = options_.torque_limit;
  out.torque_excess = std::isfinite(lim) ? std::max(0.0, out.peak_torque - lim) : 0.0;
  double v = 0.0;
  if (std::isfinite(lim)) v = std::max(v, out.torque_excess / lim);
  if (options_.singular_margin > 0) {
    v = std::max(v, (options_.singular_margin - out.min_coupler_sine) / options_.singular_margin);
  }
  out.max_violation = v;
  return out;
}

Status TrajectoryProblem::torques(const double* x, double t, double* M1, double* M2) const {
  return torques_with(exact_params_, x, t, M1, M2);
}

Status TrajectoryProblem::smoothed_torques(const double* x, double t, double* M1,
                                           double* M2) const {
  return torques_with(params_, x, t, M1, M2);
}

Status TrajectoryProblem::torques_with(const Params<double>& params, const double* x, double t,
                                       double* M1, double* M2) const {
  const auto s = motion_.state(x, t);
  const Loads<double> L = loads_(t);
  Evaluation<double> ev;
  // the rest rule (rest.h): at the ends, at rest, the holding torques of `fivebar hold`
  const Status st = inverse_dynamics(params, L, s[0][0], s[0][1], s[1][0], s[1][1], s[2][0],
                                     s[2][1], nullptr,
                                     with_rest(eval_options(options_), RestThresholds{}), &ev);
  if (!st.ok()) return st;
  *M1 = ev.M1;
  *M2 = ev.M2;
  return Status::Ok();
}

Status TrajectoryProblem::rows(const double* x, double step, std::vector<sim::Row>* out) const {
  const double T = motion_.duration();
  const int n = std::max(1, static_cast<int>(std::ceil(T / step - 1e-9)));
  std::vector<sim::Row> motion(n + 1);
  for (int i = 0; i <= n; ++i) {
    sim::Row& r = motion[i];
    r.t = std::min(T, i * step);
    if (i == n) r.t = T;
    const auto s = motion_.state(x, r.t);
    for (int j = 0; j < kDof; ++j) {
      r.theta[j] = s[0][j];
      r.omega[j] = s[1][j];
      r.alpha[j] = s[2][j];
    }
  }
  const Status st = sim::inverse_rows(exact_params_, loads_, motion, out);
  if (!st.ok()) return st;
  return add_work(exact_params_, loads_, out);
}

}  // namespace fivebar::trajectory
