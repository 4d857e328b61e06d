// The member functions of TrajectoryProblemT<M> (problem.h), included by the units that
// instantiate it for one mechanism each (problem.cc: the five-bar; problem_four_bar.cc: the
// four-bar), so that each mechanism's Jet inverse dynamics compiles once, in its own unit.
#pragma once

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <thread>

#include <ceres/jet.h>

#include "fivebar/model/rest.h"
#include "fivebar/trajectory/problem.h"
#include "fivebar/trajectory/quadrature.h"

namespace fivebar::trajectory {
namespace detail {

// fewer nodes than this per thread are evaluated on fewer threads (a thread costs ~20 us)
constexpr int kMinNodesPerThread = 32;

inline EvalOptions eval_options(const ProblemOptions& o) {
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

// the supply power of the motors from their powers p (M w + heat): max(0, .) exact or smoothed
template <typename T, size_t n>
T supply_power(const std::array<T, n>& p, const ProblemOptions& o, bool exact) {
  auto clip = [&](const T& v) {
    return exact ? (value_of(v) > 0.0 ? v : T(0.0)) : softplus(v, o.power_smoothing);
  };
  if (o.regeneration == Regeneration::kSharedBus) {
    T sum = p[0];
    for (size_t a = 1; a < n; ++a) sum = T(sum + p[a]);
    return clip(sum);
  }
  T out = clip(p[0]);
  for (size_t a = 1; a < n; ++a) out = out + clip(p[a]);
  return out;
}

// the powers of one node [W]: everything Energies integrates
template <typename T>
struct NodePowers {
  T dissipated{}, input{}, input_smooth{}, heat{}, supply{}, supply_smooth{};
};

// the powers of one state s = (q, v, qdd) from its inverse dynamics and drive torques M
template <typename T, size_t n>
NodePowers<T> node_powers(const T& P_diss, const std::array<T, n>& M,
                          const std::array<T, 3 * n>& s, const ProblemOptions& o) {
  NodePowers<T> out;
  out.dissipated = P_diss;
  std::array<T, n> electric;
  for (size_t a = 0; a < n; ++a) {
    const T mech = M[a] * s[n + a];
    const T heat = o.winding_heat[a] * M[a] * M[a];
    out.heat += heat;
    out.input += value_of(mech) < 0.0 ? T(-mech) : mech;
    out.input_smooth += smooth_abs(mech, o.power_smoothing);
    electric[a] = mech + heat;
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

// integrand of the objective and the drive torques at one state s = (q, v, qdd); all the
// powers when asked
template <class M, typename T>
Status node_values(const typename M::template Params<T>& p, const typename M::template Loads<T>& L,
                   const std::array<T, 3 * M::kDof>& s, const ProblemOptions& o, T* f,
                   std::array<T, M::kDof>* drives, NodePowers<T>* powers = nullptr) {
  typename M::template Evaluation<T> ev;
  const Status st = TrajectoryMechanism<M>::inverse(p, L, s, eval_options(o), &ev);
  if (!st.ok()) return st;
  *drives = TrajectoryMechanism<M>::drives(ev);
  const NodePowers<T> pw = node_powers(ev.P_diss, *drives, s, o);
  *f = integrand(pw, o.objective);
  if (powers) *powers = pw;
  return Status::Ok();
}

// c^2 - (1 - m^2) at q, c the smooth form of the singular measure (M::singular_cosine), and its
// gradient in q; |singular measure| when asked
template <class M>
double singular_constraint(const typename M::template Params<double>& p,
                           const std::array<double, M::kDof>& q, double margin,
                           std::array<double, M::kDof>* grad, double* abs_sine = nullptr) {
  mech::Vec<M::kDof, double> qv;
  for (int j = 0; j < M::kDof; ++j) qv[j] = q[j];
  mech::Row<M::kDof, double> g;
  const double c = M::singular_cosine(p, qv, grad ? &g : nullptr);
  if (grad) {
    for (int j = 0; j < M::kDof; ++j) (*grad)[j] = 2.0 * c * g[j];
  }
  if (abs_sine) *abs_sine = c * c <= 1.0 ? std::sqrt(1.0 - c * c) : 0.0;
  return c * c - (1.0 - margin * margin);
}

// W_in and W_ext of trajectory rows (inverse_rows leaves them zero): the powers sum_a M_a w_a
// and the external loads' integrated by the trapezoidal rule, the rule of E_diss in the same
// rows
template <class M>
Status add_work(const typename M::template Params<double>& p,
                const std::function<typename M::template Loads<double>(double)>& loads,
                std::vector<sim::Row>* rows) {
  constexpr int n = M::kDof;
  double prev_in = 0, prev_ext = 0;
  for (size_t i = 0; i < rows->size(); ++i) {
    sim::Row& r = (*rows)[i];
    std::array<double, 3 * n> s;
    for (int j = 0; j < n; ++j) {
      s[j] = r.theta[j];
      s[n + j] = r.omega[j];
      s[2 * n + j] = r.alpha[j];
    }
    typename M::template Evaluation<double> ev;
    const Status st = TrajectoryMechanism<M>::inverse(p, loads(r.t), s, EvalOptions{}, &ev);
    if (!st.ok()) return st;
    const double dt = i == 0 ? 0.0 : r.t - (*rows)[i - 1].t;
    r.W_in = i == 0 ? 0.0 : (*rows)[i - 1].W_in + 0.5 * dt * (prev_in + ev.P_in);
    r.W_ext = i == 0 ? 0.0 : (*rows)[i - 1].W_ext + 0.5 * dt * (prev_ext + ev.P_ext);
    prev_in = ev.P_in;
    prev_ext = ev.P_ext;
  }
  return Status::Ok();
}

}  // namespace detail

template <class M>
TrajectoryProblemT<M>::TrajectoryProblemT(const ParamsD& params, const LoadFunction& loads,
                                          const Motion& motion, const ProblemOptions& options)
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

template <class M>
typename TrajectoryProblemT<M>::State TrajectoryProblemT<M>::node_state(const double* x,
                                                                        const Node& node) const {
  State s{};
  for (int j = 0; j < kDof; ++j) {
    for (int i = 0; i <= kDegree; ++i) {
      const double cp = motion_.control_point(x, node.basis.first + i, j);
      for (int k = 0; k < 3; ++k) s[kDof * k + j] += node.basis.d[k][i] * cp;
    }
  }
  return s;
}

template <class M>
Status TrajectoryProblemT<M>::evaluate(const double* x, bool want_gradients,
                                       Evaluated* out) const {
  return evaluate_as(x, want_gradients ? Gradients::kDense : Gradients::kNone, out);
}

template <class M>
Status TrajectoryProblemT<M>::evaluate_local(const double* x, Evaluated* out) const {
  return evaluate_as(x, Gradients::kLocal, out);
}

template <class M>
std::array<int, TrajectoryProblemT<M>::kLocal> TrajectoryProblemT<M>::node_variables(
    int node) const {
  std::array<int, kLocal> v{};
  for (int i = 0; i <= kDegree; ++i) {
    for (int j = 0; j < kDof; ++j) v[kDof * i + j] = variable_of(nodes_[node].basis.first + i, j);
  }
  return v;
}

template <class M>
void TrajectoryProblemT<M>::node_variables_into(int node, int* out) const {
  const std::array<int, kLocal> v = node_variables(node);
  std::copy(v.begin(), v.end(), out);
}

// one node: integrand, torques and (Jets) their gradients in the node state
template <class M>
Status TrajectoryProblemT<M>::node_pass(const typename M::template Params<Jet>* pj,
                                        const Node& node, const State& s, NodeValues* v) const {
  if (!pj) return detail::node_values<M>(params_, node.loads, s, options_, &v->f, &v->drives);
  // seed the node state: derivative k of the Jets is d/d s[k]
  std::array<Jet, kState> sj;
  for (int k = 0; k < kState; ++k) sj[k] = Jet(s[k], k);
  Jet fj;
  std::array<Jet, kDof> Mj;
  const Status st = detail::node_values<M>(
      *pj, node.loads.template cast<Jet>(), sj, options_, &fj, &Mj);
  if (!st.ok()) return st;
  v->f = fj.a;
  for (int a = 0; a < kDof; ++a) v->drives[a] = Mj[a].a;
  for (int k = 0; k < kState; ++k) {
    v->df[k] = fj.v[k];
    for (int a = 0; a < kDof; ++a) v->dM[a][k] = Mj[a].v[k];
  }
  return Status::Ok();
}

// the gradients of node q by the chain rule, s[kDof k + j] = sum_i basis.d[k][i] cp(j, first +
// i): the objective's share in local form (kLocal values), the constraint rows' in the form
// `how` asks; ds: the singular row's gradient in q
template <class M>
void TrajectoryProblemT<M>::node_gradients(int q, const NodeValues& v,
                                           const std::array<double, kDof>& ds, Gradients how,
                                           double* objective_grad, Evaluated* out) const {
  constexpr int kRows = kDof + 1;
  const Node& node = nodes_[q];
  const int nv = num_variables();
  const double lim = options_.torque_limit;
  const bool limited = std::isfinite(lim);
  std::array<double, kDof> gm{};
  for (int a = 0; a < kDof; ++a) gm[a] = limited ? 2.0 * v.drives[a] / (lim * lim) : 0.0;
  const std::array<int, kLocal> vars = node_variables(q);
  for (int l = 0; l < kLocal; ++l) {
    const int i = l / kDof, j = l % kDof, var = vars[l];
    if (var < 0) continue;  // fixed end control points
    double gf = 0;
    std::array<double, kDof> gM{};
    for (int k = 0; k < 3; ++k) {
      const double b = node.basis.d[k][i];
      gf += v.df[kDof * k + j] * b;
      for (int a = 0; a < kDof; ++a) gM[a] += v.dM[a][kDof * k + j] * b;
    }
    objective_grad[l] = node.weight * gf;
    std::array<double, kRows> row;
    for (int a = 0; a < kDof; ++a) row[a] = gm[a] * gM[a];
    row[kDof] = ds[j] * node.basis.d[0][i];
    for (int r = 0; r < kRows; ++r) {
      if (how == Gradients::kDense) {
        out->constraints_grad[static_cast<size_t>(kRows * q + r) * nv + var] += row[r];
      } else {
        out->constraints_grad_local[static_cast<size_t>(kRows * q + r) * kLocal + l] = row[r];
      }
    }
  }
}

// the nodes [begin, end) of one evaluation: the constraints and their gradients (each row
// belongs to one node), and each node's share of the objective and of its gradient, which
// evaluate_as() sums in node order (the same numbers for any number of threads)
template <class M>
Status TrajectoryProblemT<M>::evaluate_nodes(const double* x, Gradients how, int begin, int end,
                                             std::vector<double>* shares,
                                             Evaluated* out) const {
  constexpr int kRows = kDof + 1;
  const double lim = options_.torque_limit;
  const bool limited = std::isfinite(lim);
  // the parameters as Jets (a small copy per evaluation, cheap beside the nodes)
  typename M::template Params<Jet> pj;
  if (how != Gradients::kNone) pj = params_.template cast<Jet>();
  for (int q = begin; q < end; ++q) {
    const Node& node = nodes_[q];
    const State s = node_state(x, node);
    NodeValues v;
    const Status st = node_pass(how == Gradients::kNone ? nullptr : &pj, node, s, &v);
    if (!st.ok()) return st;
    double* share = &(*shares)[static_cast<size_t>(q) * (1 + kLocal)];
    share[0] = node.weight * v.f;
    // constraints of this node
    double* c = &out->constraints[kRows * q];
    for (int a = 0; a < kDof; ++a) c[a] = limited ? (v.drives[a] / lim) * (v.drives[a] / lim) - 1.0 : -1.0;
    std::array<double, kDof> pose, ds{};
    std::copy(s.begin(), s.begin() + kDof, pose.begin());
    c[kDof] = detail::singular_constraint<M>(params_, pose, options_.singular_margin, &ds);
    if (how != Gradients::kNone) node_gradients(q, v, ds, how, share + 1, out);
  }
  return Status::Ok();
}

template <class M>
Status TrajectoryProblemT<M>::evaluate_as(const double* x, Gradients how, Evaluated* out) const {
  const int nv = num_variables(), nc = num_constraints(), nn = num_nodes();
  out->constraints.assign(nc, 0.0);
  if (how == Gradients::kDense) out->constraints_grad.assign(static_cast<size_t>(nc) * nv, 0.0);
  if (how == Gradients::kLocal) {
    out->constraints_grad_local.assign(static_cast<size_t>(nc) * kLocal, 0.0);
  }
  std::vector<double> shares(static_cast<size_t>(nn) * (1 + kLocal), 0.0);
  // contiguous blocks of nodes, one per thread (this one takes the first)
  const int threads = std::max(1, std::min(options_.threads, nn / detail::kMinNodesPerThread));
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
    const double* share = &shares[static_cast<size_t>(q) * (1 + kLocal)];
    out->objective += share[0];
    if (how == Gradients::kNone) continue;
    const std::array<int, kLocal> vars = node_variables(q);
    for (int l = 0; l < kLocal; ++l) {
      if (vars[l] >= 0) out->objective_grad[vars[l]] += share[1 + l];
    }
  }
  return Status::Ok();
}

template <class M>
Status TrajectoryProblemT<M>::node_gradient(const typename M::template Params<Jet>& pj,
                                            const Node& node, const State& s, double* f,
                                            State* df) const {
  NodeValues v;
  const Status st = node_pass(&pj, node, s, &v);
  *f = v.f;
  *df = v.df;
  return st;
}

template <class M>
Status TrajectoryProblemT<M>::node_hessian(const typename M::template Params<Jet>& pj,
                                           const Node& node, const State& s, bool gauss_newton,
                                           Hessian* hs) const {
  if (gauss_newton) {
    // the winding heat's Gauss-Newton part 2 c_a dM_a dM_a^T, from one Jet pass: the
    // preconditioner needs the scale of the curvature, which the heat sets (the friction's
    // share is left to the quasi-Newton updates)
    NodeValues v;
    const Status st = node_pass(&pj, node, s, &v);
    for (int i = 0; i < kState; ++i) {
      for (int k = 0; k < kState; ++k) {
        double h = 0.0;
        for (int a = 0; a < kDof; ++a) {
          h += 2.0 * options_.winding_heat[a] * v.dM[a][i] * v.dM[a][k];
        }
        (*hs)[i][k] = h;
      }
    }
    return st;
  }
  constexpr double kStep = 1e-7;  // relative difference step of the node state
  double f = 0;
  State g0{}, g{};
  Status st = node_gradient(pj, node, s, &f, &g0);
  for (int k = 0; k < kState && st.ok(); ++k) {
    State sk = s;
    const double h = kStep * std::max(1.0, std::abs(s[k]));
    sk[k] += h;
    st = node_gradient(pj, node, sk, &f, &g);
    for (int i = 0; i < kState; ++i) (*hs)[i][k] = (g[i] - g0[i]) / h;
  }
  if (!st.ok()) return st;
  for (int i = 0; i < kState; ++i) {
    for (int k = 0; k < i; ++k) (*hs)[i][k] = (*hs)[k][i] = 0.5 * ((*hs)[i][k] + (*hs)[k][i]);
  }
  return Status::Ok();
}

template <class M>
Status TrajectoryProblemT<M>::objective_hessian(const double* x, std::vector<double>* hessian,
                                                bool gauss_newton) const {
  const int nv = num_variables();
  hessian->assign(static_cast<size_t>(nv) * nv, 0.0);
  const typename M::template Params<Jet> pj = params_.template cast<Jet>();
  for (const Node& node : nodes_) {
    Hessian hs{};
    const Status st = node_hessian(pj, node, node_state(x, node), gauss_newton, &hs);
    if (!st.ok()) return st;
    // s[kDof k + j] = sum_i d[k][i] cp(j, first + i):
    // H[v][v'] += w sum_kk' d[k][i] hs d[k'][i']
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
                sum += node.basis.d[k][i] * hs[kDof * k + j][kDof * k2 + j2] *
                       node.basis.d[k2][i2];
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

template <class M>
Status TrajectoryProblemT<M>::energies(const double* x, int points, Energies* out) const {
  return energies_with(params_, x, points, out);
}

template <class M>
Status TrajectoryProblemT<M>::exact_energies(const double* x, int points, Energies* out) const {
  return energies_with(exact_params_, x, points, out);
}

template <class M>
Status TrajectoryProblemT<M>::energies_with(const ParamsD& params, const double* x, int points,
                                            Energies* out) const {
  const ClampedBasis& basis = motion_.basis();
  *out = Energies{};
  for (int s = 0; s < basis.spans(); ++s) {
    const Rule rule = gauss_legendre(points, basis.span_begin(s), basis.span_end(s));
    for (size_t i = 0; i < rule.nodes.size(); ++i) {
      Node node;
      node.t = rule.nodes[i];
      node.basis = basis.at(node.t);
      node.loads = loads_(node.t);
      const State st = node_state(x, node);
      double f;
      std::array<double, kDof> drives;
      detail::NodePowers<double> pw;
      const Status status =
          detail::node_values<M>(params, node.loads, st, options_, &f, &drives, &pw);
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

template <class M>
ConstraintCheck TrajectoryProblemT<M>::check(const double* x, int points) const {
  ConstraintCheck out;
  out.points = std::max(points, 2);
  const double T = motion_.duration();
  for (int i = 0; i < out.points; ++i) {
    const double t = T * i / (out.points - 1);
    const auto s = motion_.state(x, t);
    double sine = 0;
    detail::singular_constraint<M>(params_, s[0], options_.singular_margin, nullptr, &sine);
    out.min_coupler_sine = std::min(out.min_coupler_sine, sine);
    std::array<double, kDof> drives{};
    out.status = torques_with(exact_params_, x, t, &drives);
    if (!out.status.ok()) return out;
    for (double m : drives) out.peak_torque = std::max(out.peak_torque, std::abs(m));
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

template <class M>
Status TrajectoryProblemT<M>::torques(const double* x, double t, double* M1, double* M2) const {
  return torques_out(exact_params_, x, t, M1, M2);
}

template <class M>
Status TrajectoryProblemT<M>::smoothed_torques(const double* x, double t, double* M1,
                                               double* M2) const {
  return torques_out(params_, x, t, M1, M2);
}

template <class M>
Status TrajectoryProblemT<M>::torques_out(const ParamsD& params, const double* x, double t,
                                          double* M1, double* M2) const {
  std::array<double, kDof> drives{};
  const Status st = torques_with(params, x, t, &drives);
  if (!st.ok()) return st;
  *M1 = drives[0];
  if (M2) *M2 = kDof > 1 ? drives[kDof > 1 ? 1 : 0] : 0.0;
  return Status::Ok();
}

template <class M>
Status TrajectoryProblemT<M>::torques_with(const ParamsD& params, const double* x, double t,
                                           std::array<double, kDof>* drives) const {
  const auto s = motion_.state(x, t);
  State st;
  for (int k = 0; k < 3; ++k) {
    for (int j = 0; j < kDof; ++j) st[kDof * k + j] = s[k][j];
  }
  typename M::template Evaluation<double> ev;
  // the rest rule (rest.h): at the ends, at rest, the holding torques of `fivebar hold`
  const Status status = TrajectoryMechanism<M>::inverse(
      params, loads_(t), st, with_rest(detail::eval_options(options_), RestThresholds{}), &ev);
  if (!status.ok()) return status;
  *drives = TrajectoryMechanism<M>::drives(ev);
  return Status::Ok();
}

template <class M>
Status TrajectoryProblemT<M>::rows(const double* x, double step,
                                   std::vector<sim::Row>* out) const {
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
  return detail::add_work<M>(exact_params_, loads_, out);
}

}  // namespace fivebar::trajectory
