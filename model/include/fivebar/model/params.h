// Parameters of the planar 5R five-bar (model.md, "Geometry and coordinates"), templated on the
// scalar so that ceres::Jet can carry derivatives with respect to any of them.
#pragma once

#include <array>
#include <cmath>
#include <type_traits>

#include "fivebar/model/scalar.h"

namespace fivebar {

/// U(x); a Jet cast to double keeps its value part (the double shadow of a Jet evaluation).
template <typename U, typename T>
U scalar_cast(const T& x) {
  if constexpr (std::is_same_v<U, double> && !std::is_same_v<T, double>) {
    return value_of(x);
  } else {
    return U(x);
  }
}

/// Number of joints (O, B, C, D, D0) and of moving links (1: crank O-B, 2: crank D0-D,
/// 3: coupler B-C, 4: coupler D-C).
inline constexpr int kJoints = 5;
inline constexpr int kLinks = 4;

/// Defaults of the friction coefficients whose default is not zero: FrictionParams starts with
/// them, and the law descriptors (friction.h, kCoefficientInfo) give them as the value a scene may
/// omit, so that a library caller who switches the law of paper_params() gets the same law as a
/// scene that omits them.
inline constexpr double kDefaultStribeckExponent = 2.0;  ///< delta: a Gaussian Stribeck peak
inline constexpr double kDefaultViscousExponent = 1.0;   ///< n: linear viscous friction

/// An array of kJoints copies of v.
template <typename T>
std::array<T, kJoints> joint_array(double v) {
  std::array<T, kJoints> a;
  a.fill(T(v));
  return a;
}

/// Which of the two closures: elbow_up puts C left of the directed line B->D.
/// Stored as an int (+1 / -1), never as a scalar T, so that Jets never choose a branch.
enum Assembly : int { kElbowUp = +1, kElbowDown = -1 };

/// Friction law f(w) of a joint; the friction torque is Mf_k = r_k N_k f_k(w_k) (eq. 3).
enum class FrictionLaw : int {
  kNone = 0,            ///< no friction: no reaction solve is needed for the motion
  kCoulombViscous = 1,  ///< f(w) = mu_c sign(w) + mu_v w (the paper's law)
  /// f(w) = (mu_c + (mu_s - mu_c) exp(-|w / w_st|^delta)) sign(w) + mu_v w
  kStribeck = 2,
  /// LuGre: f = sigma0 z + sigma1 dz/dt + sigma2 w, dz/dt = w - sigma0 |w| z / g(w), with the
  /// Stribeck curve g(w) = mu_c + (mu_s - mu_c) exp(-|w / w_st|^delta); one bristle state z per
  /// joint [rad], a stiff system for large sigma0
  kLuGre = 3,
  /// f(w) = mu_c sign(w) + mu_v |w|^n sign(w): viscous friction growing as a power n of the rate
  /// (n = 1 is kCoulombViscous; n < 1 for shear-thinning lubricants)
  kPowerViscous = 4,
};

/// One moving link i: length l_i, mass m_i, inertia J_i about its centre of mass, and the centre
/// of mass at offset r_i, angle alpha_i from the proximal joint (model.md).
template <typename T>
struct Link {
  T length{};
  T mass{};
  T inertia{};
  T com_offset{};
  T com_angle{};

  template <typename U>
  Link<U> cast() const {
    return {scalar_cast<U>(length), scalar_cast<U>(mass), scalar_cast<U>(inertia),
            scalar_cast<U>(com_offset), scalar_cast<U>(com_angle)};
  }
};

/// Friction of the five joints, in the order O, B, C, D, D0.
template <typename T>
struct FrictionParams {
  FrictionLaw law = FrictionLaw::kNone;
  std::array<T, kJoints> pin_radius{};  ///< r_k [m]
  std::array<T, kJoints> coulomb{};     ///< mu_c,k [-]
  std::array<T, kJoints> viscous{};     ///< mu_v,k [s/rad]
  /// mu_s,k [-]: static coefficient (Stribeck peak; holding bound of a stuck joint). The scene
  /// loader sets it to `coulomb` when the scene omits it.
  std::array<T, kJoints> static_coulomb{};
  std::array<T, kJoints> stribeck_velocity{};  ///< w_st,k [rad/s] (kStribeck)
  /// delta_k [-] (kStribeck, and LuGre's g(w))
  std::array<T, kJoints> stribeck_exponent = joint_array<T>(kDefaultStribeckExponent);
  std::array<T, kJoints> sigma0{};  ///< bristle stiffness [1/rad] (kLuGre)
  std::array<T, kJoints> sigma1{};  ///< bristle damping [s/rad] (kLuGre)
  std::array<T, kJoints> sigma2{};  ///< viscous coefficient [s/rad] (kLuGre)
  /// n_k [-] (kPowerViscous); mu_v then in (s/rad)^n
  std::array<T, kJoints> viscous_exponent = joint_array<T>(kDefaultViscousExponent);
  /// w_s [rad/s]: 0 uses the exact sign(w); w_s > 0 replaces sign(w) by tanh(w / w_s), the smooth
  /// form used where derivatives across w = 0 are needed (identification, optimization).
  T smoothing_velocity{};

  bool active() const { return law != FrictionLaw::kNone; }

