// The double kinematics, mass matrix, reactions and holding that the headers declare `extern
// template` under FIVEBAR_DOUBLE_KINEMATICS_FROM_SIM (the command-line layer, apps/), compiled
// once here, and the holding polygon (rest.h), whose friction loops are the simulator's.
#include "fivebar/model/appell.h"
#include "fivebar/model/four_bar.h"
#include "fivebar/model/kinematics.h"
#include "fivebar/model/reactions.h"
#include "fivebar/model/rest.h"

namespace fivebar {
template Status close_loop<double>(const Params<double>&, const double&, const double&,
                                   Kinematics<double>*, double, bool);
template void place_points<double>(const Params<double>&, Kinematics<double>*);
template void first_order_coefficients<double>(const Params<double>&, Kinematics<double>*);
template Status solve_kinematics<double>(const Params<double>&, const double&, const double&,
                                         Kinematics<double>*, double, bool);
template void compute_bias<double>(const Params<double>&, const Kinematics<double>&,
                                   const double&, const double&, Bias<double>*);
template void mass_and_forces<double>(const Params<double>&, const Kinematics<double>&,
                                      const Bias<double>&, const Loads<double>&,
                                      const Vec2<double>&, Mat2<double>*, Vec2<double>*);
template void reactions<double>(const Params<double>&, const Kinematics<double>&,
                                const Bias<double>&, const Loads<double>&, const Vec2<double>&,
                                const Vec2<double>&, const std::array<double, kJoints>&,
                                std::array<Vec2<double>, kJoints>*, double*, double*);
template void reaction_norms<double>(const std::array<Vec2<double>, kJoints>&,
                                     std::array<double, kJoints>*);
template Status holding_torques<double>(const Params<double>&, const Loads<double>&,
                                        const double&, const double&, const EvalOptions&,
                                        Holding<double>*);
template Status four_bar_close<double>(const FourBarParamsT<double>&, const double&,
                                       FourBarKinematicsT<double>*, double);
template Status four_bar_kinematics<double>(const FourBarParamsT<double>&, const double&,
                                            FourBarKinematicsT<double>*, double);

Status holding_polygon(const Params<double>& p, const Loads<double>& L, double th1, double th2,
                       const EvalOptions& opt, const Holding<double>& h, HoldingPolygon* out) {
  Kinematics<double> k;
  Status st = solve_kinematics(p, th1, th2, &k, opt.singular_margin);
  if (!st.ok()) return st;
  Bias<double> b;
  compute_bias(p, k, 0.0, 0.0, &b);
  const Vec2<double> Fvec = force_vector(k, L);
  const Vec2<double> thdd = Vec2<double>::Zero();
  double al3 = 0, al4 = 0;
  auto solve = [&](const std::array<double, kJoints>& Mf, std::array<Vec2<double>, kJoints>* F) {
    reactions(p, k, b, L, Fvec, thdd, Mf, F, &al3, &al4);
  };
  std::vector<std::array<double, 2>> corners;
  for (int pattern = 0; pattern < 32; ++pattern) {
    std::array<double, kJoints> phi{}, N{}, Mf{}, motor{};  // motor: actuator Coulomb c_a
    for (int j = 0; j < kJoints; ++j) {
      const double sign = (pattern >> j) & 1 ? 1.0 : -1.0;
      phi[j] = p.friction.active() ? sign * holding_bound(p.friction, j) : 0.0;
      motor[j] = p.friction.active() ? sign * holding_capacity(p, j, 0.0) : 0.0;
    }
    std::array<Vec2<double>, kJoints> F;
    int iterations = 0;
    st = friction_loop(phi, opt, solve, &N, &Mf, &F, &iterations, &motor);
    if (!st.ok()) return st;
    const Vec2<double> M = Vec2<double>(h.M1, h.M2) + friction_transpose(k, Mf);
    corners.push_back({M[0], M[1]});
  }
  out->vertices = detail::convex_hull(corners);
  if (out->vertices.size() < 3) {  // no friction: the equilibrium alone
    out->M1_min = out->M1_max = h.M1;
    out->M2_min = out->M2_max = h.M2;
    return Status::Ok();
  }
  detail::polygon_slice(out->vertices, 0, h.M2, &out->M1_min, &out->M1_max);
  detail::polygon_slice(out->vertices, 1, h.M1, &out->M2_min, &out->M2_max);
  return Status::Ok();
}

}  // namespace fivebar
