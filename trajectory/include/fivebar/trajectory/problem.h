// The trajectory optimization problem: cost and constraints of a rest-to-rest B-spline motion of
// a mechanism (mechanism.h: the five-bar, the four-bar), evaluated by the friction-aware inverse
// dynamics, with exact gradients. TrajectoryProblem is the five-bar's; the four-bar's is declared
// in four_bar_problem.h.
#pragma once

#include <array>
#include <limits>
#include <string>
#include <vector>

#include <ceres/jet.h>
#include <functional>

#include "fivebar/model/dynamics.h"
#include "fivebar/model/five_bar_mechanism.h"
#include "fivebar/model/kinematics.h"
#include "fivebar/model/params.h"
#include "fivebar/model/status.h"
#include "fivebar/sim/simulator.h"
#include "fivebar/trajectory/bspline.h"

namespace fivebar::trajectory {

/// What the optimizer minimizes.
enum class Objective : int {
  /// E = int sum_k Mf_k w_k dt [J], the energy dissipated in the five joints (model.md).
  kDissipatedEnergy = 0,
  /// int |M1 w1| + |M2 w2| dt [J], the energy the motors put in (braking counts as spent), with
  /// |p| smoothed to sqrt(p^2 + eps^2) - eps, eps = ProblemOptions::power_smoothing.
  kInputEnergy = 1,
  /// int P_diss + sum_a c_a M_a^2 dt [J]: joint (and actuator) friction plus the motors' winding
  /// heat, c_a = R_a / (k_t,a G_a)^2 (ProblemOptions::winding_heat; docs/model.md)
  kTotalDissipation = 2,
  /// the electrical energy drawn from the supply [J]: int sum_a max(0, M_a w_a + c_a M_a^2) dt
  /// (Regeneration::kNone) or int max(0, sum_a (M_a w_a + c_a M_a^2)) dt (kSharedBus), with
  /// max(0, p) smoothed to the softplus eps log(1 + exp(p / eps)), eps = power_smoothing; the
  /// softplus exceeds max(0, p) by at most eps ln 2 per motor (0.0069 W for eps = 0.01 W)
  kSupplyEnergy = 3,
};
const char* objective_name(Objective o);
bool parse_objective(const std::string& name, Objective* out);
/// The valid objective names, comma-separated (for error messages).
std::string objective_names();
/// True for the objectives that need the motors' winding data (MotorWindings::present).
bool needs_winding(Objective o);

/// Where the braking power of a motor goes (kSupplyEnergy): kNone, lost (each motor's power is
/// clipped at 0); kSharedBus, to the other motor (the sum of both powers is clipped at 0).
enum class Regeneration : int { kNone = 0, kSharedBus = 1 };
const char* regeneration_name(Regeneration r);
bool parse_regeneration(const std::string& name, Regeneration* out);

const char* end_acceleration_name(EndAcceleration e);
bool parse_end_acceleration(const std::string& name, EndAcceleration* out);

/// The energies of one motion [J] (TrajectoryProblem::energies).
struct Energies {
  double dissipated = 0;    ///< int P_diss dt: joint and actuator friction
  double input = 0;         ///< int |M1 w1| + |M2 w2| dt
  double input_smoothed = 0;  ///< the same with the smoothed |p| the optimizer minimizes
  double winding_heat = 0;  ///< int sum_a c_a M_a^2 dt
  double supply = 0;        ///< kSupplyEnergy's integral with the exact max(0, p)
  double supply_smoothed = 0;  ///< the same with the softplus the optimizer minimizes
  double total() const { return dissipated + winding_heat; }
  /// the value of objective o (kInputEnergy, kSupplyEnergy: the exact `input`, `supply`)
  double of(Objective o) const;
};

/// Discretization and constraint settings.
struct ProblemOptions {
  int control_points = 10;      ///< per joint (n >= 7); n - 6 of them are free
  int quadrature_points = 12;   ///< Gauss-Legendre points per knot span (also constraint points)
  Objective objective = Objective::kDissipatedEnergy;
  /// |M_a| <= torque_limit [N m] for every motor a at every quadrature point; infinity: no
  /// torque constraint
  double torque_limit = std::numeric_limits<double>::infinity();
  /// |singular measure| >= singular_margin at every quadrature point (also keeps the assembly):
  /// the five-bar's |sin(th4 - th3)|, the four-bar's |sin(th3 - th2)|
  double singular_margin = kMotionSingularMargin;
  /// w_s [rad/s] of the smooth Coulomb sign tanh(w / w_s) used along the trajectory, when the
  /// scene's friction.smoothing_velocity is 0 (the exact sign has no derivative at w = 0, and
  /// every joint starts and ends at rest). A scene value > 0 is used as it is.
  double smoothing_velocity = 5e-2;
  double power_smoothing = 1e-2;  ///< eps [W] of the smooth |p| and max(0, p) (kInputEnergy,
                                  ///< kSupplyEnergy)
  Regeneration regeneration = Regeneration::kNone;  ///< of kSupplyEnergy
  /// c_a = R_a / (k_t,a G_a)^2 [W/(N m)^2] of the motors (MotorWindings::heat_coefficients;
  /// a mechanism with one motor uses the first): the winding heat is c_a M_a^2; zero without
  /// winding data
  std::array<double, 2> winding_heat{};
  /// the ends of the task motions (RestToRest): free accelerations by default (with zero ones, a
  /// boundary layer of a few ms slows the convergence of the refinement to first order)
  EndAcceleration end_acceleration = EndAcceleration::kFree;
  double friction_tol = kFrictionTol;  ///< relative stopping test of the reaction/friction loop
  /// threads of one evaluation (contiguous blocks of nodes; at least 32 nodes each). The
  /// objective and its gradient are summed in node order afterwards: the same numbers for any
  /// count.
  int threads = 1;
};

/// The friction parameters actually used along trajectories: `params` with smoothing_velocity
/// set to options.smoothing_velocity when it is 0 (see ProblemOptions::smoothing_velocity).
template <class P>
P smoothed_params(const P& params, const ProblemOptions& options) {
  P p = params;
  if (!(p.friction.smoothing_velocity > 0.0)) {
    p.friction.smoothing_velocity = options.smoothing_velocity;
  }
  return p;
}

/// Values at the constraint points of one evaluation.
struct Evaluated {
  double objective = 0;                  ///< [J]
  std::vector<double> objective_grad;    ///< d objective / dx, when asked
  std::vector<double> constraints;       ///< c(x) <= 0, see TrajectoryProblem
  std::vector<double> constraints_grad;  ///< row-major (constraints x variables), when asked
  /// the same in local form (evaluate_local): row r depends on the L = local_variables() free
  /// variables of node r / rows_per_node() only; d c_r / d those at [L r, L r + L)
  std::vector<double> constraints_grad_local;
};

/// control points (6) times joints (2) that one node's state depends on (the five-bar's)
constexpr int kLocalVariables = 2 * (kDegree + 1);

/// Constraint check on a uniform grid (t = duration i / (points - 1)).
struct ConstraintCheck {
  Status status;                ///< not ok: the inverse dynamics failed somewhere on the grid
  int points = 0;
  double peak_torque = 0;       ///< max over the grid and the motors of |M_a| [N m]
  double torque_excess = 0;     ///< max(0, peak_torque - torque_limit) [N m]
  double min_coupler_sine = 1;  ///< min |singular measure| over the grid (the five-bar's
                                ///< |sin(th4 - th3)|, the four-bar's |sin(th3 - th2)|)
  /// max(0, torque_excess / torque_limit, (margin - min_coupler_sine) / margin): relative
  double max_violation = 0;
};

/// What the optimizer (optimizer.h) and the batch's checks need of a trajectory problem,
/// whatever the mechanism: TrajectoryProblemT<M> implements it. Constraint rows come in groups
/// of rows_per_node() per node (see TrajectoryProblemT).
class TrajectoryProblemBase {
 public:
  virtual ~TrajectoryProblemBase() = default;
  /// degrees of freedom: one spline per driven joint, one torque row per motor
  virtual int dofs() const = 0;
  virtual int num_variables() const = 0;
  virtual int num_nodes() const = 0;
  int rows_per_node() const { return dofs() + 1; }
  int num_constraints() const { return rows_per_node() * num_nodes(); }
  /// control points (kDegree + 1) times joints that one node's state depends on
  int local_variables() const { return dofs() * (kDegree + 1); }
  virtual const ProblemOptions& options() const = 0;
  /// control points per joint of the spline
  virtual int control_points() const = 0;
  /// free variables per joint (joint j's are [j free_per_joint(), (j + 1) free_per_joint()))
  virtual int free_per_joint() const = 0;
  /// the motion's start and goal angle of joint j [rad]
  virtual double start_angle(int j) const = 0;
  virtual double goal_angle(int j) const = 0;

