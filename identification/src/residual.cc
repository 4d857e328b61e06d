// The structure of one sample's inverse dynamics (residual.h).
#include "fivebar/identification/residual.h"

#include <ceres/jet.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "jet_dynamics.h"

namespace fivebar::identification {

namespace {

/// The friction-free inverse dynamics of one sample at any standard inertial parameters: its
/// loop closure (close_loop: the lengths and crank angles only) once, then per parameter vector
/// the rest of the model's frictionless pass (mech::detail::inverse_pass), which the centres of
/// mass enter: the same numbers as inverse_dynamics with the friction law kNone.
class Frictionless {
 public:
  Frictionless(const Params<double>& scene, const Sample& s, const EvalOptions& eval,
               const std::array<double, kInertialParams>& pi0)
      : scene_(scene), s_(s), pi0_(pi0) {
    scene_.friction.law = FrictionLaw::kNone;
    scene_.actuators = ActuatorParams<double>();  // StructuredResidual adds the actuator terms
    set_standard_inertial(pi0.data(), &scene_);
    ok_ = close_loop(scene_, s.th1, s.th2, &closed_, eval.singular_margin, false).ok();
    v_ = Vec2<double>(s.w1, s.w2);
    a_ = Vec2<double>(s.a1, s.a2);
    if (eval.rest_acceleration >= 0.0) {  // the rest rule of a driven coordinate
      for (int i = 0; i < kDof; ++i) mech::detail::still_drive(eval, &v_[i], &a_[i]);
    }
  }

  /// Reactions (10) and actuator torques (2) at pi0, or with its parameter i (>= 0) moved by h
  /// (only that link's parameters set again); false where the inverse dynamics fails.
  bool operator()(int i, double h, Eigen::Matrix<double, 12, 1>* out) const {
    if (!ok_) return false;
    Params<double> p = scene_;
    if (i >= 0) {
      const int l = i / kInertialPerLink;
      std::array<double, kInertialPerLink> link;
      for (int c = 0; c < kInertialPerLink; ++c) link[c] = pi0_[kInertialPerLink * l + c];
      link[i % kInertialPerLink] += h;
      set_standard_inertial_links(link.data(), 1, &p.links[l]);
    }
    Evaluation<double> ev;
    ev.kin = closed_;
    place_points(p, &ev.kin);
    first_order_coefficients(p, &ev.kin);
    FiveBar::bias(p, ev.kin, v_, &ev.bias);
    ev.Mf.fill(0.0);
    FiveBar::reactions(p, ev.kin, ev.bias, s_.loads, FiveBar::applied(ev.kin, s_.loads), a_, ev.Mf,
                       &ev.F, &ev);
    FiveBar::drive_torques(p, ev.kin, a_, &ev);
    for (int k = 0; k < kJoints; ++k) {
      (*out)(2 * k) = ev.F[k].x();
      (*out)(2 * k + 1) = ev.F[k].y();
    }
    (*out)(10) = ev.M1;
    (*out)(11) = ev.M2;
    return out->allFinite();
  }