  template <typename U>
  FrictionParams<U> cast() const {
    FrictionParams<U> out;
    out.law = law;
    for (int k = 0; k < kJoints; ++k) {
      out.pin_radius[k] = scalar_cast<U>(pin_radius[k]);
      out.coulomb[k] = scalar_cast<U>(coulomb[k]);
      out.viscous[k] = scalar_cast<U>(viscous[k]);
      out.static_coulomb[k] = scalar_cast<U>(static_coulomb[k]);
      out.stribeck_velocity[k] = scalar_cast<U>(stribeck_velocity[k]);
      out.stribeck_exponent[k] = scalar_cast<U>(stribeck_exponent[k]);
      out.sigma0[k] = scalar_cast<U>(sigma0[k]);
      out.sigma1[k] = scalar_cast<U>(sigma1[k]);
      out.sigma2[k] = scalar_cast<U>(sigma2[k]);
      out.viscous_exponent[k] = scalar_cast<U>(viscous_exponent[k]);
    }
    out.smoothing_velocity = scalar_cast<U>(smoothing_velocity);
    return out;
  }
};

/// Number of actuators: the motors at O (torque M1, on link 1) and at D0 (M2, on link 2).
inline constexpr int kActuators = 2;

/// The two actuators (index 0: M1 at joint O; 1: M2 at joint D0), docs/scene.md `actuators:`.
/// The motor/gearbox friction c_a sign(w) + v_a w is load-independent and adds to the friction
/// torque of the driven joint (O or D0); the offset is a torque-sensor bias that enters only
/// measured torques (measured = motor torque + offset), never the dynamics.
template <typename T>
struct ActuatorParams {
  std::array<T, kActuators> offset{};   ///< sensor bias [N m]
  std::array<T, kActuators> coulomb{};  ///< c_a [N m]
  std::array<T, kActuators> viscous{};  ///< v_a [N m s/rad]

  template <typename U>
  ActuatorParams<U> cast() const {
    ActuatorParams<U> out;
    for (int a = 0; a < kActuators; ++a) {
      out.offset[a] = scalar_cast<U>(offset[a]);
      out.coulomb[a] = scalar_cast<U>(coulomb[a]);
      out.viscous[a] = scalar_cast<U>(viscous[a]);
    }
    return out;
  }
};

/// Every constant of the mechanism (the loads, which depend on time, are in Loads).
template <typename T>
struct Params {
  T ground_length{};                  ///< l0 [m]: O at (0,0), D0 at (l0,0)
  std::array<Link<T>, kLinks> links;  ///< links 1..4 at index 0..3
  T point_p{};                        ///< lp [m]: P on link 3, from B
  int assembly = kElbowUp;            ///< kElbowUp or kElbowDown
  T gravity{};                        ///< g [m/s^2], along -y
  FrictionParams<T> friction;
  ActuatorParams<T> actuators;  ///< motor friction and torque-sensor offsets (default none)

  template <typename U>
  Params<U> cast() const {
    Params<U> out;
    out.ground_length = scalar_cast<U>(ground_length);
    for (int i = 0; i < kLinks; ++i) out.links[i] = links[i].template cast<U>();
    out.point_p = scalar_cast<U>(point_p);
    out.assembly = assembly;
    out.gravity = scalar_cast<U>(gravity);
    out.friction = friction.template cast<U>();
    out.actuators = actuators.template cast<U>();
    return out;
  }
};

/// External loads at one instant (model.md, M_d): motor torques M1, M2 [N m] on links 1 and 2,
/// moment M3 [N m] on link 3 (counter-clockwise positive), force of magnitude F [N] at P at the
/// angle F_angle from the direction of link 3.
template <typename T>
struct Loads {
  T M1{}, M2{}, M3{}, F{}, F_angle{};

  template <typename U>
  Loads<U> cast() const {
    return {scalar_cast<U>(M1), scalar_cast<U>(M2), scalar_cast<U>(M3), scalar_cast<U>(F),
            scalar_cast<U>(F_angle)};
  }
};

/// The canonical scene of model.md, section 5 (loads at t are in paper_loads()).
inline Params<double> paper_params() {
  Params<double> p;
  p.ground_length = 0.29;
  p.links[0] = {0.08, 1.0, 0.1, 0.05, 0.0};
  p.links[1] = {0.05, 1.0, 0.1, 0.03, 0.0};
  p.links[2] = {0.25, 1.0, 0.1, 0.20, 0.0};
  p.links[3] = {0.25, 1.0, 0.1, 0.15, 0.0};
  p.point_p = 0.20;
  p.assembly = kElbowUp;
  p.gravity = 9.81;
  p.friction.law = FrictionLaw::kCoulombViscous;
  p.friction.pin_radius.fill(0.01);
  p.friction.coulomb.fill(0.12);
  p.friction.viscous.fill(0.02);
  p.friction.static_coulomb.fill(0.12);
  p.friction.stribeck_velocity.fill(0.1);
  p.friction.stribeck_exponent.fill(2.0);
  return p;
}

/// The canonical scene's loads at time t [s] (model.md, section 5; the loads of
/// datasets/scenes/paper.yaml): M1 = 2 + 5 sin(8 pi t), M2 = 3 + 5 cos(pi t), M3 = 6 [N m],
/// F = 50 N at pi/2 from link 3.
inline Loads<double> paper_loads(double t) {
  return {2 + 5 * std::sin(8 * M_PI * t), 3 + 5 * std::cos(M_PI * t), 6.0, 50.0, M_PI / 2};
}

}  // namespace fivebar