  /// Objective, constraints and (when the flags ask) their gradients at x. Not ok when the
  /// inverse dynamics fails at a node (cannot assemble, friction loop): out is then unusable.
  virtual Status evaluate(const double* x, bool want_gradients, Evaluated* out) const = 0;
  /// The same with gradients, those of the constraints in local form (constraints_grad_local;
  /// constraints_grad is left as it was): a row of the dense form has local_variables()
  /// non-zeros of up to 300 (160 variables at 85 control points), and the dense form is 2.4 MB
  /// to clear.
  virtual Status evaluate_local(const double* x, Evaluated* out) const = 0;
  /// The free variables of the local gradients of node `node`'s rows into out[0 ..
  /// local_variables()): entry dofs() i + j is control point i of the node's six of joint j,
  /// -1 where it is a fixed end point.
  virtual void node_variables_into(int node, int* out) const = 0;
  /// Objective only, in double (no Jets).
  Status objective(const double* x, double* value) const;
  /// Hessian of the objective at x (num_variables()^2 values, row-major, symmetric):
  /// sum over the nodes of weight B^T H_s B, H_s the Hessian of the integrand in the node
  /// state (3 dofs() values) by forward differences of its exact (Jet) gradient, B the spline's
  /// linear map from the free control points to the node state. Costs about 3 dofs() + 1
  /// evaluations with gradients. With `gauss_newton`, H_s is instead the winding heat's
  /// Gauss-Newton form sum_a 2 c_a grad M_a grad M_a^T, from one evaluation: positive
  /// semi-definite, and the scale a preconditioner needs where the heat is most of the
  /// objective (heat_share()).
  virtual Status objective_hessian(const double* x, std::vector<double>* hessian,
                                   bool gauss_newton = false) const = 0;
  /// The winding heat's share of the objective at x, under the smoothed law (0 for an objective
  /// without it, NaN when x cannot be evaluated).
  double heat_share(const double* x) const;
  /// The energies of the motion integrated with `points` Gauss-Legendre points per span (for
  /// the accuracy check against a denser rule).
  virtual Status energies(const double* x, int points, Energies* out) const = 0;
  /// The same with the scene's exact friction law; its integrand has kinks where a joint
  /// reverses, so ask for more points than energies() needs.
  virtual Status exact_energies(const double* x, int points, Energies* out) const = 0;
  /// Re-check of the constraints on a uniform grid of `points` instants (inverse dynamics in
  /// double with the exact law, ends included).
  virtual ConstraintCheck check(const double* x, int points) const = 0;
};

/// What the trajectory problem needs of a mechanism M beyond the concept (mechanism.h): its
/// inverse dynamics on the node state s = (q, v, qdd) and the drive torques it returns.
/// Specialized for FiveBar below and for FourBar in four_bar_problem.h.
template <class M>
struct TrajectoryMechanism;

template <>
struct TrajectoryMechanism<FiveBar> {
  template <typename T>
  static Status inverse(const Params<T>& p, const Loads<T>& L, const std::array<T, 6>& s,
                        const EvalOptions& opt, Evaluation<T>* ev) {
    return inverse_dynamics(p, L, s[0], s[1], s[2], s[3], s[4], s[5], nullptr, opt, ev);
  }
  template <typename T>
  static std::array<T, 2> drives(const Evaluation<T>& ev) {
    return {ev.M1, ev.M2};
  }
};

/// Cost and constraints of one rest-to-rest task of mechanism M (kDof = M::kDof joints) for one
/// design.
///
/// Time is discretized by composite Gauss-Legendre quadrature: quadrature_points nodes in each
/// knot span of the spline, where the integrand (a smooth function of the spline's piecewise
/// polynomial state) is smooth; with free end accelerations (EndAcceleration::kFree) two more
/// nodes of weight 0 at t = 0 and t = T, where the torques step. The nodes carry the
/// constraints, kDof + 1 per node q (the five-bar's three: M1, M2, the coupler):
///   c[(kDof + 1) q + a]    = (M_a / torque_limit)^2 - 1 <= 0  for each motor a < kDof
///                            (0 - 1 when there is no torque limit)
///   c[(kDof + 1) q + kDof] = c^2 - (1 - margin^2) <= 0,  c = M::singular_cosine(q)
/// where c is the smooth form of the singular measure (the five-bar's cos C = (l3^2 + l4^2 -
/// |BD|^2) / (2 l3 l4), C the coupler angle at joint C; the four-bar's cos(th3 - th2)). The last
/// constraint is defined for any q, also where the mechanism cannot close, and implies both the
/// margin and the assembly; the branch cannot change along a motion that keeps the measure > 0.
///
/// Gradients are exact: the inverse dynamics at each node runs on ceres::Jet<double, 3 kDof>
/// seeded on the node state (q, v, qdd), and the chain rule through the spline basis (linear in
/// x) gives the derivatives with respect to the free control points.
///
/// Thread-safety: const member functions may be called from several threads at once.
template <class M>
class TrajectoryProblemT : public TrajectoryProblemBase {
 public:
  static constexpr int kDof = M::kDof;
  static constexpr int kState = 3 * kDof;  ///< node state (q, v, qdd)
  static constexpr int kLocal = kDof * (kDegree + 1);
  using ParamsD = typename M::template Params<double>;
  using LoadsD = typename M::template Loads<double>;
  using LoadFunction = std::function<LoadsD(double)>;
  using Motion = RestToRestT<kDof>;
  using State = std::array<double, kState>;
  using Jet = ceres::Jet<double, kState>;

