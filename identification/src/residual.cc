// The structure of one sample's inverse dynamics (residual.h).
#include "fivebar/identification/residual.h"

#include <ceres/jet.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace fivebar::identification {

namespace {

/// Columns of the five-bar's sample structure: the 16 standard inertial parameters, the loads
/// (M3 and the force at P), the five friction torques (O, B, C, D, D0).
constexpr int kLoadColumn = kInertialParams;
constexpr int kTorqueColumn = kLoadColumn + 1;
constexpr int kColumns = kTorqueColumn + kJoints;

using ColumnForces = Eigen::Matrix<double, 2, kColumns>;
using ColumnRow = Eigen::Matrix<double, 1, kColumns>;

/// q x (each column of A)
ColumnRow cross_columns(const Vec2<double>& q, const ColumnForces& A) {
  return q.x() * A.row(1) - q.y() * A.row(0);
}

/// Link l's inertial wrench per unit standard parameter (m, mx, my, J_O: columns 4 l .. 4 l + 3
/// of `force` and `moment`): the force m (a_c - g) and its moment about the link's proximal
/// joint P, J_c alpha + (c - P) x m (a_c - g) = J_O alpha + m r x (a_P - g), where
/// m r = mx e + my perp(e) (e: the link's direction) and a_c = a_P + alpha perp(r) - w^2 r.
/// `ag` = a_P - g.
void link_wrench(int l, const Vec2<double>& e, double w, double alpha, const Vec2<double>& ag,
                 ColumnForces* force, ColumnRow* moment) {
  const Vec2<double> n = perp(e);
  const int c = kInertialPerLink * l;
  force->col(c) = ag;
  force->col(c + 1) = alpha * n - w * w * e;
  force->col(c + 2) = -alpha * e - w * w * n;
  (*moment)(c + 1) = cross(e, ag);
  (*moment)(c + 2) = cross(n, ag);
  (*moment)(c + 3) = alpha;
}

/// The reactions (rows 0-9: F_k's x and y) and drive torques (rows 10, 11) per unit of each
/// column's cause at the rates v and accelerations a, by the steps of
/// detail::reactions_of_accelerations and FiveBar::drive_torques written in what each link
/// contributes (its inertial wrench, link_wrench): the couplers' force balances F2 - F3 = R3,
/// F3 - F4 = R4 and moment sums about C, F2 = f3 S3 + f4 S4 (FiveBar::inverse_response); the
/// cranks' forces into F1 and F5, their moments about O and D0 into M1 and M2. Link 3 (about B)
/// gives R3 = f and S3 = n + (B - C) x f; link 4 (about D) R4 = f and S4 = -n (the (D - C) x f
/// of its moment about C cancels against S4's (D - C) x R4); the loads R3 = -Fvec and
/// S3 = -(P - C) x Fvec - M3; every column's R3 adds (D - C) x R3 to its S4; a friction torque
/// enters with a unit in S3 (+B, -C), S4 (-C, +D), M1 (+O, -B) and M2 (+D, +D0).
Eigen::Matrix<double, 12, kColumns> structure_columns(const Params<double>& p,
                                                      const Kinematics<double>& k,
                                                      const Bias<double>& bias,
                                                      const Vec2<double>& v, const Vec2<double>& a,
                                                      const Loads<double>& L) {
  ColumnForces f1 = ColumnForces::Zero(), f2 = f1, R3 = f1, R4 = f1;
  ColumnRow n1 = ColumnRow::Zero(), n2 = n1, n3 = n1, n4 = n1;
  const Vec2<double> g(0.0, -p.gravity), D0(p.ground_length, 0.0);
  const Vec2<double> aB = p.links[0].length * (a[0] * perp(k.e1) - v[0] * v[0] * k.e1);
  const Vec2<double> aD = p.links[1].length * (a[1] * perp(k.e2) - v[1] * v[1] * k.e2);
  link_wrench(0, k.e1, v[0], a[0], Vec2<double>(-g), &f1, &n1);
  link_wrench(1, k.e2, v[1], a[1], Vec2<double>(-g), &f2, &n2);
  link_wrench(2, k.e3, bias.w3, k.G3.dot(a) + bias.h3, Vec2<double>(aB - g), &R3, &n3);
  link_wrench(3, k.e4, bias.w4, k.G4.dot(a) + bias.h4, Vec2<double>(aD - g), &R4, &n4);
  const Vec2<double> u3 = k.B - k.C, u4 = k.D - k.C;
  ColumnRow S3 = n3 + cross_columns(u3, R3);
  const Vec2<double> Fvec = FiveBar::applied(k, L);
  R3.col(kLoadColumn) = -Fvec;
  S3(kLoadColumn) = -cross(Vec2<double>(k.P - k.C), Fvec) - L.M3;
  ColumnRow S4 = cross_columns(u4, R3) - n4;
  const int t = kTorqueColumn;
  S3(t + 1) = 1, S3(t + 2) = -1;
  S4(t + 2) = -1, S4(t + 3) = 1;
  n1(t) = 1, n1(t + 1) = -1;
  n2(t + 3) = 1, n2(t + 4) = 1;
  const CouplerResponse<double> response = FiveBar::inverse_response(k);
  const ColumnForces F2 = response.f3 * S3 + response.f4 * S4;
  const ColumnForces F3 = F2 - R3;
  const ColumnForces F4 = F3 - R4;
  Eigen::Matrix<double, 12, kColumns> out;
  out << f1 + F2, F2, F3, F4, f2 - F4, n1 + cross_columns(k.B, F2),
      n2 - cross_columns(Vec2<double>(k.D - D0), F4);
  return out;
}

}  // namespace