 private:
  Params<double> scene_;  ///< frictionless, at pi0
  const Sample& s_;
  const std::array<double, kInertialParams>& pi0_;
  Kinematics<double> closed_;
  Vec2<double> v_, a_;
  bool ok_ = false;
};

}  // namespace

bool sample_structure(const Params<double>& scene, const Sample& s, const EvalOptions& eval,
                      SampleStructure* out) {
  // inertial part: friction-free reactions and torques are affine in pi (forward differences
  // are exact up to rounding; Jets would be singular at a COM on the joint)
  const std::array<double, kInertialParams> pi0 = standard_inertial(scene);
  const Frictionless frictionless(scene, s, eval, pi0);
  Eigen::Matrix<double, 12, 1> v0, v1;
  if (!frictionless(-1, 0.0, &v0)) return false;
  Eigen::Matrix<double, 12, kInertialParams> D;
  for (int i = 0; i < kInertialParams; ++i) {
    const int l = i / kInertialPerLink;
    const double h = 1e-3 * std::max(std::abs(pi0[i]), scene.links[l].mass * scene.links[l].length);
    if (!frictionless(i, h, &v1)) return false;
    D.col(i) = (v1 - v0) / h;
  }
  const Eigen::Map<const Eigen::Matrix<double, kInertialParams, 1>> pv(pi0.data());
  out->A = D.topRows(10);
  out->b = v0.head(10) - out->A * pv;
  out->Y = D.bottomRows(2);
  out->c = v0.tail(2) - out->Y * pv;
  // friction part: Jets over the pin radii at 0 with unit Coulomb coefficients, so that
  // phi_j = r_j slip_j and d(F, M) / d r_j = (dF_j, G_j) slip_j N0_j
  using J5 = ceres::Jet<double, kJoints>;
  Params<J5> p = scene.cast<J5>();
  p.friction.law = FrictionLaw::kCoulombViscous;
  p.friction.smoothing_velocity = J5(0);
  p.actuators = ActuatorParams<J5>();
  for (int j = 0; j < kJoints; ++j) {
    p.friction.coulomb[j] = J5(1);
    p.friction.viscous[j] = J5(0);
    p.friction.pin_radius[j] = J5(0, j);
  }
  EvalOptions eo = eval;
  eo.want_angles = false;  // the coupler angles themselves enter no reaction
  Evaluation<J5> ev;
  if (!inverse_dynamics(p, s.loads.cast<J5>(), J5(s.th1), J5(s.th2), J5(s.w1), J5(s.w2), J5(s.a1),
                        J5(s.a2), nullptr, eo, &ev)
           .ok()) {
    return false;
  }
  double nmax = 1e-300;
  for (int k = 0; k < kJoints; ++k) nmax = std::max(nmax, ev.N[k].a);
  for (int j = 0; j < kJoints; ++j) {
    out->slip[j] = ev.slip[j];
    out->w[j] = ev.w[j].a;
    const bool acts = ev.slip[j] != kStuck && ev.slip[j] != JointMode::kRest;
    // a joint without a Coulomb sign but moving: its viscous torque needs the full model
    if (!acts && ev.slip[j] == JointMode::kRest && out->w[j] != 0 && scene.friction.pin_radius[j] != 0) {
      return false;
    }
    const double scale = acts ? coulomb_sign(ev.slip[j]) * ev.N[j].a : 0.0;
    if (acts && std::abs(scale) < 1e-9 * nmax) return false;
    for (int k = 0; k < kJoints; ++k) {
      out->dF(2 * k, j) = acts ? ev.F[k].x().v[j] / scale : 0.0;
      out->dF(2 * k + 1, j) = acts ? ev.F[k].y().v[j] / scale : 0.0;
    }
    out->G(0, j) = acts ? ev.M1.v[j] / scale : 0.0;
    out->G(1, j) = acts ? ev.M2.v[j] / scale : 0.0;
  }
  return out->A.allFinite() && out->dF.allFinite() && out->G.allFinite();
}

namespace {

/// Jet width of the passes through the friction laws in StructuredResidual::evaluate (the
/// per-joint Coulomb-viscous layout's 10 parameters in one pass)
constexpr int kFrictionStride = 10;
/// Largest parameter count of the structured residual (per-joint Stribeck with inertia)
constexpr int kMaxParams = 40;

using FrictionJet = ceres::Jet<double, kFrictionStride>;

/// The friction terms (`terms`: phi, motor, offsets) at x and their derivatives in the
/// parameters `seeded` (rows 0-4, 5-9, 10-11 of column q of D: parameter seeded[q]), by Jet
/// passes of kFrictionStride seeded parameters each.
template <typename Terms>
void friction_jacobian(const double* x, int P, const std::array<int, kMaxParams>& seeded,
                       int n_seeded, const Terms& terms, Eigen::Matrix<double, 12, kMaxParams>* D,
                       std::array<double, kJoints>* phi, std::array<double, kJoints>* motor,
                       std::array<double, kActuators>* offset) {
  using J = FrictionJet;
  std::array<J, kMaxParams> xj;
  for (int i = 0; i < P; ++i) xj[i] = J(x[i]);
  for (int first = 0; first < std::max(n_seeded, 1); first += kFrictionStride) {
    const int last = std::min(n_seeded, first + kFrictionStride);
    for (int q = first; q < last; ++q) xj[seeded[q]].v[q - first] = 1;
    std::array<J, kJoints> phi_j, motor_j;
    std::array<J, kActuators> offset_j;
    terms(xj.data(), &phi_j, &motor_j, &offset_j);
    for (int q = first; q < last; ++q) {
      xj[seeded[q]].v[q - first] = 0;
      for (int j = 0; j < kJoints; ++j) {
        (*D)(j, q) = phi_j[j].v[q - first];
        (*D)(kJoints + j, q) = motor_j[j].v[q - first];
      }
      for (int a = 0; a < kActuators; ++a) (*D)(2 * kJoints + a, q) = offset_j[a].v[q - first];
    }
    for (int j = 0; j < kJoints; ++j) (*phi)[j] = phi_j[j].a, (*motor)[j] = motor_j[j].a;
    for (int a = 0; a < kActuators; ++a) (*offset)[a] = offset_j[a].a;
  }
}

}  // namespace

bool StructuredResidual::evaluate(const double* x, double* r, double* jacobian,
                                  double* r_loop) const {
  if (jacobian == nullptr) return (*this)(x, r);
  const int P = layout_.size();
  if (P > kMaxParams) return false;
  // phi, motor, offsets and their derivatives in the parameters that are not inertial
  std::array<int, kMaxParams> seeded;
  int n_seeded = 0;
  for (int i = 0; i < P; ++i) {
    if (!layout_.is_inertial(i)) seeded[n_seeded++] = i;
  }
  Eigen::Matrix<double, 12, kMaxParams> D;
  std::array<double, kJoints> phi, motor;
  std::array<double, kActuators> offset;
  const auto terms = [this](const FrictionJet* xj, std::array<FrictionJet, kJoints>* phi_j,
                            std::array<FrictionJet, kJoints>* motor_j,
                            std::array<FrictionJet, kActuators>* offset_j) {
    friction_terms(xj, phi_j, motor_j, offset_j);
  };
  friction_jacobian(x, P, seeded, n_seeded, terms, &D, &phi, &motor, &offset);
  std::array<double, kInertialParams> pi;
  std::array<double, 10> F0;
  frictionless_reactions(x, &pi, &F0);
  std::array<double, kJoints> N_star;
  if (!loop(phi, motor, F0, &N_star)) return false;
  // the implicit step of operator() with Jets, N = N* + H^-1 (|F(N*)| - N*) with H = I - G_N,
  // its H and the reactions' unit directions U for dN/dx = H^-1 d|F(N*)|/dx
  std::array<double, kJoints> N;
  Eigen::Matrix<double, kJoints, kJoints> H;
  Eigen::Matrix<double, kJoints, 10> U;
  implicit_step(phi, motor, F0, N_star, &N, &H, &U);
  residual_at(phi, motor, offset, pi, N, r);
  if (r_loop != nullptr) residual_at(phi, motor, offset, pi, N_star, r_loop);
  // dr/dx = -(d offset + Y dpi + G dMf), dMf_j = N_j dphi_j + phi_j dN_j + dmotor_j, where
  // dN = H^-1 d|F(N*)| and d|F(N*)| = U (A dpi + dF (N* dphi + dmotor)): with W = G phi H^-1,
  // dr = -(d offset + (Y + W U A) dpi + G (N dphi + dmotor) + W U dF (N* dphi + dmotor))
  const Eigen::Map<const Eigen::Matrix<double, kJoints, 1>> Nv(N.data()), Nsv(N_star.data()),
      phiv(phi.data());
  std::array<Eigen::Vector2d, kJoints> Wt;  // W's columns: H^T W^T = (G phi)^T
  for (int k = 0; k < kJoints; ++k) Wt[k] = st_.G.col(k) * phi[k];
  Wt = fivebar::detail::solve_with_double_matrix(H.transpose().eval(), Wt);
  Eigen::Matrix<double, kActuators, kJoints> W;
  for (int k = 0; k < kJoints; ++k) W.col(k) = Wt[k];
  const Eigen::Matrix<double, kActuators, 10> WU = W.lazyProduct(U);
  const Eigen::Matrix<double, kActuators, kJoints> WUdF = WU.lazyProduct(st_.dF);
  Eigen::Map<Eigen::Matrix<double, kActuators, Eigen::Dynamic, Eigen::RowMajor>> dr(jacobian,
                                                                                    kActuators, P);
  for (int q = 0; q < n_seeded; ++q) {
    const Eigen::Matrix<double, kJoints, 1> dphi = D.col(q).head<kJoints>();
    const Eigen::Matrix<double, kJoints, 1> dmotor = D.col(q).segment<kJoints>(kJoints);
    dr.col(seeded[q]) = -(D.col(q).tail<kActuators>() + st_.G * (Nv.cwiseProduct(dphi) + dmotor) +
                          WUdF * (Nsv.cwiseProduct(dphi) + dmotor));
  }
  if (layout_.inertia) {
    const Eigen::Matrix<double, kActuators, kInertialParams> dpi = st_.Y + WU.lazyProduct(st_.A);
    dr.middleCols(layout_.inertia_offset(), kInertialParams) = -dpi;
  }
  return true;
}

}  // namespace fivebar::identification