  /// `loads` gives the scene's other loads at t (its drive torques are ignored): the
  /// constructor samples it at the nodes; check(), rows() and torques() call it at their
  /// instants.
  TrajectoryProblemT(const ParamsD& params, const LoadFunction& loads, const Motion& motion,
                     const ProblemOptions& options);

  int dofs() const override { return kDof; }
  int num_variables() const override { return motion_.num_variables(); }
  int num_nodes() const override { return static_cast<int>(nodes_.size()); }
  const Motion& motion() const { return motion_; }
  const ProblemOptions& options() const override { return options_; }
  int control_points() const override { return motion_.basis().size(); }
  int free_per_joint() const override { return motion_.free_per_joint(); }
  double start_angle(int j) const override { return motion_.start()[j]; }
  double goal_angle(int j) const override { return motion_.goal()[j]; }
  /// the parameters of the cost and constraints (friction smoothed, smoothed_params)
  const ParamsD& params() const { return params_; }
  /// the parameters as given (the scene's own friction law): those of check(), rows(),
  /// torques(), which are what the mechanism needs and what `fivebar inverse` computes
  const ParamsD& exact_params() const { return exact_params_; }

  Status evaluate(const double* x, bool want_gradients, Evaluated* out) const override;
  Status evaluate_local(const double* x, Evaluated* out) const override;
  /// node_variables_into as an array (entry kDof i + j: control point i of joint j)
  std::array<int, kLocal> node_variables(int node) const;
  void node_variables_into(int node, int* out) const override;
  Status objective_hessian(const double* x, std::vector<double>* hessian,
                           bool gauss_newton = false) const override;
  Status energies(const double* x, int points, Energies* out) const override;
  Status exact_energies(const double* x, int points, Energies* out) const override;
  ConstraintCheck check(const double* x, int points) const override;

