// Inverse-dynamics residual of one log sample, templated on the scalar for ceres::Jet.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <type_traits>

#include "fivebar/identification/parameters.h"
#include "fivebar/model/dynamics.h"
#include "fivebar/model/friction.h"
#include "fivebar/model/inertial.h"
#include "fivebar/model/params.h"

namespace fivebar::identification {

/// One sample as the residual sees it: pose, rates, accelerations (measured or estimated), the
/// measured actuator torques and the scene's other loads (M3, F, F_angle) at that time.
struct Sample {
  double t = 0, th1 = 0, th2 = 0, w1 = 0, w2 = 0, a1 = 0, a2 = 0, tau1 = 0, tau2 = 0;
  Loads<double> loads;
};

/// r = (tau1 - o1 - M1(x), tau2 - o2 - M2(x)) [N m] (o: the torque sensors' offsets), M from
/// the friction-aware inverse dynamics (dynamics.h, the reaction/friction loop resolved inside,
/// the actuators' friction included) with the friction coefficients x laid
/// out by `layout` and every other constant from `scene`. With exact sign (smoothing_velocity 0)
/// the Coulomb sign of each joint is sign(w_k) of the sample's rates: data, not a function of x,
/// so r is smooth in x. `operator()` accepts double and ceres::Jet.
class InverseDynamicsResidual {
 public:
  InverseDynamicsResidual(const Params<double>& scene, const ParameterLayout& layout,
                          const Sample& sample, const EvalOptions& eval)
      : scene_(scene), layout_(layout), s_(sample), eval_(eval) {}

  template <typename T>
  bool operator()(const T* x, T* r) const {
    Params<T> p = scene_.template cast<T>();
    layout_.apply(x, &p);
    Evaluation<T> ev;
    const Status st = inverse_dynamics(p, s_.loads.template cast<T>(), T(s_.th1), T(s_.th2),
                                       T(s_.w1), T(s_.w2), T(s_.a1), T(s_.a2), nullptr, eval_, &ev);
    if (!st.ok()) return false;  // Ceres rejects the step (e.g. the friction loop diverged)
    // measured = motor torque + the sensor's offset
    r[0] = T(s_.tau1) - p.actuators.offset[0] - ev.M1;
    r[1] = T(s_.tau2) - p.actuators.offset[1] - ev.M2;
    return true;
  }

  const Sample& sample() const { return s_; }

 private:
  const Params<double>& scene_;
  ParameterLayout layout_;
  Sample s_;
  EvalOptions eval_;
};

/// The structure of one sample's inverse dynamics, in which the residual is cheap to evaluate.
/// For the sample's motion the reactions are affine in the standard inertial parameters pi and
/// in the friction torques Mf, and so are the actuator torques:
///   F = A pi + b + dF Mf,   (M1, M2) = Y pi + c + G Mf,   Mf_k = phi_k(x) N_k,  N_k = |F_k|,
/// with phi_k = r_k f_k(w_k) the friction law at the sample's relative rate w_k and Coulomb sign.
/// The reaction/friction loop is then a fixed point on N in five numbers, with no reaction
/// solves: the Jets carry only the active parameters through it.
struct SampleStructure {
  Eigen::Matrix<double, 10, kInertialParams> A;
  Eigen::Matrix<double, 10, 1> b;
  Eigen::Matrix<double, 10, kJoints> dF;
  Eigen::Matrix<double, 2, kInertialParams> Y;
  Eigen::Vector2d c;
  Eigen::Matrix<double, 2, kJoints> G;
  JointModes slip{};  ///< mode per joint (kStuck: no friction torque)
  std::array<double, kJoints> w{};  ///< relative rates [rad/s]
};

/// The structure of sample s in `scene` (its pin radii, smoothing, geometry and loads; pi and
/// the coefficients free), in closed form from the sample's kinematics: A, Y (and b, c) from each
/// link's inertial wrench, linear in its standard parameters; dF, G the response per unit
/// friction torque (FiveBar::inverse_response) of the joints with a Coulomb sign (the rest
/// rule's modes, mech::detail::inverse_slip), zero for the others. False where it cannot be read
/// off reliably (a slipping joint whose friction-free reaction nearly vanishes, a moving joint
/// with friction but no Coulomb sign, a pose that does not close, a value not finite): use
/// InverseDynamicsResidual there.
bool sample_structure(const Params<double>& scene, const Sample& s, const EvalOptions& eval,
                      SampleStructure* out);

/// The same residual as InverseDynamicsResidual, from the sample's structure: equal to the
/// loop tolerance, and an order of magnitude cheaper with Jets.
class StructuredResidual {
 public:
  StructuredResidual(const Params<double>& scene, const ParameterLayout& layout,
                     const SampleStructure& st, const Sample& s, const EvalOptions& eval)
      : friction_(scene.friction),
        actuators_(scene.actuators),
        pi0_(standard_inertial(scene)),
        layout_(layout),
        st_(st),
        tau_{s.tau1, s.tau2},
        tol_(eval.friction_tol),
        max_iter_(eval.friction_max_iter) {}

