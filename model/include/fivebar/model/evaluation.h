// What one evaluation of the dynamics takes (EvalOptions) and computes (Evaluation).
#pragma once

#include <array>

#include "fivebar/model/kinematics.h"
#include "fivebar/model/params.h"
#include "fivebar/model/scalar.h"

namespace fivebar {

/// Joint mode value for a stuck joint (exact stick-slip): its relative rate is held at zero by a
/// holding torque solved with the motion. Other modes are the slip direction +1 / -1, or 0.
enum class JointMode : int {
  kSlipNegative = -1,  ///< slipping with w_k < 0: Coulomb sign -1
  kRest = 0,           ///< no Coulomb friction (w_k = 0 in the exact law; no friction law)
  kSlipPositive = 1,   ///< slipping with w_k > 0: Coulomb sign +1
  kStuck = 2,          ///< held: w_k = 0 kept by a holding torque within mu_s r_k N_k
};
inline constexpr JointMode kStuck = JointMode::kStuck;
using JointModes = std::array<JointMode, kJoints>;

/// The Coulomb sign a mode gives: +1, -1, or 0 (at rest, or stuck: no Coulomb term).
inline int coulomb_sign(JointMode m) { return m == kStuck ? 0 : static_cast<int>(m); }
/// The slip mode of a sign (+1, -1, 0).
inline JointMode slip_mode(int sign) {
  return sign > 0 ? JointMode::kSlipPositive : sign < 0 ? JointMode::kSlipNegative : JointMode::kRest;
}

/// The reaction/friction loop's stopping test (relative change of the normal forces) and its
/// iteration limit: the defaults of every setting of it (evaluations, runs, trajectories).
inline constexpr double kFrictionTol = 1e-13;
inline constexpr int kFrictionMaxIter = 50;

/// Settings of an evaluation: singularity margin and the reaction/friction loop.
struct EvalOptions {
  double singular_margin = 0.0;  ///< fail with kNearSingular when |sin(th4 - th3)| is below
  double friction_tol = kFrictionTol;  ///< stop when max |N^i - N^(i-1)| <= tol * (max N + 1e-300)
  int friction_max_iter = kFrictionMaxIter;
  /// compute F_k even when the scene has no friction, and with friction from a last solve at the
  /// converged friction torques (false: the friction loop's own F_k, consistent to friction_tol)
  bool want_reactions = true;
  bool want_angles = true;       ///< compute th3, th4 (the dynamics itself needs neither)
  /// Rest rule of inverse dynamics (rest.h; forward dynamics ignores both): a joint with
  /// |w_k| <= rest_rate [rad/s] is at rest, not slipping: its Coulomb sign is that of its relative
  /// acceleration, or 0 where that is within rest_acceleration. The defaults keep the exact rule
  /// (only w_k = 0 is at rest).
  double rest_rate = 0.0;
  /// < 0: no joint is stuck in inverse dynamics. >= 0 [rad/s^2]: a joint at rest whose
  /// |d w_k / dt| <= rest_acceleration is stuck (mode kStuck): it carries no friction torque (the
  /// motors hold the pose: frictionless equilibrium at that joint) and hold_margin_k =
  /// mu_s r_k N_k is how much friction torque it could add. A crank at rest and not
  /// accelerating is taken as exactly still (w = dw/dt = 0: the rest of its rates is noise).
  double rest_acceleration = -1.0;
  /// Jets (inverse_dynamics, forward_dynamics with friction): solve the friction loop in double
  /// and take its derivatives from one Newton step in Jets at the solution (implicit function
  /// theorem, friction_loop.h); false iterates the whole loop in Jets (the reference).
  bool implicit_loop_derivative = true;
};

/// Everything one evaluation computes. Forward dynamics fills thdd from the torques; inverse
/// dynamics fills M1, M2 from thdd.
template <typename T>
struct Evaluation {
  Kinematics<T> kin;
  Bias<T> bias;
  Mat2<T> A;                      ///< generalized mass matrix (eq. 10)
  Vec2<T> thdd;                   ///< (alpha1, alpha2) [rad/s^2]
  T alpha3{}, alpha4{};           ///< coupler angular accelerations [rad/s^2]
  T M1{}, M2{};                   ///< motor torques [N m] (input of forward, output of inverse)
  std::array<Vec2<T>, kJoints> F;       ///< joint reactions [N]
  std::array<T, kJoints> N{}, Mf{},
      w{};  ///< |F_k| [N], friction torques [N m], relative rates [rad/s]
  JointModes slip{};      ///< Coulomb sign used at each joint, or kStuck
  /// stuck joints: mu_s r_k N_k - |holding torque| (>= 0 while friction can hold the joint);
  /// the holding torque itself is in Mf
  std::array<T, kJoints> hold_margin{};
  std::array<T, kJoints> zdot{};        ///< LuGre bristle rates [rad/s] (zero for other laws)
  T P_diss{};                     ///< sum Mf_k w_k >= 0 [W]
  T P_in{};                       ///< M1 w1 + M2 w2 [W]
  T P_ext{};                      ///< M3 w3 + F . v_P [W]
  int iterations = 0;             ///< reaction/friction loop iterations
};

}  // namespace fivebar