  /// Rows of trajectory.csv (interfaces.md) on a uniform grid of step `step` [s] (ends
  /// included), from sim::inverse_rows with the scene's exact friction law (the torques of
  /// `fivebar inverse` on the same motion). E_diss, W_in (sum_a M_a w_a) and W_ext (the
  /// external loads' power) are integrated by the trapezoidal rule on the rows, so that
  /// d(KE + PE) = W_in + W_ext - E_diss to that rule's accuracy.
  Status rows(const double* x, double step, std::vector<sim::Row>* out) const;

  /// The drive torques [N m] of the motion at time t (inverse dynamics in double, exact law):
  /// M1 and M2 (left as it is when null; the four-bar, with one motor, sets it to 0).
  Status torques(const double* x, double t, double* M1, double* M2) const;
  /// The same with the smoothed law of the cost (params()).
  Status smoothed_torques(const double* x, double t, double* M1, double* M2) const;

 private:
  struct Node {
    double t, weight;
    BasisAt basis;
    LoadsD loads;
  };
  enum class Gradients { kNone, kDense, kLocal };
  struct NodeValues {
    double f = 0;
    std::array<double, kDof> drives{};
    std::array<double, kState> df{};  ///< in the node state (with Jets)
    std::array<std::array<double, kState>, kDof> dM{};
  };
  using Hessian = std::array<std::array<double, kState>, kState>;
  Status evaluate_as(const double* x, Gradients how, Evaluated* out) const;
  Status node_pass(const typename M::template Params<Jet>* pj, const Node& node, const State& s,
                   NodeValues* v) const;
  void node_gradients(int q, const NodeValues& v, const std::array<double, kDof>& ds,
                      Gradients how, double* objective_grad, Evaluated* out) const;
  Status evaluate_nodes(const double* x, Gradients how, int begin, int end,
                        std::vector<double>* shares, Evaluated* out) const;
  Status torques_with(const ParamsD& params, const double* x, double t,
                      std::array<double, kDof>* drives) const;
  Status torques_out(const ParamsD& params, const double* x, double t, double* M1,
                     double* M2) const;
  Status energies_with(const ParamsD& params, const double* x, int points, Energies* out) const;
  // node state (q, v, qdd: s[kDof k + j]) from x
  State node_state(const double* x, const Node& node) const;
  // integrand f at state s and its exact gradient in s
  Status node_gradient(const typename M::template Params<Jet>& pj, const Node& node,
                       const State& s, double* f, State* df) const;
  // Hessian of the integrand in the node state (forward differences of node_gradient, or the
  // winding heat's Gauss-Newton form)
  Status node_hessian(const typename M::template Params<Jet>& pj, const Node& node,
                      const State& s, bool gauss_newton, Hessian* hs) const;
  // free variable of control point c of joint j, or -1 for the fixed end points
  int variable_of(int c, int j) const { return motion_.variable_of(c, j); }

  ParamsD params_, exact_params_;
  LoadFunction loads_;
  Motion motion_;
  ProblemOptions options_;
  std::vector<Node> nodes_;
};

/// The five-bar's problem (instantiated once, in problem.cc).
extern template class TrajectoryProblemT<FiveBar>;
using TrajectoryProblem = TrajectoryProblemT<FiveBar>;

}  // namespace fivebar::trajectory