  template <typename T>
  bool operator()(const T* x, T* r) const {
    std::array<T, kJoints> phi, motor;
    std::array<T, kActuators> offset;
    friction_terms(x, &phi, &motor, &offset);
    std::array<T, kInertialParams> pi;
    std::array<T, 10> F0;
    frictionless_reactions(x, &pi, &F0);
    std::array<T, kJoints> N;
    if constexpr (std::is_same_v<T, double>) {
      if (!loop(phi, motor, F0, &N)) return false;
    } else {
      // the loop in double on the value parts, then its derivatives by one Newton step in Jets
      // (implicit function theorem, as friction_loop_implicit in the model)
      std::array<double, kJoints> phi_v, motor_v, N_v;
      std::array<double, 10> F0_v;
      for (int j = 0; j < kJoints; ++j) {
        phi_v[j] = value_of(phi[j]);
        motor_v[j] = value_of(motor[j]);
      }
      for (int a = 0; a < 10; ++a) F0_v[a] = value_of(F0[a]);
      if (!loop(phi_v, motor_v, F0_v, &N_v)) return false;
      implicit_step(phi, motor, F0, N_v, &N);
    }
    residual_at(phi, motor, offset, pi, N, r);
    return true;
  }

  /// The residual r (2) at x and, where `jacobian` is not null, its derivatives (2 x P, row
  /// major, P = layout.size()): the value as operator() with ceres::Jet gives it (the loop, then
  /// one implicit step), the derivatives in closed form from the implicit function theorem
  /// through the loop (Jets only through the friction laws, over the friction and actuator
  /// parameters). Without `jacobian`, operator()<double>. With `jacobian`, `r_loop` (if not
  /// null) receives the residual as operator()<double> gives it (from the loop's end, before
  /// the implicit step).
  bool evaluate(const double* x, double* r, double* jacobian, double* r_loop = nullptr) const;