bool sample_structure(const Params<double>& scene, const Sample& s, const EvalOptions& eval,
                      SampleStructure* out) {
  Kinematics<double> k;
  if (!solve_kinematics(scene, s.th1, s.th2, &k, eval.singular_margin, false).ok()) return false;
  Vec2<double> v(s.w1, s.w2), a(s.a1, s.a2);
  if (eval.rest_acceleration >= 0.0) {  // the rest rule of a driven coordinate
    for (int i = 0; i < kDof; ++i) mech::detail::still_drive(eval, &v[i], &a[i]);
  }
  Bias<double> bias;
  FiveBar::bias(scene, k, v, &bias);
  const Eigen::Matrix<double, 12, kColumns> D = structure_columns(scene, k, bias, v, a, s.loads);
  if (!D.allFinite()) return false;
  out->A = D.topLeftCorner<10, kInertialParams>();
  out->b = D.col(kLoadColumn).head<10>();
  out->Y = D.bottomLeftCorner<2, kInertialParams>();
  out->c = D.col(kLoadColumn).tail<2>();
  // friction part: the inverse dynamics' modes (the rest rule's) and the friction-free
  // reactions' norms N at the scene, dF and G the response per unit friction torque of the
  // joints with a Coulomb sign
  const std::array<double, kInertialParams> pi0 = standard_inertial(scene);
  const Eigen::Map<const Eigen::Matrix<double, kInertialParams, 1>> pv(pi0.data());
  const Eigen::Matrix<double, 10, 1> F0 = out->A * pv + out->b;
  std::array<double, kJoints> N;
  double nmax = 1e-300;
  for (int j = 0; j < kJoints; ++j) {
    N[j] = F0.segment<2>(2 * j).norm();
    nmax = std::max(nmax, N[j]);
  }
  const FiveBar::Joints<double> w = FiveBar::joint_rates(k, bias, v);
  const FiveBar::Joints<double> wdot = FiveBar::joint_accelerations(k, bias, a);
  for (int j = 0; j < kJoints; ++j) {
    out->slip[j] = mech::detail::inverse_slip(eval, w[j], wdot[j]);
    out->w[j] = w[j];
    const bool acts = out->slip[j] != kStuck && out->slip[j] != JointMode::kRest;
    // a joint without a Coulomb sign but moving: its viscous torque needs the full model
    if (!acts && out->slip[j] == JointMode::kRest && w[j] != 0 &&
        scene.friction.pin_radius[j] != 0) {
      return false;
    }
    // a reaction that nearly vanishes: the friction torque's direction is not reliable
    if (acts && N[j] < 1e-9 * nmax) return false;
    out->dF.col(j) = acts ? Eigen::Matrix<double, 10, 1>(D.col(kTorqueColumn + j).head<10>())
                          : Eigen::Matrix<double, 10, 1>::Zero();
    out->G.col(j) =
        acts ? Eigen::Vector2d(D.col(kTorqueColumn + j).tail<2>()) : Eigen::Vector2d::Zero();
  }
  return true;
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