 private:
  /// The friction law's part phi_k = r_k f_k(w_k) of each joint's friction torque, the
  /// actuators' friction at their joints (load-independent) and the torque sensors' offsets, at
  /// the parameters x.
  template <typename T>
  void friction_terms(const T* x, std::array<T, kJoints>* phi, std::array<T, kJoints>* motor,
                      std::array<T, kActuators>* offset) const {
    FrictionParams<T> fp = friction_.template cast<T>();
    layout_.apply(x, &fp);
    ActuatorParams<T> act = actuators_.template cast<T>();
    if (layout_.actuator) ParameterLayout::apply_actuators(x + layout_.actuator_offset(), &act);
    motor->fill(T(0));
    for (int a = 0; a < kActuators; ++a) {  // as actuator_torques (actuator.h)
      const int k = actuator_joint(a);
      if (st_.slip[k] == kStuck) continue;
      (*motor)[k] = actuator_friction(fp, act, k, T(st_.w[k]), coulomb_sign(st_.slip[k]));
    }
    for (int j = 0; j < kJoints; ++j) {
      (*phi)[j] =
          st_.slip[j] == kStuck
              ? T(0)
              : fp.pin_radius[j] * friction_law(fp, j, T(st_.w[j]), coulomb_sign(st_.slip[j]));
    }
    for (int a = 0; a < kActuators; ++a) (*offset)[a] = act.offset[a];
  }
  /// The standard inertial parameters pi at x (the scene's where they are not fitted) and the
  /// reactions without friction torques, F0 = A pi + b.
  template <typename T>
  void frictionless_reactions(const T* x, std::array<T, kInertialParams>* pi,
                              std::array<T, 10>* F0) const {
    for (int i = 0; i < kInertialParams; ++i) {
      (*pi)[i] = layout_.inertia ? x[layout_.inertia_offset() + i] : T(pi0_[i]);
    }
    for (int a = 0; a < 10; ++a) {
      (*F0)[a] = T(st_.b(a));
      for (int i = 0; i < kInertialParams; ++i) (*F0)[a] += st_.A(a, i) * (*pi)[i];
    }
  }
  /// r = tau - (c + offset + Y pi + G Mf), Mf = phi N + motor.
  template <typename T>
  void residual_at(const std::array<T, kJoints>& phi, const std::array<T, kJoints>& motor,
                   const std::array<T, kActuators>& offset,
                   const std::array<T, kInertialParams>& pi, const std::array<T, kJoints>& N,
                   T* r) const {
    std::array<T, kJoints> Mf;
    for (int j = 0; j < kJoints; ++j) Mf[j] = phi[j] * N[j] + motor[j];
    for (int a = 0; a < kActuators; ++a) {
      T m = T(st_.c(a)) + offset[a];
      for (int i = 0; i < kInertialParams; ++i) m += st_.Y(a, i) * pi[i];
      for (int j = 0; j < kJoints; ++j) m += st_.G(a, j) * Mf[j];
      r[a] = T(tau_[a]) - m;
    }
  }
  /// F = F0 + dF Mf with Mf = phi N + motor (stacked F_1x, F_1y, ..., F_5x, F_5y).
  template <typename T>
  void reactions_of(const std::array<T, kJoints>& phi, const std::array<T, kJoints>& motor,
                    const std::array<T, 10>& F0, const std::array<T, kJoints>& N,
                    std::array<T, 10>* F) const {
    *F = F0;
    for (int j = 0; j < kJoints; ++j) {
      const T Mf = phi[j] * N[j] + motor[j];
      for (int a = 0; a < 10; ++a) (*F)[a] += st_.dF(a, j) * Mf;
    }
  }
  /// The fixed point N = |F0 + dF (phi N + motor)| from N = |F0|; false when it does not
  /// converge within max_iter_ (Ceres then rejects the step: the loop does not contract here).
  template <typename T>
  bool loop(const std::array<T, kJoints>& phi, const std::array<T, kJoints>& motor,
            const std::array<T, 10>& F0, std::array<T, kJoints>* N) const {
    using std::sqrt;
    for (int k = 0; k < kJoints; ++k) {
      (*N)[k] = sqrt(F0[2 * k] * F0[2 * k] + F0[2 * k + 1] * F0[2 * k + 1]);
    }
    std::array<T, 10> F;
    for (int it = 0; it < max_iter_; ++it) {
      reactions_of(phi, motor, F0, *N, &F);
      double change = 0, scale = 1e-300;
      for (int k = 0; k < kJoints; ++k) {
        const T n = sqrt(F[2 * k] * F[2 * k] + F[2 * k + 1] * F[2 * k + 1]);
        change = std::max(change, std::abs(value_of(n) - value_of((*N)[k])));
        scale = std::max(scale, std::abs(value_of(n)));
        (*N)[k] = n;
      }
      if (!std::isfinite(change)) return false;
      if (change <= tol_ * scale) return true;
    }
    return false;
  }
  /// The Jet solution of the loop from its double solution N*: N = N* + (I - G_N)^-1 (G(N*) - N*)
  /// with G(N) = |F(phi N)|, G_N in double; the value is N* refined, the derivatives
  /// dN/dx = (I - G_N)^-1 G_x.
  template <typename T>
  void implicit_step(const std::array<T, kJoints>& phi, const std::array<T, kJoints>& motor,
                     const std::array<T, 10>& F0, const std::array<double, kJoints>& N_star,
                     std::array<T, kJoints>* N,
                     Eigen::Matrix<double, kJoints, kJoints>* H_out = nullptr,
                     Eigen::Matrix<double, kJoints, 10>* U = nullptr) const {
    using std::sqrt;
    std::array<T, kJoints> Ns;
    for (int k = 0; k < kJoints; ++k) Ns[k] = T(N_star[k]);
    std::array<T, 10> F;
    reactions_of(phi, motor, F0, Ns, &F);
    Eigen::Matrix<double, kJoints, kJoints> J = Eigen::Matrix<double, kJoints, kJoints>::Identity();
    if (U) U->setZero();
    std::array<T, kJoints> r;
    for (int k = 0; k < kJoints; ++k) {
      const T n = sqrt(F[2 * k] * F[2 * k] + F[2 * k + 1] * F[2 * k + 1]);
      r[k] = n - N_star[k];
      if (!(value_of(n) > 0.0)) continue;
      const double fx = value_of(F[2 * k]) / value_of(n), fy = value_of(F[2 * k + 1]) / value_of(n);
      if (U) (*U)(k, 2 * k) = fx, (*U)(k, 2 * k + 1) = fy;
      for (int j = 0; j < kJoints; ++j) {
        J(k, j) -= (fx * st_.dF(2 * k, j) + fy * st_.dF(2 * k + 1, j)) * value_of(phi[j]);
      }
    }
    const std::array<T, kJoints> dN = fivebar::detail::solve_with_double_matrix(J, r);
    for (int k = 0; k < kJoints; ++k) (*N)[k] = dN[k] + N_star[k];
    if (H_out) *H_out = J;
  }

  FrictionParams<double> friction_;
  ActuatorParams<double> actuators_;
  std::array<double, kInertialParams> pi0_;
  ParameterLayout layout_;
  SampleStructure st_;
  double tau_[2];
  double tol_;
  int max_iter_;
};

}  // namespace fivebar::identification
